// LCM transport of HDL-32E-sized revolutions (~70,000 points, 1.19 MB) between two processes:
// what a mapper pays to have a revolution in hand. The revolution travels as slices (cut by
// runtime::SplitSlice and paced over the revolution period, as a spinning sensor delivers them)
// against the same revolution sent as one message at the end of its period. Both sides run the
// real code path: the sender converts each message (runtime::ToLcm) when its points are ready,
// the receiver decodes, converts back (runtime::FromLcm) and assembles revolutions
// (runtime::RevolutionAssembler).
//
// Headline per rate: the revolution latency, from the moment the revolution's last points were
// ready at the sender to the moment the receiver holds the assembled revolution (p50, p99 over
// delivered revolutions), and the share of revolutions delivered whole (a revolution missing one
// slice, or a whole message lost, is a failure: counted, never left out quietly). Parts: message
// loss and the latency of single messages. Kernel default receive buffer.
//
// The benchmark forks a receiver process (this executable with --receiver) on a private
// multicast port (ttl=0).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cairn/lcmt_point_cloud_slice.hpp"

#include "bench/support/figure.h"
#include "services/runtime/conversions.h"
#include "services/runtime/revolution_assembler.h"
#include "services/runtime/tiler.h"

namespace {

constexpr int kRings = 32;
constexpr int kAzimuths = 2187;  // 32 x 2187 = 69,984 points, the simulated HDL-32E of Gazebo
constexpr size_t kSliceBytes = 64000;

int64_t WallUtime() {
  timeval tv{};
  gettimeofday(&tv, nullptr);
  return static_cast<int64_t>(tv.tv_sec) * 1000000 + tv.tv_usec;
}

cairn::common::LidarSlice MakeRevolution() {
  cairn::common::LidarSlice rev;
  rev.robot = "bench";
  rev.azimuth_start_rad = 0.0;
  rev.azimuth_end_rad = 2 * M_PI;
  rev.max_range_m = 70.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> range(1.0f, 40.0f);
  rev.points.reserve(kRings * kAzimuths);
  for (int a = 0; a < kAzimuths; ++a) {
    const double az = 2 * M_PI * a / kAzimuths;
    for (int r = 0; r < kRings; ++r) {
      const double el = (-30.67 + r * (41.34 / 31.0)) * M_PI / 180.0;
      const float d = range(rng);
      rev.points.push_back({static_cast<float>(d * std::cos(el) * std::cos(az)),
                            static_cast<float>(d * std::cos(el) * std::sin(az)),
                            static_cast<float>(d * std::sin(el)), 0.5f, static_cast<int16_t>(r)});
    }
  }
  return rev;
}

// Receiver: decodes, converts and assembles every message until END arrives; records each
// message's latency ("M revolution slice latency_us") and each revolution it emits ("R revolution
// complete latency_us": from the newest of its slices' stamps to the moment it was assembled).
int RunReceiver(const std::string& url, const std::string& out_path) {
  lcm::LCM lcm(url);
  if (!lcm.good()) return 3;
  std::string log;
  log.reserve(4 << 20);
  cairn::runtime::RevolutionAssembler assembler;
  int64_t bad = 0;
  bool done = false;
  auto handler = [&](const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cairn::lcmt_point_cloud_slice m;
    if (m.decode(rbuf->data, 0, rbuf->data_size) < 0) {
      ++bad;
      return;
    }
    auto slice = cairn::runtime::FromLcm(m);
    if (!slice.ok()) {
      ++bad;
      return;
    }
    const int64_t converted = WallUtime();
    log += "M " + std::to_string(m.revolution) + " " + std::to_string(m.slice_index) + " " +
           std::to_string(converted - m.utime) + "\n";
    for (const auto& rev : assembler.OnSlice(std::move(*slice), converted)) {
      const int64_t now = WallUtime();
      int64_t newest = 0;
      for (const auto& s : rev.slices) newest = std::max(newest, s.utime);
      log += "R " + std::to_string(rev.revolution) + " " + (rev.complete() ? "1 " : "0 ") +
             std::to_string(now - newest) + "\n";
    }
  };
  lcm.subscribeFunction<decltype(handler)*>(
      "BENCH.CLOUD",
      [](const lcm::ReceiveBuffer* r, const std::string& c, decltype(handler)* h) { (*h)(r, c); },
      &handler);
  auto end_handler = [&](const lcm::ReceiveBuffer*, const std::string&) { done = true; };
  lcm.subscribeFunction<decltype(end_handler)*>(
      "BENCH.END",
      [](const lcm::ReceiveBuffer* r, const std::string& c, decltype(end_handler)* h) {
        (*h)(r, c);
      },
      &end_handler);
  std::ofstream ready(out_path + ".ready");
  ready << "ready\n";
  ready.close();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!done && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  // Drain what is still queued.
  while (lcm.handleTimeout(50) > 0) {
  }
  std::ofstream out(out_path);
  out << log << "B " << bad << "\n";
  return 0;
}

struct Result {
  double message_loss_percent{NAN};
  double revolutions_delivered_percent{NAN};
  int revolutions_failed{0};
  double revolution_p50_ms{NAN};
  double revolution_p99_ms{NAN};
  double message_p50_ms{NAN};
  double message_p99_ms{NAN};
};

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * v.size()))];
}

