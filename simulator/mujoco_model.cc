#include "simulator/mujoco_model.h"

#include <atomic>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "common/log.h"

namespace cairn::sim {
namespace {

std::atomic<int64_t> g_warning_count{0};

// Set while this thread compiles a scene with placeholder buffers (LoadModelFromText's
// `placeholder_buffers`).
thread_local bool t_placeholder_buffers = false;

// MuJoCo prints warnings in bursts (one per step while a condition lasts): log them at most
// once every few seconds with the number swallowed in between.
common::RateLimiter& WarningLimiter() {
  static common::RateLimiter limiter(5.0);
  return limiter;
}

void OnMujocoWarning(const char* message) {
  // The compiler's own mjData of a scene compiled with placeholder buffers sees every robot at
  // the origin, on top of each other: its full buffers say nothing about the simulation.
  if (t_placeholder_buffers && std::strstr(message, "Pre-allocated") != nullptr) return;
  ++g_warning_count;
  int64_t suppressed = 0;
  if (WarningLimiter().Allow(&suppressed)) {
    if (suppressed > 0) {
      CAIRN_LOG_WARN("MuJoCo: %s (%lld similar warnings suppressed)", message,
                     static_cast<long long>(suppressed));
    } else {
      CAIRN_LOG_WARN("MuJoCo: %s", message);
    }
  }
}

void OnMujocoError(const char* message) {
  CAIRN_LOG_ERROR("MuJoCo error: %s", message);
  throw std::runtime_error(std::string("MuJoCo error: ") + message);
}

std::string BaseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

void InstallMujocoLogHooks() {
  mju_user_warning = &OnMujocoWarning;
  mju_user_error = &OnMujocoError;
}

int64_t MujocoWarningCount() { return g_warning_count.load(); }

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

MjModelPtr LoadModelFromText(const std::string& xml, const std::string& path,
                             bool placeholder_buffers) {
  // mjVFS holds fixed-size name tables (about 2 MB): keep it off the stack.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const std::string name = BaseName(path);
  if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(xml.size())) != 0) {
    throw std::runtime_error(path + ": cannot stage the model text in MuJoCo's file system");
  }
  const int index = mj_findFileVFS(vfs.get(), name.c_str());
  if (index < 0) throw std::runtime_error(path + ": staged model text not found");
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());

  char error[1024] = {0};
  t_placeholder_buffers = placeholder_buffers;
  mjModel* model = nullptr;
  try {
    model = mj_loadXML(path.c_str(), vfs.get(), error, sizeof(error));
  } catch (...) {
    t_placeholder_buffers = false;
    mj_deleteVFS(vfs.get());
    throw;
  }
  t_placeholder_buffers = false;
  mj_deleteVFS(vfs.get());
  if (model == nullptr) {
    throw std::runtime_error(path + ": " + (error[0] ? error : "MuJoCo could not load the model"));
  }
  const bool placeholder_warning =
      placeholder_buffers && std::strstr(error, "Pre-allocated") != nullptr;
  if (error[0] && !placeholder_warning) CAIRN_LOG_WARN("MuJoCo (%s): %s", path.c_str(), error);
  return MjModelPtr(model);
}

MjModelPtr LoadModelFromFile(const std::string& path) {
  char error[1024] = {0};
  mjModel* model = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  if (model == nullptr) {
    throw std::runtime_error(path + ": " + (error[0] ? error : "MuJoCo could not load the model"));
  }
  return MjModelPtr(model);
}

std::string MjName(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name ? std::string(name) : std::string();
}

}  // namespace cairn::sim
