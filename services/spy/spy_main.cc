// cairn-spy: a terminal spy for the cairn bus.

#include <algorithm>
#include <chrono>
#include <cstdio>

#include <unistd.h>

#include "common/flags.h"
#include "services/launch/graph.h"
#include "services/runtime/node.h"
#include "services/spy/lcm/spy.h"

using namespace cairn;

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::string lcm_url, graph_file;
  bool once = false, strict = false;
  double duration_s = 3.0, refresh_s = 1.0;
  common::FlagParser flags(
      "cairn-spy",
      "Shows every channel on the bus: decoded type (by fingerprint among the cairn types),\n"
      "messages/s, bandwidth, decode errors and the age of the last message. With --graph, each\n"
      "channel's expected rate from the graph file, marked SLOW when below 80 % of it. Expected\n"
      "rates are in simulated time: when SIM.CLOCK shows the simulator running slower than real\n"
      "time, they are judged at its pace.");
  flags.AddString("lcm-url", &lcm_url, "LCM bus (else LCM_DEFAULT_URL, else the default udpm URL)");
  flags.AddString("graph", &graph_file, "a cairn-launch graph whose expected_rates_hz to check");
  flags.AddBool("once", &once, "listen for --duration seconds, print one table and exit");
  flags.AddDouble("duration", &duration_s, "--once: seconds to listen");
  flags.AddDouble("refresh", &refresh_s, "seconds between tables in continuous mode");
  flags.AddBool("strict", &strict, "--once: exit 1 when an expected channel is slow or missing");
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  try {
    std::map<std::string, double> expected;
    if (!graph_file.empty()) {
      expected = launch::LoadGraph(graph_file, {}, /*require_executables=*/false).ExpectedRates();
    }
    runtime::NodeOptions options;
    options.process_name = "cairn-spy";
    options.lcm_url = lcm_url;
    options.follow_sim_clock = false;
    runtime::Node node(options);
    node.SetState(runtime::HealthState::kReady);
    // --once measures over its whole listening time; the live table over the last 3 s.
    spy::Spy spy(expected, once ? std::max(duration_s, 1.0) : 3.0);
    node.SubscribeRaw(".*", [&](const std::string& channel, const void* data, int size, int64_t) {
      spy.OnMessage(channel, data, size, Now());
    });
    const bool tty = isatty(STDOUT_FILENO);
    if (once) {
      const double end = Now() + duration_s;
      while (Now() < end && node.SpinOnce(20)) {
      }
      const std::string table = spy.Format(Now());
      std::fputs(table.c_str(), stdout);
      if (strict) {
        for (const auto& [c, v] : spy.Snapshot(Now())) {
          if (v.expected_hz > 0 && v.slow) return 1;
        }
      }
      return 0;
    }
    node.AddTimer(refresh_s, [&] {
      if (tty) std::fputs("\033[H\033[2J", stdout);
      std::printf("cairn-spy on %s\n", node.url().c_str());
      std::fputs(spy.Format(Now()).c_str(), stdout);
      std::fflush(stdout);
    });
    return node.Spin();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-spy: %s\n", e.what());
    return 2;
  }
}
