#include "mapstore/map_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <png.h>
#include <unistd.h>

#include "common/layers.h"
#include "common/yaml_reader.h"
#include "mapstore/names.h"

namespace cairn::mapstore::io {

namespace fs = std::filesystem;
using common::InvalidArgumentError;
using common::Result;
using common::Status;

namespace {

// The shortest decimal text that reads back as exactly `v`.
std::string Fmt(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

bool IsOccupancyLayer(const std::string& name) {
  return layers::IsCostLayer(name) || name == layers::kStaticMap || name == layers::kShortTerm ||
         name == layers::kLongTerm || name == layers::kFinal || name == "occupancy";
}

// ---- A 5x7 bitmap font for legends (rows top to bottom, bit 4 = leftmost column). ----
struct Glyph {
  char c;
  std::array<uint8_t, 7> rows;
};

constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {' ', {0, 0, 0, 0, 0, 0, 0}},
};

struct Rgb {
  uint8_t r, g, b;
};

// An RGB canvas with text drawing.
class Canvas {
 public:
  Canvas(int width, int height) : w_(width), h_(height), pixels_(width * height * 3, 255) {}
  int width() const { return w_; }
  int height() const { return h_; }
  void Set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    uint8_t* p = &pixels_[(static_cast<size_t>(y) * w_ + x) * 3];
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }
  void Fill(int x0, int y0, int w, int h, Rgb c) {
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) Set(x, y, c);
    }
  }
  void Frame(int x0, int y0, int w, int h, Rgb c) {
    for (int x = x0; x < x0 + w; ++x) {
      Set(x, y0, c);
      Set(x, y0 + h - 1, c);
    }
    for (int y = y0; y < y0 + h; ++y) {
      Set(x0, y, c);
      Set(x0 + w - 1, y, c);
    }
  }
  /// Draws text (upper-cased; unknown characters as '?'-less blanks); returns the end x.
  int Text(int x, int y, const std::string& text, Rgb c) {
    for (char ch : text) {
      const char up = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      for (const Glyph& g : kFont) {
        if (g.c != up) continue;
        for (int row = 0; row < 7; ++row) {
          for (int col = 0; col < 5; ++col) {
            if (g.rows[row] & (0x10 >> col)) Set(x + col, y + row, c);
          }
        }
        break;
      }
      x += 6;
    }
    return x;
  }
  /// A line of the given thickness (Bresenham, square pen).
  void Line(int x0, int y0, int x1, int y1, Rgb c, int thickness = 1) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    const int half = thickness / 2;
    for (int guard = 0; guard < 100000; ++guard) {
      Fill(x0 - half, y0 - half, thickness, thickness, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x0 += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y0 += sy;
      }
    }
  }
  const std::vector<uint8_t>& pixels() const { return pixels_; }

 private:
  int w_, h_;
  std::vector<uint8_t> pixels_;
};

constexpr Rgb kUnknownColour{196, 212, 232};
constexpr Rgb kBlack{0, 0, 0};

Rgb OccupancyColour(float percent) {
  if (std::isnan(percent)) return kUnknownColour;
  if (percent <= 0.f) return {255, 255, 255};
  if (percent >= 100.f) return kBlack;
  // Graded cost: from light amber to dark red.
  const float t = percent / 100.f;
  return {static_cast<uint8_t>(250 - 110 * t), static_cast<uint8_t>(210 - 190 * t),
          static_cast<uint8_t>(120 - 100 * t)};
}

// A perceptual blue-green-yellow ramp (viridis-like) for continuous layers.
Rgb RampColour(float t) {
  static constexpr Rgb kStops[] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  t = std::clamp(t, 0.f, 1.f) * 4.f;
  const int i = std::min(3, static_cast<int>(t));
  const float f = t - i;
  auto mix = [&](uint8_t a, uint8_t b) { return static_cast<uint8_t>(a + (b - a) * f); };
  return {mix(kStops[i].r, kStops[i + 1].r), mix(kStops[i].g, kStops[i + 1].g),
          mix(kStops[i].b, kStops[i + 1].b)};
}

