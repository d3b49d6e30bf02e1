#include "mapstore/map_cli.h"

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "mapstore/io/format_registry.h"
#include "mapstore/map_cli_support.h"

namespace cairn::mapstore {
namespace {

struct Command {
  const char* name;
  const char* summary;
  std::function<int(int, char**)> run;
};

const std::vector<Command>& Commands() {
  using namespace cli;
  static const std::vector<Command> commands = {
      {"list", "list stored maps", CmdList},
      {"show", "summary of one map version", CmdShow},
      {"export", "write a map in a registered format (see Export formats)", CmdExport},
      {"import", "read a file in a registered format into a new version", CmdImport},
      {"share", "derive a map for another profile; verdicts that change", CmdShare},
      {"diff", "compare two versions, or one version under two profiles", CmdDiff},
      {"eval", "judge a map against a simulator world's geometry (precision, recall, ...)",
       CmdEval},
      {"check", "integrity check (exit 1 when damaged)", CmdCheck},
      {"vacuum", "drop unreferenced blobs, compact the file", CmdVacuum},
      {"migrate", "migrate an older schema", CmdMigrate},
      {"profiles", "list robot profiles", CmdProfiles},
      {"put-profile", "store a robot profile YAML", CmdPutProfile},
      {"delete", "soft-delete a map or version", CmdDelete},
      {"audit", "recent changes", CmdAudit},
      {"places", "semantic places of a site", CmdPlaces},
      {"serve", "serve a stored map to a robot on the bus (cairn-map-server)", CmdServe},
  };
  return commands;
}

void Usage(FILE* out) {
  std::fprintf(out,
               "usage: cairn-map <command> [flags]   (cairn-map <command> --help for its flags)\n\n"
               "Works on a cairn map database directly (default %s).\n\ncommands:\n",
               cli::kDefaultDb);
  for (const Command& c : Commands()) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(out, "\nexport formats:\n");
  for (const auto& [name, format] : io::BuiltinFormats().exporters()) {
    std::fprintf(out, "  %-12s %s\n", name.c_str(), format.summary.c_str());
  }
  std::fprintf(out, "\nimport formats:\n");
  for (const auto& [name, format] : io::BuiltinFormats().importers()) {
    std::fprintf(out, "  %-12s %s (%s)\n", name.c_str(), format.summary.c_str(),
                 cli::Join(format.extensions).c_str());
  }
  std::fprintf(out,
               "\nDefault export layer: cost/<profile> with --profile; else for ros the first of "
               "final, static, occupancy, occupancy_logodds, long_term, short_term; for png "
               "elevation.\nExit status: 0 success, 1 failure (or damage found), 2 bad usage.\n");
}

}  // namespace

int RunMapCli(int argc, char** argv) {
  if (argc < 2) {
    Usage(stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (command == "--help" || command == "-h" || command == "help") {
    Usage(stdout);
    return 0;
  }
  for (const Command& c : Commands()) {
    if (command == c.name) {
      try {
        return c.run(argc - 1, argv + 1);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "cairn-map %s: %s\n", c.name, e.what());
        return 1;
      }
    }
  }
  std::fprintf(stderr, "cairn-map: unknown command '%s'\n\n", command.c_str());
  Usage(stderr);
  return 2;
}

}  // namespace cairn::mapstore
