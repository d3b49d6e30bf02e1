#include "simulator/mjcf_compose.h"

#include <regex>
#include <sstream>
#include <stdexcept>

namespace cairn::sim {
namespace {

// Finds "<tag" followed by whitespace, '>' or '/' at or after `from`.
size_t FindOpenTag(const std::string& xml, const std::string& tag, size_t from) {
  const std::string open = "<" + tag;
  for (size_t pos = xml.find(open, from); pos != std::string::npos; pos = xml.find(open, pos + 1)) {
    const size_t next = pos + open.size();
    if (next < xml.size()) {
      const char c = xml[next];
      if (c == '>' || c == '/' || c == ' ' || c == '\t' || c == '\n' || c == '\r') return pos;
    }
  }
  return std::string::npos;
}

bool ValidRobotId(const std::string& id) {
  if (id.empty()) return false;
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

std::string SpawnPool(int slots) {
  std::ostringstream xml;
  xml << "\n    <!-- cairn-sim: pool of objects spawned at run time (parked below the floor) -->\n";
  for (int k = 0; k < slots; ++k) {
    // Geoms of the world body: no extra bodies for MuJoCo's broad phase to sort. Their type,
    // size and pose are set at run time.
    xml << "    <geom name=\"" << kSpawnGeomPrefix << k << "\" type=\"box\" size=\"0.1 0.1 0.1\""
        << " pos=\"" << 2.0 * k << " 0 -50\" contype=\"0\" conaffinity=\"0\" group=\""
        << kParkedGeomGroup << "\" rgba=\"0.55 0.45 0.35 1\"/>\n";
  }
  return xml.str();
}

}  // namespace

std::string StripXmlComments(const std::string& xml) {
  std::string out;
  out.reserve(xml.size());
  size_t pos = 0;
  while (pos < xml.size()) {
    const size_t open = xml.find("<!--", pos);
    if (open == std::string::npos) {
      out.append(xml, pos, std::string::npos);
      break;
    }
    out.append(xml, pos, open - pos);
    const size_t close = xml.find("-->", open + 4);
    if (close == std::string::npos) break;  // unterminated comment: MuJoCo will report it
    // Keep the comment's line breaks so MuJoCo's line numbers still point into the file.
    for (size_t i = open; i < close; ++i) {
      if (xml[i] == '\n') out.push_back('\n');
    }
    pos = close + 3;
  }
  return out;
}

std::string ExtractSection(const std::string& xml_in, const std::string& tag, bool* found) {
  const std::string xml = StripXmlComments(xml_in);
  *found = false;
  const size_t open = FindOpenTag(xml, tag, 0);
  if (open == std::string::npos) return "";
  const size_t open_end = xml.find('>', open);
  if (open_end == std::string::npos) return "";
  *found = true;
  if (xml[open_end - 1] == '/') return "";  // <tag/>
  const size_t close = xml.find("</" + tag, open_end);
  if (close == std::string::npos) {
    *found = false;
    return "";
  }
  return xml.substr(open_end + 1, close - open_end - 1);
}

std::string PrefixNames(const std::string& fragment, const std::string& prefix) {
  // Attributes that hold a name or refer to one (MJCF 2.2).
  static const std::regex kNameAttr(
      R"re(\b(name|joint|joint1|joint2|site|refsite|body|body1|body2|geom|geom1|geom2|objname|)re"
      R"re(refname|tendon|actuator|material|mesh|texture|hfield|target|jointinparent|)re"
      R"re(cranksite|slidersite)\s*=\s*"([^"]*)")re");
  return std::regex_replace(fragment, kNameAttr, "$1=\"" + prefix + "/$2\"");
}

std::string ComposeScene(const std::string& world_xml_in, const std::string& world_source,
                         const std::vector<RobotInsertion>& robots, int spawn_slots) {
  if (spawn_slots < 0) throw std::invalid_argument("spawn_slots must be >= 0");
  const std::string world = StripXmlComments(world_xml_in);
  const size_t body_close = world.rfind("</worldbody>");
  const size_t mujoco_close = world.rfind("</mujoco>");
  if (FindOpenTag(world, "mujoco", 0) == std::string::npos || mujoco_close == std::string::npos) {
    throw std::invalid_argument(world_source + ": not an MJCF file (no <mujoco> element)");
  }
  if (body_close == std::string::npos || body_close > mujoco_close) {
    throw std::invalid_argument(world_source + ": the world has no <worldbody> ... </worldbody>");
  }

  std::string bodies;
  std::string sections;
  for (const RobotInsertion& robot : robots) {
    if (!ValidRobotId(robot.id)) {
      throw std::invalid_argument("robot id '" + robot.id +
                                  "' must be letters, digits, '_' or '-'");
    }
    bool found = false;
    const std::string body = ExtractSection(robot.xml, "worldbody", &found);
    if (!found || body.find("<body") == std::string::npos) {
      throw std::invalid_argument(robot.source + ": robot file has no <worldbody> with a <body>");
    }
    bodies += "\n    <!-- robot " + robot.id + " (" + robot.source + ") -->\n" +
              PrefixNames(body, robot.id) + "\n";
    for (const char* tag : {"asset", "contact", "actuator", "sensor"}) {
      const std::string section = ExtractSection(robot.xml, tag, &found);
      if (found && !section.empty()) {
        sections +=
            std::string("  <") + tag + ">" + PrefixNames(section, robot.id) + "</" + tag + ">\n";
      }
    }
  }
  bodies += SpawnPool(spawn_slots);

  std::string out = world.substr(0, body_close) + bodies + "  ";
  out += world.substr(body_close, mujoco_close - body_close);
  out += sections;
  out += world.substr(mujoco_close);
  return out;
}

}  // namespace cairn::sim
