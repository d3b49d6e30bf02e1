#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <mujoco/mujoco.h>

/// @file
/// Owning pointers for MuJoCo's model and data, MJCF loading with readable errors, and the
/// process-wide hooks that route MuJoCo's warnings and errors to the cairn logger.

namespace cairn::sim {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

/// Compiles MJCF text as if it were the file at `path`: the text is served through MuJoCo's
/// virtual file system under that name, so includes, meshes and height-field images named
/// relative to `path` resolve next to it on disk.
/// With `placeholder_buffers` the text's <size> buffers are placeholders the caller replaces
/// before making its mjData: warnings that the compiler's own mjData ran out of contact or
/// constraint room are not reported.
/// @throws std::runtime_error "<path>: <MuJoCo's message>" when parsing or compiling fails.
MjModelPtr LoadModelFromText(const std::string& xml, const std::string& path,
                             bool placeholder_buffers = false);

/// Compiles an MJCF file from disk. @throws std::runtime_error with the file name and
/// MuJoCo's message.
MjModelPtr LoadModelFromFile(const std::string& path);

/// Routes mju_user_warning to CAIRN_LOG_WARN (rate-limited) and mju_user_error to
/// CAIRN_LOG_ERROR followed by a std::runtime_error. Idempotent; call once at start-up.
void InstallMujocoLogHooks();

/// Number of MuJoCo warnings seen by the hooks since the process started.
int64_t MujocoWarningCount();

/// Reads a whole text file. @throws std::runtime_error naming the file when it cannot be read.
std::string ReadTextFile(const std::string& path);

/// Name of an object in the model, or "" when it has none.
std::string MjName(const mjModel* m, mjtObj type, int id);

}  // namespace cairn::sim