Result<std::string> EncodePng(const Canvas& canvas) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (png == nullptr) return common::InternalError("libpng: cannot create a writer");
  png_infop info = png_create_info_struct(png);
  std::string out;
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return common::InternalError("libpng failed while encoding");
  }
  png_set_write_fn(
      png, &out,
      [](png_structp p, png_bytep data, png_size_t n) {
        static_cast<std::string*>(png_get_io_ptr(p))->append(reinterpret_cast<char*>(data), n);
      },
      nullptr);
  png_set_IHDR(png, info, canvas.width(), canvas.height(), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < canvas.height(); ++y) {
    png_write_row(
        png, const_cast<png_bytep>(&canvas.pixels()[static_cast<size_t>(y) * canvas.width() * 3]));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

// CSV helpers: quote every text field; backslash-escape ';' '|' '\' inside list fields.
std::string CsvQuote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string EscapeItem(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == ';' || c == '|' || c == '\\') out += '\\';
    if (c == '\n') {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out;
}

// Splits on an unescaped separator, keeping the escapes in the parts.
std::vector<std::string> SplitRaw(const std::string& s, char sep) {
  std::vector<std::string> parts(1);
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      parts.back() += s[i];
      parts.back() += s[++i];
    } else if (s[i] == sep) {
      parts.emplace_back();
    } else {
      parts.back() += s[i];
    }
  }
  if (parts.size() == 1 && parts[0].empty()) parts.clear();
  return parts;
}

std::string Unescape(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) ++i;
    out += s[i];
  }
  return out;
}

// Splits one CSV line (RFC 4180 quoting); false on an unterminated quote.
bool ParseCsvLine(const std::string& line, std::vector<std::string>* fields) {
  fields->assign(1, "");
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields->back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields->back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields->emplace_back();
    } else if (c != '\r') {
      fields->back() += c;
    }
  }
  return !quoted;
}

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end != nullptr && *end == '\0';
}

constexpr char kCsvHeader[] =
    "id,kind,centroid_x_m,centroid_y_m,slope_rad,height_m,width_m,length_m,depth_m,area_m2,"
    "num_cells,outline_m,verdicts";

Result<common::ObstacleKind> KindFromName(const std::string& name) {
  for (int k = 1; k <= 5; ++k) {
    const auto kind = static_cast<common::ObstacleKind>(k);
    if (name == common::ObstacleKindName(kind)) return kind;
  }
  return InvalidArgumentError("unknown obstacle kind '" + name + "'");
}

// Skips whitespace and '#' comments in a PGM header.
void SkipPgmSpace(const std::string& data, size_t* pos) {
  while (*pos < data.size()) {
    if (std::isspace(static_cast<unsigned char>(data[*pos]))) {
      ++*pos;
    } else if (data[*pos] == '#') {
      while (*pos < data.size() && data[*pos] != '\n') ++*pos;
    } else {
      break;
    }
  }
}

bool ReadPgmInt(const std::string& data, size_t* pos, int* value) {
  SkipPgmSpace(data, pos);
  const size_t start = *pos;
  long v = 0;
  while (*pos < data.size() && std::isdigit(static_cast<unsigned char>(data[*pos]))) {
    v = v * 10 + (data[*pos] - '0');
    if (v > 1000000) return false;
    ++*pos;
  }
  *value = static_cast<int>(v);
  return *pos > start;
}

}  // namespace

const char* PgmModeName(PgmMode mode) {
  switch (mode) {
    case PgmMode::kTrinary:
      return "trinary";
    case PgmMode::kScale:
      return "scale";
    case PgmMode::kRaw:
      return "raw";
  }
  return "?";
}

Result<PgmMode> PgmModeFromName(const std::string& name) {
  if (name == "trinary") return PgmMode::kTrinary;
  if (name == "scale") return PgmMode::kScale;
  if (name == "raw") return PgmMode::kRaw;
  return InvalidArgumentError("unknown PGM mode '" + name + "' (trinary, scale, raw)");
}

