#include "simulator/catalogue.h"

#include <exception>
#include <sstream>

namespace cairn::sim {

std::string DescribeWorlds(const SimPaths& paths) {
  std::ostringstream out;
  for (const std::string& world : paths.ShippedWorlds()) {
    out << "  " << world << ": " << paths.WorldSummary(world) << "\n";
  }
  out << "  (or the path of any MJCF file: robots are inserted into it)\n";
  return out.str();
}

std::string DescribeRobots(const SimPaths& paths) {
  std::ostringstream out;
  for (const std::string& name : paths.ShippedRobots()) {
    try {
      const RobotModel model = LoadRobotModel(paths, name);
      out << "  " << name << ": " << model.description << "\n      default profile "
          << model.default_profile << "; sensors:";
      for (const std::string& s : model.default_sensors.Names()) out << " " << s;
      out << "\n";
    } catch (const std::exception& e) {
      out << "  " << name << ": (unreadable: " << e.what() << ")\n";
    }
  }
  return out.str();
}

std::string DescribeSensors(const SensorRegistry& registry) {
  std::ostringstream out;
  for (const auto& [name, description] : registry.Catalogue()) {
    out << "  " << name << ": " << description << "\n";
  }
  return out.str();
}

}  // namespace cairn::sim
