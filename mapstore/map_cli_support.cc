#include "mapstore/map_cli_support.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

#include <unistd.h>

namespace cairn::mapstore::cli {

void Table::Print() const {
  std::vector<size_t> width;
  for (const auto& row : rows_) {
    width.resize(std::max(width.size(), row.size()));
    for (size_t i = 0; i < row.size(); ++i) width[i] = std::max(width[i], row[i].size());
  }
  for (size_t r = 0; r < rows_.size(); ++r) {
    std::string line;
    for (size_t i = 0; i < rows_[r].size(); ++i) {
      std::string cell = rows_[r][i];
      if (i + 1 < rows_[r].size()) cell.resize(width[i], ' ');
      line += (i == 0 ? "" : "  ") + cell;
    }
    std::printf("%s\n", line.c_str());
    if (r == 0) {
      size_t total = 0;
      for (size_t w : width) total += w + 2;
      std::printf("%s\n", std::string(total > 2 ? total - 2 : 0, '-').c_str());
    }
  }
}

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

std::string Time(int64_t utime) {
  if (utime <= 0) return "-";
  const std::time_t t = static_cast<std::time_t>(utime / 1000000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M:%SZ", &tm);
  return buf;
}

std::string Join(const std::vector<std::string>& items, const char* sep) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : sep) + i;
  return out;
}

int Fail(const common::Status& s) {
  std::fprintf(stderr, "cairn-map: %s\n", s.ToString().c_str());
  return 1;
}

ProgressFn TerminalProgress() {
  if (!isatty(STDOUT_FILENO)) return nullptr;
  return [](double fraction, const std::string& stage) {
    const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 30);
    std::printf("\r[%s%s] %3d%% %-24s", std::string(filled, '#').c_str(),
                std::string(30 - filled, ' ').c_str(), static_cast<int>(fraction * 100),
                stage.c_str());
    if (fraction >= 1.0) std::printf("\n");
    std::fflush(stdout);
  };
}

void Common::AddMap(common::FlagParser* f, bool with_version) {
  f->AddString("site", &site, "site");
  f->AddString("map", &map, "map name");
  if (with_version) f->AddInt("version", &version, "map version (0 = latest)");
}

common::Result<std::unique_ptr<SqliteMapStore>> OpenStore(const std::string& path, bool write) {
  SqliteOptions options;
  options.read_only = !write;
  options.create_if_missing = write;
  return SqliteMapStore::Open(path, options);
}

int NeedMap(const Common& c) { return Need(c.map, "map"); }

int Need(const std::string& value, const char* flag) {
  if (!value.empty()) return -1;
  std::fprintf(stderr, "cairn-map: --%s is required (see --help)\n", flag);
  return 2;
}

}  // namespace cairn::mapstore::cli