Result<common::Layer> OccupancyPercent(const common::GridMap& map, const std::string& layer) {
  if (!map.HasLayer(layer)) return common::NotFoundError("no layer '" + layer + "'");
  const common::Layer& in = map.at(layer);
  common::Layer out(in.rows(), in.cols());
  if (layer == layers::kOccupancyLogOdds) {
    for (Eigen::Index i = 0; i < in.size(); ++i) {
      const float l = in.data()[i];
      out.data()[i] = std::isnan(l) ? common::kUnknown : 100.f / (1.f + std::exp(-l));
    }
    return out;
  }
  if (!IsOccupancyLayer(layer)) {
    return InvalidArgumentError("layer '" + layer +
                                "' is not an occupancy or cost layer (export it as png)");
  }
  for (Eigen::Index i = 0; i < in.size(); ++i) {
    const float v = in.data()[i];
    out.data()[i] = std::isnan(v) ? common::kUnknown : std::clamp(v, 0.f, 100.f);
  }
  return out;
}

Result<std::string> SafeOutputPath(const std::string& folder, const std::string& file_name) {
  if (file_name.empty() || file_name == "." || file_name == ".." ||
      file_name.find('/') != std::string::npos || file_name.find('\0') != std::string::npos) {
    return InvalidArgumentError("'" + file_name + "' is not a plain file name");
  }
  if (folder.empty()) return InvalidArgumentError("no output folder given");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (!fs::is_directory(folder, ec)) {
    return InvalidArgumentError("'" + folder + "' is not a folder");
  }
  const fs::path root = fs::canonical(folder, ec);
  if (ec) return InvalidArgumentError("cannot resolve '" + folder + "': " + ec.message());
  const fs::path target = root / file_name;
  if (target.parent_path() != root) {
    return InvalidArgumentError("'" + file_name + "' would leave the folder '" + folder + "'");
  }
  const auto status = fs::symlink_status(target, ec);
  if (fs::is_symlink(status)) {
    return InvalidArgumentError("refusing to write through the symlink '" + target.string() + "'");
  }
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    return InvalidArgumentError("'" + target.string() + "' exists and is not a file");
  }
  return target.string();
}

Status WriteFileAtomically(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return common::UnavailableError("cannot write '" + tmp + "'");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      return common::ResourceExhaustedError("writing '" + path + "' failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return common::UnavailableError("cannot rename into '" + path + "': " + ec.message());
  }
  return Status::Ok();
}

Result<std::string> ReadFile(const std::string& path, size_t max_bytes) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return common::NotFoundError("no file '" + path + "'");
  const auto size = fs::file_size(path, ec);
  if (ec || size > max_bytes) return InvalidArgumentError("'" + path + "' is too large");
  std::ifstream in(path, std::ios::binary);
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (!in) return common::UnavailableError("cannot read '" + path + "'");
  return data;
}

