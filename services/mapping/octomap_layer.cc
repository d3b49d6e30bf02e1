#include "services/mapping/octomap_layer.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

namespace {

constexpr unsigned kTreeDepth = 16;  // octomap::OcTree's fixed depth

// ---- Stream checks ---------------------------------------------------------------------------
// octomap reads node data recursively without bounding the depth or checking for the end of
// the stream, so a corrupt or truncated stream can make it recurse without end. Streams are
// therefore walked here first: header, node structure within the tree depth, node count equal
// to the header's size, nothing missing.

struct StreamHeader {
  std::string id;
  long long size{-1};
  double resolution_m{0.0};
  size_t data_offset{0};
};

common::Status ParseHeader(const std::string& bytes, bool binary, StreamHeader* header) {
  const std::string magic = binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
  if (bytes.compare(0, magic.size(), magic) != 0) {
    return common::CorruptError(std::string("not an OctoMap ") + (binary ? ".bt" : ".ot") +
                                " stream (bad first line)");
  }
  size_t pos = bytes.find('\n');
  while (pos != std::string::npos && pos + 1 <= bytes.size()) {
    const size_t start = pos + 1;
    const size_t eol = bytes.find('\n', start);
    if (eol == std::string::npos) break;
    std::istringstream line(bytes.substr(start, eol - start));
    std::string token;
    line >> token;
    pos = eol;
    if (token.empty() || token[0] == '#') continue;
    if (token == "data") {
      header->data_offset = eol + 1;
      if (header->id.empty() || header->size < 0 || !(header->resolution_m > 0.0) ||
          !std::isfinite(header->resolution_m)) {
        return common::CorruptError("OctoMap stream header lacks a valid id, size or res");
      }
      return common::Status::Ok();
    }
    if (token == "id") {
      line >> header->id;
    } else if (token == "size") {
      line >> header->size;
    } else if (token == "res") {
      line >> header->resolution_m;
    }
    if (line.fail()) return common::CorruptError("OctoMap stream header: bad '" + token + "'");
  }
  return common::CorruptError("OctoMap stream header has no 'data' line");
}

// Walks one binary node (two bytes, two bits per child: 10 free, 01 occupied, 11 inner).
bool WalkBinaryNode(const std::string& bytes, size_t* pos, unsigned depth, long long* nodes) {
  if (*pos + 2 > bytes.size()) return false;
  const uint8_t lo = static_cast<uint8_t>(bytes[*pos]), hi = static_cast<uint8_t>(bytes[*pos + 1]);
  *pos += 2;
  const uint16_t bits = static_cast<uint16_t>(lo | (hi << 8));
  for (unsigned i = 0; i < 8; ++i) {
    if (((bits >> (2 * i)) & 3u) != 0) ++*nodes;
  }
  for (unsigned i = 0; i < 8; ++i) {
    if (((bits >> (2 * i)) & 3u) != 3u) continue;
    if (depth + 1 >= kTreeDepth) return false;  // a leaf-level node cannot have children
    if (!WalkBinaryNode(bytes, pos, depth + 1, nodes)) return false;
  }
  return true;
}

// Walks one full node (a float log-odds, then a byte with one bit per existing child).
bool WalkFullNode(const std::string& bytes, size_t* pos, unsigned depth, long long* nodes) {
  if (*pos + sizeof(float) + 1 > bytes.size()) return false;
  float value;
  std::memcpy(&value, bytes.data() + *pos, sizeof(float));
  if (!std::isfinite(value)) return false;
  const uint8_t children = static_cast<uint8_t>(bytes[*pos + sizeof(float)]);
  *pos += sizeof(float) + 1;
  ++*nodes;
  for (unsigned i = 0; i < 8; ++i) {
    if (!(children & (1u << i))) continue;
    if (depth + 1 > kTreeDepth) return false;
    if (!WalkFullNode(bytes, pos, depth + 1, nodes)) return false;
  }
  return true;
}

common::Status CheckStream(const std::string& bytes, bool binary, StreamHeader* header) {
  common::Status status = ParseHeader(bytes, binary, header);
  if (!status.ok()) return status;
  if (header->id != "OcTree") {
    return common::CorruptError("OctoMap stream holds a '" + header->id + "', not an OcTree");
  }
  size_t pos = header->data_offset;
  long long nodes = 0;
  if (header->size > 0) {
    bool ok;
    if (binary) {
      nodes = 1;  // the root
      ok = WalkBinaryNode(bytes, &pos, 0, &nodes);
    } else {
      ok = WalkFullNode(bytes, &pos, 0, &nodes);
    }
    if (!ok) return common::CorruptError("OctoMap stream data is truncated or malformed");
  }
  if (nodes != header->size) {
    return common::CorruptError("OctoMap stream has " + std::to_string(nodes) +
                                " nodes but its header says " + std::to_string(header->size));
  }
  if (pos != bytes.size()) {
    return common::CorruptError("OctoMap stream has " + std::to_string(bytes.size() - pos) +
                                " bytes after its data");
  }
  return common::Status::Ok();
}

}  // namespace

void OctomapLayerParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(resolution_m) && resolution_m >= 0.001 && resolution_m <= 10.0,
                     "octomap resolution_m must be in [0.001, 10], got " << resolution_m);
  CAIRN_THROW_UNLESS(prob_hit > 0.5 && prob_hit < 1.0,
                     "octomap prob_hit must be in (0.5, 1), got " << prob_hit);
  CAIRN_THROW_UNLESS(prob_miss > 0.0 && prob_miss < 0.5,
                     "octomap prob_miss must be in (0, 0.5), got " << prob_miss);
  CAIRN_THROW_UNLESS(clamp_min > 0.0 && clamp_min < 0.5 && clamp_max > 0.5 && clamp_max < 1.0,
                     "octomap clamps must satisfy 0 < clamp_min < 0.5 < clamp_max < 1");
  CAIRN_THROW_UNLESS(occupancy_threshold > 0.0 && occupancy_threshold < 1.0,
                     "octomap occupancy_threshold must be in (0, 1), got " << occupancy_threshold);
  CAIRN_THROW_UNLESS(
      std::isfinite(max_range_m) && max_range_m > 0.0 && max_range_m <= 2000.0 * resolution_m,
      "octomap max_range_m must be in (0, 2000 * resolution_m], got " << max_range_m);
  CAIRN_THROW_UNLESS(std::isfinite(min_range_m) && min_range_m >= 0.0,
                     "octomap min_range_m must be >= 0, got " << min_range_m);
}

OctomapLayer::OctomapLayer(const OctomapLayerParams& params)
    : params_(params), inserter_(std::make_unique<internal::OctomapBatchInserter>()) {
  params_.Validate();
  tree_ = std::make_unique<octomap::OcTree>(params_.resolution_m);
  ApplySensorModel(tree_.get());
}

void OctomapLayer::ApplySensorModel(octomap::OcTree* tree) const {
  tree->setProbHit(params_.prob_hit);
  tree->setProbMiss(params_.prob_miss);
  tree->setClampingThresMin(params_.clamp_min);
  tree->setClampingThresMax(params_.clamp_max);
  tree->setOccupancyThres(params_.occupancy_threshold);
}

OctomapInsertStats OctomapLayer::InsertScan(const octomap::Pointcloud& points_world,
                                            const octomap::point3d& origin) {
  OctomapInsertStats stats;
  stats.points = static_cast<int64_t>(points_world.size());
  if (!std::isfinite(origin.x()) || !std::isfinite(origin.y()) || !std::isfinite(origin.z())) {
    stats.points_invalid = stats.points;
    return stats;
  }
  inserter_->Reserve(points_world.size());
  const double min_range_sq = params_.min_range_m * params_.min_range_m;
  for (size_t i = 0; i < points_world.size(); ++i) {
    const octomap::point3d& p = points_world[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      ++stats.points_invalid;
      continue;
    }
    if (min_range_sq > 0.0 && (p - origin).norm_sq() < min_range_sq) {
      ++stats.points_too_close;
      continue;
    }
    inserter_->AddPoint(origin, p);
  }
  const internal::OctomapBatchStats batch =
      inserter_->Insert(tree_.get(), params_.max_range_m, params_.prune);
  stats.rays_truncated = batch.rays_truncated;
  stats.rays_outside = batch.rays_outside;
  stats.occupied_voxels = batch.occupied_voxels;
  stats.free_voxels = batch.free_voxels;
  stats.voxels_s = batch.voxels_s;
  stats.tree_s = batch.tree_s;
  if (batch.occupied_voxels + batch.free_voxels > 0) ++version_;
  return stats;
}

