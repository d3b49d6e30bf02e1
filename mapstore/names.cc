#include "mapstore/names.h"

#include <cctype>
#include <cstdio>

namespace cairn::mapstore {
namespace {

bool IsNameChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
}

// Printable form of a rejected name for messages (control bytes escaped, length capped).
std::string Quote(const std::string& name) {
  std::string out = "'";
  for (size_t i = 0; i < name.size() && i < 80; ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (std::isprint(c)) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", c);
      out += buf;
    }
  }
  if (name.size() > 80) out += "...";
  return out + "'";
}

}  // namespace

common::Status ValidateName(const std::string& what, const std::string& name) {
  if (name.empty()) return common::InvalidArgumentError(what + " is empty");
  if (name.size() > kMaxNameLength) {
    return common::InvalidArgumentError(what + " " + Quote(name) + " is longer than " +
                                        std::to_string(kMaxNameLength) + " characters");
  }
  if (!std::isalnum(static_cast<unsigned char>(name[0]))) {
    return common::InvalidArgumentError(what + " " + Quote(name) +
                                        " must start with a letter or digit");
  }
  for (char c : name) {
    if (!IsNameChar(c)) {
      return common::InvalidArgumentError(what + " " + Quote(name) +
                                          " may only use letters, digits, '_', '.' and '-'");
    }
  }
  if (name.find("..") != std::string::npos) {
    return common::InvalidArgumentError(what + " " + Quote(name) + " may not contain '..'");
  }
  return common::Status::Ok();
}

common::Status ValidateLayerName(const std::string& name) {
  if (name.size() > 128) {
    return common::InvalidArgumentError("layer name " + Quote(name) + " is too long");
  }
  size_t start = 0;
  while (true) {
    const size_t slash = name.find('/', start);
    const std::string part =
        name.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    common::Status s = ValidateName("layer name part", part);
    if (!s.ok()) {
      return common::InvalidArgumentError("layer name " + Quote(name) + ": " + s.message());
    }
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return common::Status::Ok();
}

common::Status ValidatePlaceName(const std::string& name) {
  if (name.empty()) return common::InvalidArgumentError("place name is empty");
  if (name.size() > kMaxNameLength) {
    return common::InvalidArgumentError("place name " + Quote(name) + " is too long");
  }
  if (!std::isalnum(static_cast<unsigned char>(name[0]))) {
    return common::InvalidArgumentError("place name " + Quote(name) +
                                        " must start with a letter or digit");
  }
  for (char c : name) {
    if (!IsNameChar(c) && c != ' ') {
      return common::InvalidArgumentError("place name " + Quote(name) +
                                          " may only use letters, digits, spaces, '_', '.', '-'");
    }
  }
  return common::Status::Ok();
}

}  // namespace cairn::mapstore