Result<std::vector<std::string>> WriteRosMap(const std::string& folder, const std::string& stem,
                                             const common::GridGeometry& geometry,
                                             const common::Layer& occupancy,
                                             const RosMapOptions& options) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  if (occupancy.rows() != geometry.size_x || occupancy.cols() != geometry.size_y) {
    return InvalidArgumentError("the layer does not match the geometry");
  }
  if (!(options.free_thresh >= 0 && options.free_thresh < options.occupied_thresh &&
        options.occupied_thresh <= 1)) {
    return InvalidArgumentError("need 0 <= free_thresh < occupied_thresh <= 1");
  }
  auto yaml_path = SafeOutputPath(folder, stem + ".yaml");
  if (!yaml_path.ok()) return yaml_path.status();
  auto pgm_path = SafeOutputPath(folder, stem + ".pgm");
  if (!pgm_path.ok()) return pgm_path.status();

  // PGM rows run from the top of the map (largest y) down, as map_server reads them.
  const int w = geometry.size_x, h = geometry.size_y;
  std::string pgm = "P5\n# cairn map store export (" + std::string(PgmModeName(options.mode)) +
                    ")\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  const size_t header = pgm.size();
  pgm.resize(header + static_cast<size_t>(w) * h);
  for (int row = 0; row < h; ++row) {
    const int iy = h - 1 - row;
    for (int ix = 0; ix < w; ++ix) {
      const float v = occupancy(ix, iy);
      uint8_t pixel = 205;
      switch (options.mode) {
        case PgmMode::kTrinary:
          if (!std::isnan(v)) {
            if (v >= options.occupied_thresh * 100.0) {
              pixel = 0;
            } else if (v <= options.free_thresh * 100.0) {
              pixel = 254;
            }
          }
          break;
        case PgmMode::kScale:
          if (!std::isnan(v)) {
            pixel = static_cast<uint8_t>(
                std::lround(255.0 * (1.0 - std::clamp(v, 0.f, 100.f) / 100.0)));
          }
          break;
        case PgmMode::kRaw:
          pixel =
              std::isnan(v) ? 255 : static_cast<uint8_t>(std::lround(std::clamp(v, 0.f, 100.f)));
          break;
      }
      pgm[header + static_cast<size_t>(row) * w + ix] = static_cast<char>(pixel);
    }
  }
  std::ostringstream yaml;
  yaml << "image: " << stem << ".pgm\n"
       << "mode: " << PgmModeName(options.mode) << "\n"
       << "resolution: " << Fmt(geometry.resolution_m) << "\n"
       << "origin: [" << Fmt(geometry.origin.x_m) << ", " << Fmt(geometry.origin.y_m) << ", "
       << Fmt(geometry.origin.yaw_rad) << "]\n"
       << "negate: 0\n"
       << "occupied_thresh: " << Fmt(options.occupied_thresh) << "\n"
       << "free_thresh: " << Fmt(options.free_thresh) << "\n";
  if (!(s = WriteFileAtomically(*pgm_path, pgm)).ok()) return s;
  if (!(s = WriteFileAtomically(*yaml_path, yaml.str())).ok()) return s;
  return std::vector<std::string>{*yaml_path, *pgm_path};
}

