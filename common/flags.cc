#include "common/flags.h"

#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace cairn::common {

FlagParser::FlagParser(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

void FlagParser::AddString(const std::string& name, std::string* value, const std::string& help) {
  flags_[name] = {help, *value, false, [value](const std::string& v) {
                    *value = v;
                    return true;
                  }};
  order_.push_back(name);
}

void FlagParser::AddDouble(const std::string& name, double* value, const std::string& help) {
  std::ostringstream def;
  def << *value;
  flags_[name] = {help, def.str(), false, [value](const std::string& v) {
                    char* end = nullptr;
                    const double d = std::strtod(v.c_str(), &end);
                    if (end == v.c_str() || *end != '\0') return false;
                    *value = d;
                    return true;
                  }};
  order_.push_back(name);
}

void FlagParser::AddInt(const std::string& name, int* value, const std::string& help) {
  flags_[name] = {help, std::to_string(*value), false, [value](const std::string& v) {
                    char* end = nullptr;
                    const long d = std::strtol(v.c_str(), &end, 10);
                    if (end == v.c_str() || *end != '\0') return false;
                    *value = static_cast<int>(d);
                    return true;
                  }};
  order_.push_back(name);
}

void FlagParser::AddBool(const std::string& name, bool* value, const std::string& help) {
  flags_[name] = {help, *value ? "true" : "false", true, [value](const std::string& v) {
                    if (v == "true" || v == "1" || v.empty()) {
                      *value = true;
                    } else if (v == "false" || v == "0") {
                      *value = false;
                    } else {
                      return false;
                    }
                    return true;
                  }};
  order_.push_back(name);
}

void FlagParser::AddStringList(const std::string& name, std::vector<std::string>* values,
                               const std::string& help) {
  flags_[name] = {help + " (repeatable)", "", false, [values](const std::string& v) {
                    values->push_back(v);
                    return true;
                  }};
  order_.push_back(name);
}

void FlagParser::AddHelpSection(const std::string& title, const std::string& body) {
  sections_.emplace_back(title, body);
}

std::string FlagParser::Usage() const {
  std::ostringstream out;
  out << "usage: " << program_ << " [flags]\n\n" << summary_ << "\n\nflags:\n";
  for (const auto& name : order_) {
    const Flag& f = flags_.at(name);
    std::string left = "  --" + name + (f.is_bool ? "" : " VALUE");
    if (left.size() < 28) left.resize(28, ' ');
    out << left << " " << f.help;
    if (!f.default_text.empty()) out << " (default: " << f.default_text << ")";
    out << "\n";
  }
  out << "  --help                       print this help and exit\n";
  for (const auto& [title, body] : sections_) out << "\n" << title << ":\n" << body;
  if (!sections_.empty() && !sections_.back().second.empty() && sections_.back().second.back() != '\n') {
    out << "\n";
  }
  return out.str();
}

int FlagParser::Parse(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(Usage().c_str(), stdout);
      return 0;
    }
    if (arg.rfind("--", 0) != 0 || arg == "--") {
      if (arg == "--") {
        for (++i; i < argc; ++i) positional_.push_back(argv[i]);
        break;
      }
      positional_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2), value;
    bool has_value = false;
    const auto eq = name.find('=');
    if (eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    auto it = flags_.find(name);
    if (it == flags_.end()) {
      std::fprintf(stderr, "%s: unknown flag --%s (see --help)\n", program_.c_str(), name.c_str());
      return 2;
    }
    if (!has_value && !it->second.is_bool) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: flag --%s needs a value\n", program_.c_str(), name.c_str());
        return 2;
      }
      value = argv[++i];
    }
    if (!it->second.set(value)) {
      std::fprintf(stderr, "%s: bad value '%s' for --%s\n", program_.c_str(), value.c_str(),
                   name.c_str());
      return 2;
    }
  }
  return -1;
}

}  // namespace cairn::common
