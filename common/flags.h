#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

/// @file
/// Command-line flags for the thin *_main.cc processes: "--name value" or "--name=value",
/// "--help" prints the usage. Unknown flags are an error.

namespace cairn::common {

class FlagParser {
 public:
  /// @param program the executable name; @param summary one paragraph printed by --help.
  FlagParser(std::string program, std::string summary);

  void AddString(const std::string& name, std::string* value, const std::string& help);
  void AddDouble(const std::string& name, double* value, const std::string& help);
  void AddInt(const std::string& name, int* value, const std::string& help);
  void AddBool(const std::string& name, bool* value, const std::string& help);
  /// A flag that may be given several times; each occurrence appends its value.
  void AddStringList(const std::string& name, std::vector<std::string>* values,
                     const std::string& help);
  /// A free-form section appended to --help (lists of worlds, robots, sensors, ...).
  void AddHelpSection(const std::string& title, const std::string& body);

  /// Parses argv. Returns -1 to continue, otherwise the exit code the program should return
  /// (0 after --help, 2 after an error, which is printed to stderr).
  int Parse(int argc, char** argv);
  /// Positional arguments left after the flags.
  const std::vector<std::string>& positional() const { return positional_; }
  std::string Usage() const;

 private:
  struct Flag {
    std::string help;
    std::string default_text;
    bool is_bool{false};
    std::function<bool(const std::string&)> set;
  };
  std::string program_;
  std::string summary_;
  std::map<std::string, Flag> flags_;
  std::vector<std::string> order_;
  std::vector<std::pair<std::string, std::string>> sections_;
  std::vector<std::string> positional_;
};

}  // namespace cairn::common