Result<RosMap> ReadRosMap(const std::string& yaml_path) {
  RosMap map;
  std::string image;
  int negate = 0;
  std::vector<double> origin;
  std::string mode = "trinary";
  try {
    common::YamlMap yaml = common::YamlMap::LoadFile(yaml_path);
    image = yaml.Require<std::string>("image");
    map.geometry.resolution_m = yaml.Require<double>("resolution");
    origin = yaml.Require<std::vector<double>>("origin");
    yaml.Get("mode", &mode);
    yaml.Get("negate", &negate);
    yaml.Get("occupied_thresh", &map.options.occupied_thresh);
    yaml.Get("free_thresh", &map.options.free_thresh);
    yaml.Finish();
  } catch (const std::exception& e) {
    return InvalidArgumentError(e.what());
  }
  auto parsed_mode = PgmModeFromName(mode);
  if (!parsed_mode.ok())
    return InvalidArgumentError(yaml_path + ": " + parsed_mode.status().message());
  map.options.mode = *parsed_mode;
  if (origin.size() != 3 || !std::isfinite(origin[0]) || !std::isfinite(origin[1]) ||
      !std::isfinite(origin[2])) {
    return InvalidArgumentError(yaml_path + ": origin must be [x, y, yaw] with finite values");
  }
  if (!(map.geometry.resolution_m > 0) || !std::isfinite(map.geometry.resolution_m)) {
    return InvalidArgumentError(yaml_path + ": resolution must be positive");
  }
  map.geometry.origin = {origin[0], origin[1], origin[2]};

  // The image must sit in the YAML's folder (or below it).
  std::error_code ec;
  const fs::path base = fs::canonical(
      fs::path(yaml_path).parent_path().empty() ? fs::path(".") : fs::path(yaml_path).parent_path(),
      ec);
  const fs::path image_path = fs::weakly_canonical(base / image, ec);
  const std::string rel = fs::relative(image_path, base, ec).string();
  if (ec || rel.empty() || rel.rfind("..", 0) == 0 || fs::path(image).is_absolute()) {
    return InvalidArgumentError(yaml_path + ": image '" + image +
                                "' must be a file in the YAML's folder");
  }
  map.image_path = image_path.string();
  auto data = ReadFile(map.image_path, 256u << 20);
  if (!data.ok()) return data.status();
  size_t pos = 0;
  if (data->size() < 2 || (*data)[0] != 'P' || ((*data)[1] != '5' && (*data)[1] != '2')) {
    return InvalidArgumentError(map.image_path + " is not a PGM image (P5 or P2)");
  }
  const bool ascii = (*data)[1] == '2';
  pos = 2;
  int w = 0, h = 0, maxval = 0;
  if (!ReadPgmInt(*data, &pos, &w) || !ReadPgmInt(*data, &pos, &h) ||
      !ReadPgmInt(*data, &pos, &maxval) || w <= 0 || h <= 0 || maxval <= 0 || maxval > 255) {
    return InvalidArgumentError(map.image_path + ": bad PGM header (8-bit grey images only)");
  }
  ++pos;  // the single whitespace after maxval
  map.geometry.size_x = w;
  map.geometry.size_y = h;
  map.occupancy = common::Layer::Constant(w, h, common::kUnknown);
  const double occ = map.options.occupied_thresh, free = map.options.free_thresh;
  for (int row = 0; row < h; ++row) {
    for (int ix = 0; ix < w; ++ix) {
      int pixel = 0;
      if (ascii) {
        if (!ReadPgmInt(*data, &pos, &pixel)) {
          return InvalidArgumentError(map.image_path + ": truncated PGM data");
        }
      } else {
        if (pos >= data->size())
          return InvalidArgumentError(map.image_path + ": truncated PGM data");
        pixel = static_cast<uint8_t>((*data)[pos++]);
      }
      pixel = pixel * 255 / maxval;
      float value = common::kUnknown;
      const double p = negate ? pixel / 255.0 : (255 - pixel) / 255.0;
      switch (map.options.mode) {
        case PgmMode::kTrinary:
          if (p > occ) {
            value = 100.f;
          } else if (p < free) {
            value = 0.f;
          }
          break;
        case PgmMode::kScale:
          if (p > occ) {
            value = 100.f;
          } else if (p < free) {
            value = 0.f;
          } else {
            value = static_cast<float>(static_cast<int>(99.0 * (p - free) / (occ - free)));
          }
          break;
        case PgmMode::kRaw:
          value = pixel <= 100 ? static_cast<float>(pixel) : common::kUnknown;
          break;
      }
      map.occupancy(ix, h - 1 - row) = value;
    }
  }
  return map;
}

Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                             const common::GridMap& map, const std::string& layer) {
  PngOverlay none;
  none.min_pixels = 320;
  return WritePng(folder, stem, map, layer, none);
}

Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                             const common::GridMap& map, const std::string& layer,
                             const PngOverlay& overlay) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  if (!map.HasLayer(layer)) return common::NotFoundError("no layer '" + layer + "'");
  auto path = SafeOutputPath(folder, stem + ".png");
  if (!path.ok()) return path.status();
  const bool occupancy = IsOccupancyLayer(layer) || layer == layers::kOccupancyLogOdds;
  common::Layer values = map.at(layer);
  if (occupancy) {
    auto percent = OccupancyPercent(map, layer);
    if (!percent.ok()) return percent.status();
    values = *percent;
  }
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const float v = values.data()[i];
    if (std::isnan(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  const int w = map.size_x(), h = map.size_y();
  const int scale = std::clamp(overlay.min_pixels / std::max(1, std::max(w, h)), 1, 8);
  const bool has_overlay = !overlay.path_m.empty() || !overlay.obstacles.empty();
  const int legend_h = has_overlay || !overlay.caption.empty() ? 92 : 52;
  const int canvas_w = std::max(w * scale, has_overlay ? 560 : 300);
  Canvas canvas(canvas_w, h * scale + legend_h);
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const float v = values(ix, iy);
      Rgb c;
      if (occupancy) {
        c = OccupancyColour(v);
      } else if (std::isnan(v)) {
        c = kUnknownColour;
      } else {
        c = RampColour(hi > lo ? (v - lo) / (hi - lo) : 0.5f);
      }
      canvas.Fill(ix * scale, (h - 1 - iy) * scale, scale, scale, c);
    }
  }
  // Overlay: obstacles (outline and label) and the path, in world coordinates.
  auto to_pixel = [&](const common::Vector2& p) {
    const common::Vector2 c = map.geometry().ContinuousIndexOf(p);
    return std::make_pair(static_cast<int>(std::lround(c.x() * scale)),
                          static_cast<int>(std::lround((h - c.y()) * scale)));
  };
  constexpr Rgb kPath{20, 90, 230}, kCrossable{0, 150, 60}, kBlocked{215, 25, 30}, kNoVerdict{90, 90, 90};
  for (const auto& o : overlay.obstacles) {
    Rgb colour = kNoVerdict;
    if (const auto* v = o.VerdictFor(overlay.verdict_profile)) colour = v->crossable ? kCrossable : kBlocked;
    for (size_t i = 0; i < o.outline_m.size(); ++i) {
      const auto a = to_pixel(o.outline_m[i]);
      const auto b = to_pixel(o.outline_m[(i + 1) % o.outline_m.size()]);
      canvas.Line(a.first, a.second, b.first, b.second, colour, 2);
    }
    std::string kind = common::ObstacleKindName(o.kind);
    for (auto& ch : kind) ch = ch == '_' ? ' ' : ch;
    const auto c = to_pixel(o.centroid_m);
    const std::string label = std::to_string(o.id) + " " + kind;
    canvas.Fill(c.first - 1, c.second - 1, static_cast<int>(label.size()) * 6 + 2, 9, {255, 255, 255});
    canvas.Text(c.first, c.second, label, colour);
  }
  for (size_t i = 1; i < overlay.path_m.size(); ++i) {
    const auto a = to_pixel(overlay.path_m[i - 1]);
    const auto b = to_pixel(overlay.path_m[i]);
    canvas.Line(a.first, a.second, b.first, b.second, kPath, 3);
  }
  if (!overlay.path_m.empty()) {
    const auto s = to_pixel(overlay.path_m.front());
    const auto e = to_pixel(overlay.path_m.back());
    canvas.Fill(s.first - 4, s.second - 4, 9, 9, kPath);
    canvas.Frame(e.first - 6, e.second - 6, 13, 13, kPath);
    canvas.Frame(e.first - 5, e.second - 5, 11, 11, kPath);
  }
  // Legend: the layer and resolution, then swatches or a colour bar.
  const int y0 = h * scale + 6;
  char title[160];
  std::snprintf(title, sizeof(title), "%s  %.3g M/CELL  %dX%d", layer.c_str(), map.resolution_m(),
                w, h);
  canvas.Text(4, y0, title, kBlack);
  const int y1 = y0 + 14;
  int x = 4;
  int row_y = y1;
  auto swatch = [&](Rgb c, const std::string& label) {
    canvas.Fill(x, row_y, 12, 12, c);
    canvas.Frame(x, row_y, 12, 12, kBlack);
    x = canvas.Text(x + 16, row_y + 3, label, kBlack) + 10;
  };
  if (occupancy) {
    swatch(OccupancyColour(0.f), "FREE");
    swatch(OccupancyColour(50.f), "1-99");
    swatch(OccupancyColour(100.f), "LETHAL");
    swatch(kUnknownColour, "UNKNOWN");
  } else {
    char lo_text[32], hi_text[32];
    std::snprintf(lo_text, sizeof(lo_text), "%.3g", std::isfinite(lo) ? lo : 0.f);
    std::snprintf(hi_text, sizeof(hi_text), "%.3g", std::isfinite(hi) ? hi : 0.f);
    x = canvas.Text(x, y1 + 3, lo_text, kBlack) + 4;
    for (int i = 0; i < 100; ++i) canvas.Fill(x + i, y1, 1, 12, RampColour(i / 99.f));
    canvas.Frame(x, y1, 100, 12, kBlack);
    x = canvas.Text(x + 104, y1 + 3, hi_text, kBlack) + 10;
    swatch(kUnknownColour, "UNKNOWN");
  }
  // Second legend row (overlay), caption, signature.
  int y2 = y1 + 20;
  if (has_overlay) {
    x = 4;
    row_y = y2;
    if (!overlay.path_m.empty()) swatch(kPath, "DRIVEN PATH");
    if (!overlay.obstacles.empty()) {
      swatch(kCrossable, "CROSSABLE" + (overlay.verdict_profile.empty()
                                            ? std::string()
                                            : " BY " + overlay.verdict_profile));
      swatch(kBlocked, "NOT CROSSABLE");
    }
    y2 += 18;
  }
  if (!overlay.caption.empty()) {
    canvas.Text(4, y2, overlay.caption, kBlack);
    y2 += 12;
  }
  canvas.Text(4, y2, "CAIRN MAP STORE", {90, 90, 90});
  auto png = EncodePng(canvas);
  if (!png.ok()) return png.status();
  if (!(s = WriteFileAtomically(*path, *png)).ok()) return s;
  return *path;
}

