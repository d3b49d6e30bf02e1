#pragma once

#include <cstddef>
#include <string>

#include "common/status.h"

/// @file
/// File handling shared by every export and import format: writers take a target folder and a
/// plain file name and never write elsewhere (names with '/' or "..", or an existing symlink in
/// the folder, are refused); files are written to a temporary name and renamed, so a reader
/// never sees half a file.

namespace cairn::mapstore::io {

/// The path `folder`/`file_name` after checking that it stays inside `folder` (created if
/// missing) and is not a symlink or a directory.
common::Result<std::string> SafeOutputPath(const std::string& folder, const std::string& file_name);
/// Writes bytes atomically (temporary file + rename) to a path from SafeOutputPath.
common::Status WriteFileAtomically(const std::string& path, const std::string& bytes);
/// SafeOutputPath of "<stem><extension>" after checking the stem is a plain name (ValidateName).
common::Result<std::string> OutputPath(const std::string& folder, const std::string& stem,
                                       const std::string& extension);
common::Result<std::string> ReadFile(const std::string& path, size_t max_bytes = 1u << 30);

/// `relative` resolved below `root` (created if missing): kInvalidArgument when it would leave
/// it (through "..", an absolute path or a symlink), kUnavailable when the root is unusable.
common::Result<std::string> PathBelow(const std::string& root, const std::string& relative);

/// The shortest decimal text that reads back as exactly `v` ("nan" for NaN).
std::string ShortestDecimal(double v);

}  // namespace cairn::mapstore::io
