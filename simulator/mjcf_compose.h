#pragma once

#include <string>
#include <vector>

/// @file
/// Composition of the simulated scene as MJCF text. MuJoCo 2.2 has no model-editing API, so
/// robots and the pool of spawnable objects are inserted into the user's world file as XML:
///
/// - each robot file's <worldbody>, <asset>, <contact>, <actuator> and <sensor> contents are
///   copied with every name and name reference prefixed by "<robot id>/";
/// - the robot bodies and the spawn pool go at the end of the world's <worldbody>, the other
///   sections before the closing </mujoco>.
///
/// The buffers MuJoCo allocates for the result (<size nconmax njmax nstack>) are sized from the
/// compiled scene by model_capacity.h (MujocoSim does it).
///
/// Robot files are ordinary MJCF files (loadable on their own) and must not use default classes
/// or angle-valued attributes (euler, axisangle) so that the world's <compiler> and <default>
/// settings cannot change them.

namespace cairn::sim {

/// Geom group conventions of composed scenes.
inline constexpr int kRobotGeomGroup = 3;     ///< robot geoms (seen by other robots' sensors)
inline constexpr int kSensorHiddenGroup = 4;  ///< collides but is invisible to sensors
inline constexpr int kParkedGeomGroup = 5;    ///< unused spawn-pool geoms
inline constexpr char kSpawnGeomPrefix[] = "cairn_spawn_";

struct RobotInsertion {
  std::string id;      ///< robot id, the name prefix
  std::string xml;     ///< the robot MJCF file's text
  std::string source;  ///< file name, for messages
};

/// Inserts robots and `spawn_slots` parked world-body geoms (named "cairn_spawn_<k>", whose
/// type, size and pose are set at spawn time) into world MJCF text.
/// @throws std::invalid_argument naming `world_source` or the robot file when a section is
/// missing or malformed, or a robot id is not [A-Za-z0-9_-]+.
std::string ComposeScene(const std::string& world_xml, const std::string& world_source,
                         const std::vector<RobotInsertion>& robots, int spawn_slots);

/// Text between <tag ...> and </tag> (first occurrence, comments removed), or "" when absent.
/// A self-closing <tag/> yields "".
std::string ExtractSection(const std::string& xml, const std::string& tag, bool* found);

/// Prefixes the values of name and name-reference attributes (name, joint, site, body, geom,
/// objname, material, mesh, ...) with "<prefix>/".
std::string PrefixNames(const std::string& xml_fragment, const std::string& prefix);

/// Removes <!-- ... --> comments, keeping their line breaks.
std::string StripXmlComments(const std::string& xml);

}  // namespace cairn::sim