Result<std::string> WriteObstaclesCsv(const std::string& folder, const std::string& stem,
                                      const common::ObstacleRegistry& registry) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  auto path = SafeOutputPath(folder, stem + ".csv");
  if (!path.ok()) return path.status();
  std::ostringstream out;
  out << kCsvHeader << "\n";
  for (const common::Obstacle& o : registry.obstacles) {
    std::string outline, verdicts;
    for (const auto& v : o.outline_m) {
      outline += (outline.empty() ? "" : ";") + Fmt(v.x()) + " " + Fmt(v.y());
    }
    for (const auto& v : o.verdicts) {
      verdicts += (verdicts.empty() ? "" : ";") + EscapeItem(v.profile) + "|" +
                  EscapeItem(v.profile_hash) + "|" + (v.crossable ? "crossable" : "blocked") + "|" +
                  EscapeItem(v.reason);
    }
    out << o.id << "," << common::ObstacleKindName(o.kind) << "," << Fmt(o.centroid_m.x()) << ","
        << Fmt(o.centroid_m.y()) << "," << Fmt(o.slope_rad) << "," << Fmt(o.height_m) << ","
        << Fmt(o.width_m) << "," << Fmt(o.length_m) << "," << Fmt(o.depth_m) << ","
        << Fmt(o.area_m2) << "," << o.num_cells << "," << CsvQuote(outline) << ","
        << CsvQuote(verdicts) << "\n";
  }
  if (!(s = WriteFileAtomically(*path, out.str())).ok()) return s;
  return *path;
}