// Publishes `revolutions` revolutions at `rate_hz`, sliced or whole, to a forked receiver.
Result RunCase(const char* self, const std::string& url, bool sliced, double rate_hz,
               int revolutions, const cairn::common::LidarSlice& rev, const std::string& dir) {
  const std::string out = dir + "/recv_" + (sliced ? "sliced" : "whole") + "_" +
                          std::to_string(static_cast<int>(rate_hz)) + ".txt";
  std::remove(out.c_str());
  std::remove((out + ".ready").c_str());
  const pid_t pid = fork();
  if (pid == 0) {
    execl(self, self, "--receiver", url.c_str(), out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the receiver to subscribe.
  for (int i = 0; i < 500 && !std::ifstream(out + ".ready").good(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  lcm::LCM lcm(url);
  // The sensor's pieces as the core has them; each is converted when its points are ready.
  std::vector<cairn::common::LidarSlice> pieces =
      sliced ? cairn::runtime::SplitSlice(rev, kSliceBytes)
             : std::vector<cairn::common::LidarSlice>{rev};
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  const auto pace = period / static_cast<double>(pieces.size());
  auto next = std::chrono::steady_clock::now() +
              std::chrono::duration_cast<std::chrono::steady_clock::duration>(pace);
  int64_t sent = 0;
  for (int r = 0; r < revolutions; ++r) {
    for (auto& piece : pieces) {
      std::this_thread::sleep_until(next);
      piece.revolution = r;
      piece.utime = WallUtime();  // its points are ready now
      const cairn::lcmt_point_cloud_slice m = cairn::runtime::ToLcm(piece);
      lcm.publish("BENCH.CLOUD", &m);
      ++sent;
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(pace);
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  int8_t end = 1;
  for (int i = 0; i < 5; ++i) lcm.publish("BENCH.END", &end, 1);
  int status = 0;
  waitpid(pid, &status, 0);

  std::ifstream in(out);
  std::vector<double> message_ms, revolution_ms;
  std::vector<std::vector<bool>> got(revolutions, std::vector<bool>(pieces.size(), false));
  int64_t received = 0;
  int delivered = 0;
  std::string kind;
  while (in >> kind) {
    if (kind == "M") {
      int64_t r, slice, lat;
      in >> r >> slice >> lat;
      if (r < 0 || r >= revolutions || slice < 0 || slice >= static_cast<int64_t>(pieces.size()))
        continue;
      got[r][slice] = true;
      message_ms.push_back(lat / 1000.0);
      ++received;
    } else if (kind == "R") {
      int64_t r, complete, lat;
      in >> r >> complete >> lat;
      if (complete == 1 && r >= 0 && r < revolutions) {
        ++delivered;
        revolution_ms.push_back(lat / 1000.0);
      }
    } else {
      int64_t bad;
      in >> bad;
      if (bad > 0) std::printf("  %lld messages failed to decode\n", static_cast<long long>(bad));
    }
  }
  // Which slices were lost tells a stalled receiver (a run of them) from scattered drops.
  int listed = 0;
  for (int r = 0; r < revolutions && sliced; ++r) {
    for (size_t s = 0; s < got[r].size(); ++s) {
      if (!got[r][s] && listed++ < 20) std::printf("  lost: revolution %d slice %zu\n", r, s);
    }
  }
  Result result;
  result.message_loss_percent = 100.0 * (sent - received) / std::max<int64_t>(1, sent);
  result.revolutions_delivered_percent = 100.0 * delivered / std::max(1, revolutions);
  result.revolutions_failed = revolutions - delivered;
  result.revolution_p50_ms = Percentile(revolution_ms, 0.50);
  result.revolution_p99_ms = Percentile(revolution_ms, 0.99);
  result.message_p50_ms = Percentile(message_ms, 0.50);
  result.message_p99_ms = Percentile(message_ms, 0.99);
  return result;
}

// CPU time the hypervisor gave to others (the steal column of /proc/stat), seconds over all CPUs:
// a receiver not scheduled for longer than its buffer lasts (192 KB at 12 MB/s: 16 ms) drops.
double StolenSeconds() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  long long v[8] = {0};
  in >> cpu;
  for (auto& x : v) in >> x;
  const long ticks = sysconf(_SC_CLK_TCK);
  return cpu == "cpu" && ticks > 0 ? static_cast<double>(v[7]) / ticks : 0.0;
}

int ReadRmemDefault() {
  std::ifstream in("/proc/sys/net/core/rmem_default");
  int v = 0;
  in >> v;
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--receiver") return RunReceiver(argv[2], argv[3]);
  const cairn::bench::StealNote steal_note;
  double seconds = 5.0;
  if (argc == 3 && std::string(argv[1]) == "--seconds") seconds = std::atof(argv[2]);
  const int port = 20000 + (getpid() % 20000);
  const std::string url = "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
  const std::string dir = "/tmp/cairn_bench_transport_" + std::to_string(getpid());
  std::system(("mkdir -p " + dir).c_str());
  const auto rev = MakeRevolution();  // slice_index 0 of 1: the whole revolution
  const size_t whole_bytes = cairn::runtime::ToLcm(rev).getEncodedSize();
  std::printf(
      "transport: %zu points per revolution, %.2f MB whole, slices of <= %zu bytes, "
      "net.core.rmem_default %d bytes\n",
      rev.points.size(), whole_bytes / 1e6, kSliceBytes, ReadRmemDefault());
  bool all_pass = true;
  for (double hz : {10.0, 20.0}) {
    const int revolutions = static_cast<int>(seconds * hz);
    const double stolen_before = StolenSeconds();
    const Result sliced = RunCase(argv[0], url, true, hz, revolutions, rev, dir);
    std::printf(
        "transport: %.0f Hz sliced: %.2f s of CPU stolen by the hypervisor during the run; "
        "%d of %d revolutions not delivered whole\n",
        hz, StolenSeconds() - stolen_before, sliced.revolutions_failed, revolutions);
    const Result whole = RunCase(argv[0], url, false, hz, revolutions, rev, dir);
    std::printf("transport: %.0f Hz whole: %d of %d revolutions not delivered\n", hz,
                whole.revolutions_failed, revolutions);
    const std::string rate = std::to_string(static_cast<int>(hz));
    const std::string tag = "transport.sliced_" + rate + "hz";
    const std::string base = "whole 1.19 MB message at " + rate + " Hz";
    using cairn::bench::Figure;
    const std::vector<Figure> figures = {
        // Headline: a revolution in the receiver's hands.
        {tag + ".revolution_p99_latency", sliced.revolution_p99_ms, "ms",
         base + ", revolution p99", whole.revolution_p99_ms, false, "<= 2 ms",
         std::isfinite(sliced.revolution_p99_ms) && sliced.revolution_p99_ms <= 2.0},
        {tag + ".revolution_p50_latency", sliced.revolution_p50_ms, "ms",
         base + ", revolution p50", whole.revolution_p50_ms, false, "reported", true},
        {tag + ".revolutions_delivered", sliced.revolutions_delivered_percent, "%",
         base + ", revolutions delivered", whole.revolutions_delivered_percent, true, "100 %",
         sliced.revolutions_delivered_percent == 100.0},
        // Parts: single messages (a slice, or the whole message).
        {tag + ".part.message_loss", sliced.message_loss_percent, "%", base + ", message loss",
         whole.message_loss_percent, false, "0 %", sliced.message_loss_percent == 0.0},
        {tag + ".part.message_p99_latency", sliced.message_p99_ms, "ms",
         base + ", message p99", whole.message_p99_ms, false, "reported", true},
    };
    for (const auto& f : figures) {
      cairn::bench::Report(f);
      all_pass &= f.pass;
    }
  }
  std::system(("rm -rf " + dir).c_str());
  return all_pass ? 0 : 1;
}
