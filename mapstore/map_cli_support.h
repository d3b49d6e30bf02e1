#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/flags.h"
#include "common/status.h"
#include "mapstore/map_store.h"
#include "mapstore/sqlite_map_store.h"

/// @file
/// What the commands of cairn-map share (mapstore/map_cli.h): aligned tables, number and time
/// formatting, the common flags, opening the database. Internal to the command line.

namespace cairn::mapstore::cli {

inline constexpr char kDefaultDb[] = "var/cairn.db";
inline constexpr char kActor[] = "cairn-map";

/// Aligned columns, header first.
class Table {
 public:
  explicit Table(std::vector<std::string> header) { rows_.push_back(std::move(header)); }
  void Add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  void Print() const;

 private:
  std::vector<std::vector<std::string>> rows_;
};

/// printf of one number.
std::string Fmt(const char* format, double v);
/// UTC time of a utime ("-" for none).
std::string Time(int64_t utime);
std::string Join(const std::vector<std::string>& items, const char* sep = ", ");
/// Prints the status and returns exit status 1.
int Fail(const common::Status& s);
/// A progress bar on a terminal, nothing otherwise.
ProgressFn TerminalProgress();

/// Flags every command shares.
struct Common {
  std::string db{kDefaultDb};
  std::string site{kDefaultSite};
  std::string map;
  int version{0};
  void AddDb(common::FlagParser* f) { f->AddString("db", &db, "database file"); }
  void AddMap(common::FlagParser* f, bool with_version = true);
  MapRef ref() const { return {site, map, version}; }
};

common::Result<std::unique_ptr<SqliteMapStore>> OpenStore(const std::string& path, bool write);
/// Exit status 2 with a message when --map is missing, else -1 (go on).
int NeedMap(const Common& c);
/// Exit status 2 with a message when a required flag is empty, else -1 (go on).
int Need(const std::string& value, const char* flag);

// The commands: each parses its own flags (argv[0] is the command) and returns the exit status.
int CmdList(int argc, char** argv);
int CmdShow(int argc, char** argv);
int CmdDiff(int argc, char** argv);
int CmdEval(int argc, char** argv);
int CmdProfiles(int argc, char** argv);
int CmdAudit(int argc, char** argv);
int CmdPlaces(int argc, char** argv);
int CmdExport(int argc, char** argv);
int CmdImport(int argc, char** argv);
int CmdShare(int argc, char** argv);
int CmdCheck(int argc, char** argv);
int CmdVacuum(int argc, char** argv);
int CmdMigrate(int argc, char** argv);
int CmdPutProfile(int argc, char** argv);
int CmdDelete(int argc, char** argv);
int CmdServe(int argc, char** argv);

}  // namespace cairn::mapstore::cli