Result<common::ObstacleRegistry> ReadObstaclesCsv(const std::string& path) {
  auto data = ReadFile(path, 64u << 20);
  if (!data.ok()) return data.status();
  std::istringstream in(*data);
  std::string line;
  if (!std::getline(in, line) || (line != kCsvHeader && line != std::string(kCsvHeader) + "\r")) {
    return InvalidArgumentError(path + ": not an obstacle CSV (the first line must be '" +
                                kCsvHeader + "')");
  }
  common::ObstacleRegistry registry;
  int line_no = 1;
  std::vector<std::string> f;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (!ParseCsvLine(line, &f) || f.size() != 13) {
      return InvalidArgumentError(where + "expected 13 fields");
    }
    common::Obstacle o;
    double id = 0, num_cells = 0, cx = 0, cy = 0;
    auto kind = KindFromName(f[1]);
    if (!kind.ok()) return InvalidArgumentError(where + kind.status().message());
    o.kind = *kind;
    if (!ParseDouble(f[0], &id) || !ParseDouble(f[2], &cx) || !ParseDouble(f[3], &cy) ||
        !ParseDouble(f[4], &o.slope_rad) || !ParseDouble(f[5], &o.height_m) ||
        !ParseDouble(f[6], &o.width_m) || !ParseDouble(f[7], &o.length_m) ||
        !ParseDouble(f[8], &o.depth_m) || !ParseDouble(f[9], &o.area_m2) ||
        !ParseDouble(f[10], &num_cells) || id != std::floor(id) || std::abs(id) > 2e9) {
      return InvalidArgumentError(where + "a number does not parse");
    }
    o.id = static_cast<int32_t>(id);
    o.num_cells = static_cast<int32_t>(num_cells);
    o.centroid_m = {cx, cy};
    for (const std::string& vertex : SplitRaw(f[11], ';')) {
      std::istringstream vs(vertex);
      std::string xs, ys;
      double vx = 0, vy = 0;
      if (!(vs >> xs >> ys) || !ParseDouble(xs, &vx) || !ParseDouble(ys, &vy)) {
        return InvalidArgumentError(where + "bad outline vertex '" + vertex + "'");
      }
      o.outline_m.push_back({vx, vy});
    }
    for (const std::string& item : SplitRaw(f[12], ';')) {
      const std::vector<std::string> parts = SplitRaw(item, '|');
      if (parts.size() != 4 || (parts[2] != "crossable" && parts[2] != "blocked")) {
        return InvalidArgumentError(where + "bad verdict '" + item + "'");
      }
      common::ObstacleVerdict v;
      v.profile = Unescape(parts[0]);
      v.profile_hash = Unescape(parts[1]);
      v.crossable = parts[2] == "crossable";
      v.reason = Unescape(parts[3]);
      o.verdicts.push_back(std::move(v));
    }
    registry.obstacles.push_back(std::move(o));
  }
  return registry;
}

