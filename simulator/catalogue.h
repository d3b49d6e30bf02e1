#pragma once

#include <string>

#include "simulator/scenario.h"
#include "simulator/sensor_registry.h"

/// @file
/// What cairn-sim can simulate, as text for `cairn-sim --help`: the shipped worlds and robot
/// models of a data folder, and the sensor kinds of a registry.

namespace cairn::sim {

/// "  <world>: <summary>" per shipped world, and a line saying any MJCF file will do.
std::string DescribeWorlds(const SimPaths& paths);
/// "  <model>: <description>" per shipped robot, with its default profile and sensors.
std::string DescribeRobots(const SimPaths& paths);
/// "  <sensor>: <description>" per sensor kind.
std::string DescribeSensors(const SensorRegistry& registry = BuiltinSensors());

}  // namespace cairn::sim
