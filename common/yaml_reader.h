#pragma once

#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

/// @file
/// Strict YAML reading for params structs, used only from *_main.cc and config loaders.
/// Every error names the file and line; a key nobody asked for is an error
/// (Cartographer's CheckAllKeysWereUsedExactlyOnce, Drake's allow_yaml_with_no_cpp=false).

namespace cairn::common {

/// A configuration error, with "file:line: " already in what().
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads one YAML map. Call Get/Require for every field you know, then Finish(), which throws
/// on any key that was not read.
class YamlMap {
 public:
  /// @param where the file name (for messages); @param context a dotted path ("processes.sim").
  YamlMap(YAML::Node node, std::string where, std::string context = "");

  /// Loads a file and returns its root map. @throws ConfigError if unreadable or not a map.
  static YamlMap LoadFile(const std::string& path);
  /// Parses a string (tests, inline configs).
  static YamlMap FromString(const std::string& text, const std::string& where = "<string>");

  bool Has(const std::string& key) const;
  /// Reads key into *out when present; returns whether it was present.
  template <typename T>
  bool Get(const std::string& key, T* out);
  template <typename T>
  T Require(const std::string& key);
  /// A node's value (an element of a sequence, a key), converted.
  /// @throws ConfigError naming its line when it is not a `what`.
  template <typename T>
  T As(const YAML::Node& node, const std::string& what) const;
  /// A nested map.
  YamlMap Child(const std::string& key);
  /// Keys of this map in file order (marks them read).
  std::vector<std::string> Keys();
  /// The raw node of a key (marks it read), for sequences of maps.
  YAML::Node Raw(const std::string& key);
  /// A nested map built from a raw node (elements of a sequence).
  YamlMap Wrap(const YAML::Node& node, const std::string& context) const;

  /// @throws ConfigError naming the first unknown key and its line.
  void Finish() const;

  /// "file:line: " of a node (or of this map).
  std::string Where(const YAML::Node& node) const;
  std::string Where() const { return Where(node_); }
  const std::string& file() const { return where_; }
  [[noreturn]] void Fail(const YAML::Node& node, const std::string& message) const;

 private:
  YAML::Node Lookup(const std::string& key);

  YAML::Node node_;
  std::string where_;
  std::string context_;
  std::set<std::string> used_;
};

template <typename T>
bool YamlMap::Get(const std::string& key, T* out) {
  if (!Has(key)) return false;
  YAML::Node value = Lookup(key);
  try {
    *out = value.as<T>();
  } catch (const YAML::Exception&) {
    Fail(value, "bad value for '" + (context_.empty() ? key : context_ + "." + key) + "'");
  }
  return true;
}

template <typename T>
T YamlMap::As(const YAML::Node& node, const std::string& what) const {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    Fail(node, "expected " + what);
  }
}

template <typename T>
T YamlMap::Require(const std::string& key) {
  T value{};
  if (!Get(key, &value)) {
    Fail(node_, "missing required key '" + (context_.empty() ? key : context_ + "." + key) + "'");
  }
  return value;
}

}  // namespace cairn::common