Result<std::string> WriteOctomap(const std::string& folder, const std::string& stem,
                                 const OctomapData& octomap, bool binary) {
  Status s = ValidateName("file stem", stem);
  if (!s.ok()) return s;
  auto path = SafeOutputPath(folder, stem + (binary ? ".bt" : ".ot"));
  if (!path.ok()) return path.status();
  std::string bytes;
  if (octomap.binary == binary) {
    bytes = octomap.bytes;
  } else {
    // Convert through an OcTree.
    std::istringstream in(octomap.bytes);
    std::unique_ptr<octomap::OcTree> tree;
    if (octomap.binary) {
      tree = std::make_unique<octomap::OcTree>(octomap.resolution_m);
      if (!tree->readBinary(in)) return common::CorruptError("the stored OctoMap does not parse");
    } else {
      std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(in));
      auto* as_tree = dynamic_cast<octomap::OcTree*>(any.get());
      if (as_tree == nullptr) {
        return common::CorruptError("the stored OctoMap is not an OcTree");
      }
      any.release();
      tree.reset(as_tree);
    }
    std::ostringstream out;
    const bool ok = binary ? tree->writeBinary(out) : tree->write(out);
    if (!ok) return common::InternalError("OctoMap could not write the tree");
    bytes = out.str();
  }
  if (!(s = WriteFileAtomically(*path, bytes)).ok()) return s;
  return *path;
}

Result<OctomapData> ReadOctomap(const std::string& path) {
  auto data = ReadFile(path);
  if (!data.ok()) return data.status();
  OctomapData out;
  const bool binary = data->rfind("# Octomap OcTree binary file", 0) == 0;
  const bool full = data->rfind("# Octomap OcTree file", 0) == 0;
  if (!binary && !full) {
    return InvalidArgumentError(path + " is not an OctoMap .bt or .ot file");
  }
  std::istringstream in(*data);
  if (binary) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(in)) return InvalidArgumentError(path + ": OctoMap cannot read it");
    out.resolution_m = tree.getResolution();
  } else {
    std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
    if (!tree) return InvalidArgumentError(path + ": OctoMap cannot read it");
    out.resolution_m = tree->getResolution();
  }
  out.binary = binary;
  out.bytes = std::move(data).value();
  return out;
}

}  // namespace cairn::mapstore::io
