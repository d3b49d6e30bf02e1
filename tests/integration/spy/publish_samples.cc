// Test helper: publishes N value-initialised messages of every cairn type, each on the channel
// "SAMPLE.<type>", on the LCM URL given as argv[1].

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmtypes_registry.hpp"

int main(int argc, char** argv) {
  if (argc < 3) return 2;
  lcm::LCM lcm(argv[1]);
  if (!lcm.good()) return 3;
  const int count = std::atoi(argv[2]);
  for (int i = 0; i < count; ++i) {
    for (const auto& t : cairn::AllLcmTypes()) {
      const auto bytes = t.sample();
      const std::string name = t.name;
      lcm.publish("SAMPLE." + name.substr(name.find('.') + 1), bytes.data(),
                  static_cast<unsigned>(bytes.size()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return 0;
}