OctomapInsertStats OctomapLayer::InsertRevolution(const common::LidarRevolution& revolution) {
  OctomapInsertStats stats;
  inserter_->Reserve(revolution.num_points());
  const double min_range_sq = params_.min_range_m * params_.min_range_m;
  for (const common::LidarSlice& slice : revolution.slices) {
    const common::Pose3& pose = slice.sensor_pose;
    stats.points += static_cast<int64_t>(slice.points.size());
    if (!pose.position_m.allFinite() || !pose.orientation.coeffs().allFinite() ||
        pose.orientation.norm() < 1e-6) {
      stats.points_invalid += static_cast<int64_t>(slice.points.size());
      continue;
    }
    const Eigen::Matrix3d rotation = pose.orientation.normalized().toRotationMatrix();
    const octomap::point3d origin(static_cast<float>(pose.position_m.x()),
                                  static_cast<float>(pose.position_m.y()),
                                  static_cast<float>(pose.position_m.z()));
    for (const common::LidarPoint& p : slice.points) {
      const Eigen::Vector3d local(p.x_m, p.y_m, p.z_m);
      if (!local.allFinite()) {
        ++stats.points_invalid;
        continue;
      }
      if (local.squaredNorm() < min_range_sq) {
        ++stats.points_too_close;
        continue;
      }
      const Eigen::Vector3d w = pose.position_m + rotation * local;
      inserter_->AddPoint(origin,
                          octomap::point3d(static_cast<float>(w.x()), static_cast<float>(w.y()),
                                           static_cast<float>(w.z())));
    }
  }
  const internal::OctomapBatchStats batch =
      inserter_->Insert(tree_.get(), params_.max_range_m, params_.prune);
  stats.rays_truncated = batch.rays_truncated;
  stats.rays_outside = batch.rays_outside;
  stats.occupied_voxels = batch.occupied_voxels;
  stats.free_voxels = batch.free_voxels;
  stats.voxels_s = batch.voxels_s;
  stats.tree_s = batch.tree_s;
  if (batch.occupied_voxels + batch.free_voxels > 0) ++version_;
  return stats;
}

std::string OctomapLayer::ToBinary() const {
  // The .bt stream of OcTree::writeBinaryConst, header and data, written here: Debian's
  // liboctomap is built with its debug output on, and writeBinaryConst prints " done." to stderr
  // on every call (one log line per publication).
  std::ostringstream out(std::ios::binary);
  out << "# Octomap OcTree binary file\n#\n"
      << "id " << tree_->getTreeType() << "\n"
      << "size " << tree_->size() << "\n"
      << "res " << tree_->getResolution() << "\n"
      << "data\n";
  tree_->writeBinaryData(out);
  return out.str();
}

std::string OctomapLayer::ToFull() const {
  std::ostringstream out(std::ios::binary);
  tree_->write(out);
  return out.str();
}

namespace {
common::Status WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) return common::UnavailableError("cannot open '" + path + "' for writing");
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.close();
  if (!file) return common::UnavailableError("cannot write '" + path + "'");
  return common::Status::Ok();
}
}  // namespace

common::Status OctomapLayer::WriteBinaryFile(const std::string& path) const {
  return WriteBytes(path, ToBinary());
}

common::Status OctomapLayer::WriteFullFile(const std::string& path) const {
  return WriteBytes(path, ToFull());
}

common::Result<std::unique_ptr<octomap::OcTree>> ReadOcTree(const std::string& bytes, bool binary) {
  StreamHeader header;
  common::Status status = CheckStream(bytes, binary, &header);
  if (!status.ok()) return status;
  std::istringstream in(bytes, std::ios::binary);
  if (binary) {
    auto tree = std::make_unique<octomap::OcTree>(header.resolution_m);
    if (!tree->readBinary(in)) return common::CorruptError("octomap could not read the .bt stream");
    return tree;
  }
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(in));
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  if (!tree) return common::CorruptError("octomap could not read the .ot stream as an OcTree");
  read.release();
  return std::unique_ptr<octomap::OcTree>(tree);
}

common::Status OctomapLayer::Load(const std::string& bytes, bool binary) {
  common::Result<std::unique_ptr<octomap::OcTree>> read = ReadOcTree(bytes, binary);
  if (!read.ok()) return read.status();
  std::unique_ptr<octomap::OcTree> tree = std::move(read).value();
  if (std::abs(tree->getResolution() - params_.resolution_m) > 1e-9) {
    return common::CorruptError("OctoMap stream has resolution " +
                                std::to_string(tree->getResolution()) + " m, the layer uses " +
                                std::to_string(params_.resolution_m) + " m");
  }
  ApplySensorModel(tree.get());
  tree_ = std::move(tree);
  ++version_;
  return common::Status::Ok();
}

void OctomapLayer::Clear() {
  tree_->clear();
  ++version_;
}

OctomapLayerParams ReadOctomapLayerParams(common::YamlMap& m) {
  OctomapLayerParams p;
  m.Get("resolution_m", &p.resolution_m);
  m.Get("prob_hit", &p.prob_hit);
  m.Get("prob_miss", &p.prob_miss);
  m.Get("clamp_min", &p.clamp_min);
  m.Get("clamp_max", &p.clamp_max);
  m.Get("max_range_m", &p.max_range_m);
  m.Get("min_range_m", &p.min_range_m);
  return p;
}

}  // namespace cairn::mapping
