#include "common/yaml_reader.h"

#include <set>

namespace cairn::common {

YamlMap::YamlMap(YAML::Node node, std::string where, std::string context)
    : node_(std::move(node)), where_(std::move(where)), context_(std::move(context)) {
  if (node_.IsNull()) node_ = YAML::Node(YAML::NodeType::Map);
  if (!node_.IsMap()) {
    Fail(node_, context_.empty() ? "expected a map" : "'" + context_ + "' must be a map");
  }
  // yaml-cpp keeps a key given twice and answers with one of the values: a line lost silently
  // (a process entry that lost its name under a pasted block, say). Refuse it.
  std::set<std::string> seen;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) continue;
    const std::string key = entry.first.Scalar();
    if (!seen.insert(key).second) {
      Fail(entry.first,
           "key '" + (context_.empty() ? key : context_ + "." + key) + "' given twice");
    }
  }
}

YamlMap YamlMap::LoadFile(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot read file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return YamlMap(root, path);
}

YamlMap YamlMap::FromString(const std::string& text, const std::string& where) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(where + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return YamlMap(root, where);
}

bool YamlMap::Has(const std::string& key) const { return static_cast<bool>(node_[key]); }

YAML::Node YamlMap::Lookup(const std::string& key) {
  used_.insert(key);
  return node_[key];
}

YamlMap YamlMap::Child(const std::string& key) {
  const std::string ctx = context_.empty() ? key : context_ + "." + key;
  if (!Has(key)) return YamlMap(YAML::Node(YAML::NodeType::Map), where_, ctx);
  return YamlMap(Lookup(key), where_, ctx);
}

std::vector<std::string> YamlMap::Keys() {
  std::vector<std::string> keys;
  for (const auto& kv : node_) {
    keys.push_back(As<std::string>(kv.first, "a key that is a name"));
    used_.insert(keys.back());
  }
  return keys;
}

YAML::Node YamlMap::Raw(const std::string& key) { return Lookup(key); }

YamlMap YamlMap::Wrap(const YAML::Node& node, const std::string& context) const {
  return YamlMap(node, where_, context);
}

void YamlMap::Finish() const {
  for (const auto& kv : node_) {
    const std::string key = As<std::string>(kv.first, "a key that is a name");
    if (used_.count(key) == 0) {
      Fail(kv.first, "unknown key '" + (context_.empty() ? key : context_ + "." + key) + "'");
    }
  }
}

std::string YamlMap::Where(const YAML::Node& node) const {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return where_ + ": ";
  return where_ + ":" + std::to_string(mark.line + 1) + ": ";
}

void YamlMap::Fail(const YAML::Node& node, const std::string& message) const {
  throw ConfigError(Where(node) + message);
}

}  // namespace cairn::common
