#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <time.h>
#include <unistd.h>

/// @file
/// One benchmark figure: printed as a readable line and as a machine line
///   FIGURE {"name": ..., "value": ..., "unit": ..., "baseline": ..., "baseline_value": ...,
///           "ratio": ..., "target": ..., "pass": ...}
/// which scripts/bench gathers into build/bench/results.json. `ratio` is always "times better
/// than the baseline": baseline/value when lower is better, value/baseline when higher is.

namespace cairn::bench {

struct Figure {
  std::string name;  ///< "transport.sliced_10hz.p99_latency"
  double value{0.0};
  std::string unit;            ///< "ms", "points/s", "%", "x"
  std::string baseline;        ///< what it is compared with, measured in the same run if possible
  double baseline_value{NAN};  ///< NaN when the baseline is a published figure with no value
  bool higher_is_better{false};
  std::string target;  ///< "<= 1 ms"
  bool pass{true};
};

inline std::string JsonEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

inline std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

inline double Ratio(const Figure& f) {
  if (!std::isfinite(f.baseline_value) || f.baseline_value == 0.0 || f.value == 0.0) return NAN;
  return f.higher_is_better ? f.value / f.baseline_value : f.baseline_value / f.value;
}

inline void Report(const Figure& f) {
  const double ratio = Ratio(f);
  std::printf("%-48s %12s %-9s | baseline %s = %s | ratio %s | target %s | %s\n", f.name.c_str(),
              JsonNumber(f.value).c_str(), f.unit.c_str(), f.baseline.c_str(),
              JsonNumber(f.baseline_value).c_str(), JsonNumber(ratio).c_str(), f.target.c_str(),
              f.pass ? "PASS" : "FAIL");
  std::printf(
      "FIGURE {\"name\": \"%s\", \"value\": %s, \"unit\": \"%s\", \"baseline\": \"%s\", "
      "\"baseline_value\": %s, \"ratio\": %s, \"target\": \"%s\", \"pass\": %s, "
      "\"higher_is_better\": %s}\n",
      JsonEscape(f.name).c_str(), JsonNumber(f.value).c_str(), JsonEscape(f.unit).c_str(),
      JsonEscape(f.baseline).c_str(), JsonNumber(f.baseline_value).c_str(),
      JsonNumber(ratio).c_str(), JsonEscape(f.target).c_str(), f.pass ? "true" : "false",
      f.higher_is_better ? "true" : "false");
  std::fflush(stdout);
}

/// The median of `v` (the mean of the middle two for an even count); NaN when empty.
inline double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// CPU seconds of `clock` (CLOCK_THREAD_CPUTIME_ID, CLOCK_PROCESS_CPUTIME_ID) so far.
inline double CpuSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
inline double ThreadCpuSeconds() { return CpuSeconds(CLOCK_THREAD_CPUTIME_ID); }
inline double ProcessCpuSeconds() { return CpuSeconds(CLOCK_PROCESS_CPUTIME_ID); }

/// The 1-minute load average as text ("3.20"), so a reader can tell a busy machine from a slow
/// program; "0.00" where unknown.
inline std::string LoadAverage() {
  double load = 0.0;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = 0.0;
    std::fclose(f);
  }
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", load);
  return text;
}

/// CPU time the host took from this machine's processors so far (the `steal` column of
/// /proc/stat's `cpu` line), in milliseconds summed over processors; NaN where unknown. A
/// virtual machine whose host is busy loses it, and every timed figure suffers with it.
inline double HostStealMs() {
  std::ifstream stat("/proc/stat");
  std::string line;
  if (!std::getline(stat, line) || line.rfind("cpu ", 0) != 0) return NAN;
  std::istringstream fields(line.substr(4));
  long long value = 0;
  for (int i = 0; i < 8 && fields >> value; ++i) {
  }
  const long ticks_per_s = sysconf(_SC_CLK_TCK);
  if (!fields || ticks_per_s <= 0) return NAN;
  return 1000.0 * static_cast<double>(value) / static_cast<double>(ticks_per_s);
}

/// Prints, when it goes out of scope, how much CPU time the host stole while it lived: a
/// benchmark declares one first, so that its figures can be read against it.
class StealNote {
 public:
  StealNote() : start_ms_(HostStealMs()) {}
  ~StealNote() {
    const double stolen = HostStealMs() - start_ms_;
    if (std::isfinite(stolen)) {
      std::printf("(host CPU steal during this benchmark: %.0f ms summed over processors)\n",
                  stolen);
      std::fflush(stdout);
    }
  }
  StealNote(const StealNote&) = delete;
  StealNote& operator=(const StealNote&) = delete;

 private:
  double start_ms_;
};

}  // namespace cairn::bench
