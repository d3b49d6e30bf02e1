// cairn-map's commands that write files or the database (export, import, share, check,
// vacuum, migrate, put-profile, delete), and serve, which runs cairn-map-server.

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/map_cli_support.h"
#include "mapstore/map_operations.h"
#include "mapstore/map_transfer.h"
#include "mapstore/mapping_deriver.h"

namespace cairn::mapstore::cli {

namespace fs = std::filesystem;

namespace {

// "name: summary" of every registered export (or import) format, one per line.
std::string FormatList(bool exports) {
  const io::FormatRegistry& formats = io::BuiltinFormats();
  std::string out;
  if (exports) {
    for (const auto& [name, f] : formats.exporters()) out += "  " + name + ": " + f.summary + "\n";
  } else {
    for (const auto& [name, f] : formats.importers()) {
      out += "  " + name + " (" + Join(f.extensions, ", ") + "): " + f.summary + "\n";
    }
  }
  return out;
}

}  // namespace

int CmdExport(int argc, char** argv) {
  Common c;
  ExportOptions options;
  std::string mode = "trinary";
  common::FlagParser flags("cairn-map export",
                           "Writes a stored map to files in a registered format (below). Files "
                           "go into --out and nowhere else.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("format", &options.format,
                  Join(io::BuiltinFormats().ExportNames()) + " (see Formats)");
  flags.AddString("out", &options.folder, "target folder (created if missing)");
  flags.AddString("mode", &mode, "ros: trinary, scale or raw (raw keeps 0..100 exactly)");
  flags.AddString("layer", &options.layer, "ros/png: layer to write (default: see cairn-map help)");
  flags.AddString("profile", &options.profile,
                  "derive this profile's layers (cost/<profile>, verdicts)");
  flags.AddString("stem", &options.stem, "file name stem (default <map>_v<version>[_<layer>])");
  flags.AddDouble("occupied-thresh", &options.ros.occupied_thresh,
                  "ros: occupied above this probability");
  flags.AddDouble("free-thresh", &options.ros.free_thresh, "ros: free below this probability");
  flags.AddHelpSection("Formats", FormatList(true));
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (int rc = Need(options.folder, "out"); rc >= 0) return rc;
  auto parsed_mode = io::PgmModeFromName(mode);
  if (!parsed_mode.ok()) return Fail(parsed_mode.status());
  options.ros.mode = *parsed_mode;
  options.ref = c.ref();
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  const ProfileDeriver deriver = MappingDeriver();
  const ProgressFn progress = TerminalProgress();
  if (progress) progress(0.1, "exporting");
  auto files = ExportMap(**store, &deriver, options);
  if (progress) progress(1.0, "done");
  if (!files.ok()) return Fail(files.status());
  for (const std::string& f : *files) std::printf("%s\n", f.c_str());
  return 0;
}

int CmdImport(int argc, char** argv) {
  Common c;
  ImportOptions options;
  options.layer = layers::kStaticMap;
  common::FlagParser flags("cairn-map import",
                           "Imports a file as a new version of a map, read by a registered format "
                           "(below; by default the one of the file's extension). The new version "
                           "keeps the latest version's other content.");
  c.AddDb(&flags);
  c.AddMap(&flags, false);
  flags.AddString("file", &options.path, "the file (a .yaml, .bt, .ot or .csv, ...)");
  flags.AddString("format", &options.format, "read it as this format (default: by extension)");
  flags.AddString("layer", &options.layer, "layer that receives a YAML map");
  flags.AddString("robot", &options.provenance.source_robot,
                  "source robot recorded in the provenance");
  flags.AddString("profile", &options.provenance.source_profile,
                  "source profile recorded in the provenance");
  flags.AddHelpSection("Formats", FormatList(false));
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (int rc = Need(options.path, "file"); rc >= 0) return rc;
  options.site = c.site;
  options.name = c.map;
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  auto info = ImportMap(**store, options, {kActor, 0, 0});
  if (!info.ok()) return Fail(info.status());
  std::printf("imported %s as %s/%s version %lld (layers: %s)\n", options.path.c_str(),
              info->site.c_str(), info->name.c_str(), static_cast<long long>(info->version),
              Join(info->layers).c_str());
  return 0;
}

int CmdShare(int argc, char** argv) {
  Common c;
  std::string profile;
  common::FlagParser flags(
      "cairn-map share",
      "Derives a map's layers for another robot profile (cached in the database) "
      "and lists the obstacles whose verdict differs from the source profile's.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  flags.AddString("profile", &profile, "target profile (stored with put-profile)");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  if (int rc = Need(profile, "profile"); rc >= 0) return rc;
  const ProfileDeriver deriver = MappingDeriver();
  if (!deriver.valid()) return Fail(common::UnavailableError("built without the mapping core"));
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  const ProgressFn progress = TerminalProgress();
  if (progress) progress(0.1, "deriving " + profile);
  auto shared = ShareMap(**store, deriver, c.ref(), profile, {kActor, 0, 0});
  if (progress) progress(1.0, "done");
  if (!shared.ok()) return Fail(shared.status());
  std::printf("%s/%s version %lld for %s: layers %s (%s)\n", shared->info.site.c_str(),
              shared->info.name.c_str(), static_cast<long long>(shared->info.version),
              profile.c_str(), Join(shared->derived.layers.layer_names()).c_str(),
              shared->was_cached ? "from the cache" : "derived and cached");
  std::printf("%zu obstacles change verdict from %s to %s\n", shared->changed.size(),
              shared->source_profile.empty() ? "(unknown)" : shared->source_profile.c_str(),
              profile.c_str());
  if (!shared->changed.empty()) {
    Table t({"id", "kind", "x_m", "y_m", "before", "after"});
    for (const auto& o : shared->changed) {
      auto text = [](const common::ObstacleVerdict& v) {
        return v.profile + ": " +
               (v.crossable ? "crossable"
                            : std::string(common::VerdictWord(v)) + " (" + v.reason + ")");
      };
      t.Add({std::to_string(o.id), common::ObstacleKindName(o.kind), Fmt("%.2f", o.centroid_m.x()),
             Fmt("%.2f", o.centroid_m.y()), o.verdicts.size() > 1 ? text(o.verdicts[0]) : "-",
             text(o.verdicts.back())});
    }
    t.Print();
  }
  return 0;
}

int CmdCheck(int argc, char** argv) {
  Common c;
  common::FlagParser flags(
      "cairn-map check",
      "Checks a database: that it is a cairn database of a known schema, "
      "PRAGMA integrity_check, foreign keys, and every stored blob against its "
      "checksum. Exit status 0 when sound, 1 otherwise.");
  c.AddDb(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, false);
  if (!store.ok()) return Fail(store.status());
  auto report = (*store)->Check(TerminalProgress());
  if (!report.ok()) return Fail(report.status());
  for (const std::string& p : report->problems) std::printf("problem: %s\n", p.c_str());
  std::printf("%s: %lld map versions, %lld blobs checked: %s\n", c.db.c_str(),
              static_cast<long long>(report->maps_checked),
              static_cast<long long>(report->blobs_checked), report->ok ? "ok" : "DAMAGED");
  return report->ok ? 0 : 1;
}

int CmdVacuum(int argc, char** argv) {
  Common c;
  common::FlagParser flags(
      "cairn-map vacuum",
      "Removes blobs that no version or cache refers to and compacts the file. "
      "Soft-deleted maps keep their data.");
  c.AddDb(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  auto shrunk = (*store)->Vacuum(TerminalProgress());
  if (!shrunk.ok()) return Fail(shrunk.status());
  std::printf("%s: %lld bytes freed\n", c.db.c_str(), static_cast<long long>(*shrunk));
  return 0;
}

int CmdMigrate(int argc, char** argv) {
  Common c;
  common::FlagParser flags(
      "cairn-map migrate",
      "Opens a database for writing, which migrates an older schema to the current "
      "one in a single transaction.");
  c.AddDb(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  SqliteOptions options;
  options.create_if_missing = false;
  auto store = SqliteMapStore::Open(c.db, options);
  if (!store.ok()) return Fail(store.status());
  std::printf("%s: schema version %d\n", c.db.c_str(), (*store)->schema_version());
  return 0;
}

int CmdPutProfile(int argc, char** argv) {
  Common c;
  std::string file;
  common::FlagParser flags("cairn-map put-profile",
                           "Stores a robot profile YAML (config/profiles/*.yaml); storing the same "
                           "content again changes nothing.");
  c.AddDb(&flags);
  flags.AddString("file", &file, "profile YAML");
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = Need(file, "file"); rc >= 0) return rc;
  common::RobotProfile profile;
  try {
    profile = common::LoadRobotProfileFile(file);
  } catch (const std::exception& e) {
    return Fail(common::InvalidArgumentError(e.what()));
  }
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  common::Status s = (*store)->PutProfile(profile, {kActor, 0, 0});
  if (!s.ok()) return Fail(s);
  std::printf("profile %s stored (%s)\n", profile.name.c_str(), profile.ContentHash().c_str());
  return 0;
}

int CmdDelete(int argc, char** argv) {
  Common c;
  common::FlagParser flags(
      "cairn-map delete",
      "Marks a map (every version, or --version) deleted. The data stay; lists and "
      "loads no longer show it.");
  c.AddDb(&flags);
  c.AddMap(&flags);
  if (int rc = flags.Parse(argc, argv); rc >= 0) return rc;
  if (int rc = NeedMap(c); rc >= 0) return rc;
  auto store = OpenStore(c.db, true);
  if (!store.ok()) return Fail(store.status());
  common::Status s = (*store)->DeleteMap(c.ref(), {kActor, 0, 0});
  if (!s.ok()) return Fail(s);
  std::printf("deleted %s/%s%s\n", c.site.c_str(), c.map.c_str(),
              c.version == 0 ? "" : (" version " + std::to_string(c.version)).c_str());
  return 0;
}

int CmdServe(int argc, char** argv) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const std::string server =
      ec ? std::string("cairn-map-server") : (self.parent_path() / "cairn-map-server").string();
  std::vector<std::string> args = {server};
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  std::vector<char*> exec_argv;
  for (auto& a : args) exec_argv.push_back(a.data());
  exec_argv.push_back(nullptr);
  execvp(server.c_str(), exec_argv.data());
  std::fprintf(stderr, "cairn-map serve: cannot run %s: %s\n", server.c_str(),
               std::strerror(errno));
  return 1;
}

}  // namespace cairn::mapstore::cli
