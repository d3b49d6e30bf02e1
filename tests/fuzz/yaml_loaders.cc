// Every YAML loader: robot profiles, the mapper's, navigator's, explorer's and map store's
// configurations, simulator scenarios and launch graphs. The first byte picks the loader, the
// rest is the file. A bad file is a ConfigError (or std::invalid_argument from a Validate)
// naming what was wrong; anything else escaping is a finding.

#include <stdexcept>
#include <string>

#include "common/robot_profile.h"
#include "common/yaml_reader.h"
#include "mapstore/mapstore_params.h"
#include "planner/navigator_config.h"
#include "services/explore/explorer_config.h"
#include "services/launch/graph.h"
#include "services/mapping/mapper_config.h"
#include "simulator/scenario.h"

namespace {

void Load(int pick, const std::string& text) {
  using cairn::common::YamlMap;
  switch (pick) {
    case 0:
      (void)cairn::common::LoadRobotProfileString(text);
      break;
    case 1: {
      YamlMap root = YamlMap::FromString(text);
      (void)cairn::mapping::LoadMapperConfig(root);
      break;
    }
    case 2: {
      YamlMap root = YamlMap::FromString(text);
      (void)cairn::planner::LoadNavigatorConfig(root);
      break;
    }
    case 3: {
      YamlMap root = YamlMap::FromString(text);
      (void)cairn::explore::LoadExplorerConfig(root);
      break;
    }
    case 4: {
      YamlMap root = YamlMap::FromString(text);
      (void)cairn::mapstore::LoadMapstoreParams(root);
      break;
    }
    case 5: {
      YamlMap root = YamlMap::FromString(text);
      (void)cairn::sim::LoadScenario(root, cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR));
      break;
    }
    default:
      (void)cairn::launch::LoadGraphString(text, "<fuzz>", {}, /*require_executables=*/false);
      break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    Load(data[0] % 7, text);
  } catch (const cairn::common::ConfigError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
