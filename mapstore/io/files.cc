#include "mapstore/io/files.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "mapstore/names.h"

namespace cairn::mapstore::io {

namespace fs = std::filesystem;
using common::InvalidArgumentError;
using common::Result;
using common::Status;

Result<std::string> SafeOutputPath(const std::string& folder, const std::string& file_name) {
  if (file_name.empty() || file_name == "." || file_name == ".." ||
      file_name.find('/') != std::string::npos || file_name.find('\0') != std::string::npos) {
    return InvalidArgumentError("'" + file_name + "' is not a plain file name");
  }
  if (folder.empty()) return InvalidArgumentError("no output folder given");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (!fs::is_directory(folder, ec)) {
    return InvalidArgumentError("'" + folder + "' is not a folder");
  }
  const fs::path root = fs::canonical(folder, ec);
  if (ec) return InvalidArgumentError("cannot resolve '" + folder + "': " + ec.message());
  const fs::path target = root / file_name;
  if (target.parent_path() != root) {
    return InvalidArgumentError("'" + file_name + "' would leave the folder '" + folder + "'");
  }
  const auto status = fs::symlink_status(target, ec);
  if (fs::is_symlink(status)) {
    return InvalidArgumentError("refusing to write through the symlink '" + target.string() + "'");
  }
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    return InvalidArgumentError("'" + target.string() + "' exists and is not a file");
  }
  return target.string();
}

Status WriteFileAtomically(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return common::UnavailableError("cannot write '" + tmp + "'");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      return common::ResourceExhaustedError("writing '" + path + "' failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return common::UnavailableError("cannot rename into '" + path + "': " + ec.message());
  }
  return Status::Ok();
}

Result<std::string> OutputPath(const std::string& folder, const std::string& stem,
                               const std::string& extension) {
  const Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  return SafeOutputPath(folder, stem + extension);
}

Result<std::string> ReadFile(const std::string& path, size_t max_bytes) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return common::NotFoundError("no file '" + path + "'");
  const auto size = fs::file_size(path, ec);
  if (ec || size > max_bytes) return InvalidArgumentError("'" + path + "' is too large");
  std::ifstream in(path, std::ios::binary);
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (!in) return common::UnavailableError("cannot read '" + path + "'");
  return data;
}

Result<std::string> PathBelow(const std::string& root_folder, const std::string& relative) {
  std::error_code ec;
  fs::create_directories(root_folder, ec);
  const fs::path root = fs::weakly_canonical(root_folder, ec);
  if (ec) return common::UnavailableError("files root '" + root_folder + "' is unusable");
  if (relative.find('\0') != std::string::npos) {
    return InvalidArgumentError("path holds a NUL byte");
  }
  const fs::path candidate = fs::weakly_canonical(root / relative, ec);
  if (ec) return InvalidArgumentError("cannot resolve path '" + relative + "'");
  const fs::path rel = candidate.lexically_relative(root);
  if (rel.empty() || *rel.begin() == "..") {
    return InvalidArgumentError("path '" + relative + "' leaves the store's files folder");
  }
  return candidate.string();
}

std::string ShortestDecimal(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace cairn::mapstore::io
