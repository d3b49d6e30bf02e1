#include "services/mapping/octomap_layer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace cairn::mapping {
namespace {

using octomap::OcTree;
using octomap::OcTreeKey;
using octomap::point3d;

struct Box {
  double lo[3];
  double hi[3];
};

// A 20 m x 12 m x 4 m room with a pillar and a low box, as solid slabs.
std::vector<Box> Room() {
  return {{{-10, -6, -1}, {10, 6, 0}}, {{-10, -6, 4}, {10, 6, 5}},  {{-11, -6, 0}, {-10, 6, 4}},
          {{10, -6, 0}, {11, 6, 4}},   {{-10, -7, 0}, {10, -6, 4}}, {{-10, 6, 0}, {10, 7, 4}},
          {{3, 1, 0}, {3.6, 1.6, 4}},  {{-4, -3, 0}, {-3, -2, 0.5}}};
}

double Cast(const std::vector<Box>& scene, const double o[3], const double d[3]) {
  double best = INFINITY;
  for (const Box& b : scene) {
    double t0 = 0.0, t1 = best;
    bool hit = true;
    for (int a = 0; a < 3 && hit; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        hit = o[a] >= b.lo[a] && o[a] <= b.hi[a];
        continue;
      }
      double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      hit = t0 <= t1;
    }
    if (hit && t0 > 1e-6) best = std::min(best, t0);
  }
  return best;
}

// A 16-ring lidar scan of the room from `o` (seeded range noise).
octomap::Pointcloud Scan(const double o[3], uint32_t seed, int azimuths = 720) {
  const std::vector<Box> scene = Room();
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  octomap::Pointcloud cloud;
  for (int az = 0; az < azimuths; ++az) {
    const double a = az * 2.0 * M_PI / azimuths;
    for (int ring = 0; ring < 16; ++ring) {
      const double el = (-15.0 + ring * 2.0) * M_PI / 180.0;
      const double d[3] = {std::cos(el) * std::cos(a), std::cos(el) * std::sin(a), std::sin(el)};
      const double t = Cast(scene, o, d);
      if (!std::isfinite(t)) continue;
      const double r = t + noise(rng);
      cloud.push_back(static_cast<float>(o[0] + r * d[0]), static_cast<float>(o[1] + r * d[1]),
                      static_cast<float>(o[2] + r * d[2]));
    }
  }
  return cloud;
}

std::unique_ptr<OcTree> StockTree(const OctomapLayerParams& p) {
  auto tree = std::make_unique<OcTree>(p.resolution_m);
  tree->setProbHit(p.prob_hit);
  tree->setProbMiss(p.prob_miss);
  tree->setClampingThresMin(p.clamp_min);
  tree->setClampingThresMax(p.clamp_max);
  return tree;
}

struct Comparison {
  int64_t both{0};
  int64_t same_class{0};
  int64_t same_logodds{0};
  int64_t only_a{0};
};

// Every voxel of a's leaves (pruned leaves expanded) looked up in b.
Comparison Compare(const OcTree& a, const OcTree& b) {
  Comparison c;
  const unsigned depth = a.getTreeDepth();
  for (auto it = a.begin_leafs(), end = a.end_leafs(); it != end; ++it) {
    const OcTreeKey base = it.getIndexKey();
    const unsigned side = 1u << (depth - it.getDepth());
    for (unsigned dx = 0; dx < side; ++dx) {
      for (unsigned dy = 0; dy < side; ++dy) {
        for (unsigned dz = 0; dz < side; ++dz) {
          const OcTreeKey key(base[0] + dx, base[1] + dy, base[2] + dz);
          const octomap::OcTreeNode* node = b.search(key);
          if (!node) {
            ++c.only_a;
            continue;
          }
          ++c.both;
          if (a.isNodeOccupied(*it) == b.isNodeOccupied(node)) ++c.same_class;
          if (it->getLogOdds() == node->getLogOdds()) ++c.same_logodds;
        }
      }
    }
  }
  return c;
}

std::string TempPath(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(CAIRN_BINARY_DIR) / "test-tmp" / "octomap_layer_test";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// ---- A known scene ------------------------------------------------------------------------

TEST(OctomapLayerTest, WallAtFiveMetresOccupiedFreeInFrontUnknownBehind) {
  OctomapLayer layer;  // 0.1 m, 0.7 / 0.4, clamps 0.12 / 0.97, 30 m
  const point3d origin(0.05f, 0.05f, 1.05f);
  octomap::Pointcloud wall;
  for (double y = -2.0; y <= 2.0; y += 0.05) {
    for (double z = 0.2; z <= 2.0; z += 0.05) {
      wall.push_back(5.02f, static_cast<float>(y), static_cast<float>(z));
    }
  }
  for (int i = 0; i < 3; ++i) {
    const OctomapInsertStats stats = layer.InsertScan(wall, origin);
    EXPECT_EQ(stats.points, static_cast<int64_t>(wall.size()));
    EXPECT_GT(stats.occupied_voxels, 0);
  }
  const OcTree& tree = layer.tree();
  const octomap::OcTreeNode* at_wall = tree.search(5.05, 0.05, 1.05);
  ASSERT_NE(at_wall, nullptr);
  EXPECT_TRUE(tree.isNodeOccupied(at_wall));
  EXPECT_NEAR(at_wall->getOccupancy(), 1.0 / (1.0 + std::exp(-3 * std::log(0.7 / 0.3))), 1e-4);
  for (double x : {0.55, 2.55, 4.55}) {
    const octomap::OcTreeNode* in_front = tree.search(x, 0.05, 1.05);
    ASSERT_NE(in_front, nullptr) << x;
    EXPECT_FALSE(tree.isNodeOccupied(in_front)) << x;
  }
  EXPECT_EQ(tree.search(6.05, 0.05, 1.05), nullptr);  // behind the wall: unknown
  EXPECT_EQ(tree.search(5.55, 0.05, 1.05), nullptr);
  EXPECT_EQ(layer.version(), 3);
}

TEST(OctomapLayerTest, SensorModelDefaults) {
  OctomapLayer layer;
  EXPECT_DOUBLE_EQ(layer.tree().getResolution(), 0.1);
  EXPECT_NEAR(layer.tree().getProbHit(), 0.7, 1e-6);
  EXPECT_NEAR(layer.tree().getProbMiss(), 0.4, 1e-6);
  EXPECT_NEAR(layer.tree().getClampingThresMin(), 0.12, 1e-6);
  EXPECT_NEAR(layer.tree().getClampingThresMax(), 0.97, 1e-6);
  EXPECT_DOUBLE_EQ(layer.params().max_range_m, 30.0);
}

// ---- Agreement with the stock insertion ---------------------------------------------------

TEST(OctomapLayerTest, AgreesWithStockInsertPointCloud) {
  OctomapLayerParams params;
  params.max_range_m = 8.0;  // part of the room lies beyond: those rays only clear
  OctomapLayer layer(params);
  std::unique_ptr<OcTree> stock = StockTree(params);
  const double origins[3][3] = {{0.0, 0.0, 1.0}, {1.3, -0.7, 1.2}, {-5.0, 2.0, 0.8}};
  for (int s = 0; s < 3; ++s) {
    const octomap::Pointcloud cloud = Scan(origins[s], 11 + s);
    const point3d o(origins[s][0], origins[s][1], origins[s][2]);
    const OctomapInsertStats stats = layer.InsertScan(cloud, o);
    EXPECT_GT(stats.rays_truncated, 0);
    stock->insertPointCloud(cloud, o, params.max_range_m);

    const Comparison stock_side = Compare(*stock, layer.tree());
    const Comparison layer_side = Compare(layer.tree(), *stock);
    ASSERT_GT(stock_side.both, 100000);
    const double agreement = static_cast<double>(stock_side.same_class) / stock_side.both;
    EXPECT_GE(agreement, 0.99) << "scan " << s;
    // In fact the trees are the same voxel for voxel.
    EXPECT_EQ(stock_side.same_logodds, stock_side.both) << "scan " << s;
    EXPECT_EQ(stock_side.only_a, 0) << "scan " << s;
    EXPECT_EQ(layer_side.only_a, 0) << "scan " << s;
    EXPECT_EQ(layer.tree().size(), stock->size()) << "scan " << s;
  }
}

TEST(OctomapLayerTest, RevolutionSlicesUseTheirOwnPoses) {
  // Two slices seen from two sensor poses; the same points inserted as two stock scans.
  OctomapLayerParams params;
  OctomapLayer layer(params);
  common::LidarRevolution revolution;
  revolution.expected_slices = 2;
  const double o0[3] = {0.0, 0.0, 1.0}, o1[3] = {0.5, 0.2, 1.0};
  const octomap::Pointcloud world0 = Scan(o0, 3, 360), world1 = Scan(o1, 4, 360);
  std::unique_ptr<OcTree> stock = StockTree(params);
  octomap::Pointcloud both;
  for (int s = 0; s < 2; ++s) {
    const double* o = s == 0 ? o0 : o1;
    const octomap::Pointcloud& world = s == 0 ? world0 : world1;
    common::LidarSlice slice;
    slice.slice_index = s;
    slice.slice_count = 2;
    slice.sensor_pose.position_m = {o[0], o[1], o[2]};
    const double yaw = 0.3 * s;
    slice.sensor_pose.orientation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
    const Eigen::Matrix3d to_sensor = slice.sensor_pose.orientation.toRotationMatrix().transpose();
    for (size_t i = 0; i < world.size(); ++i) {
      const Eigen::Vector3d local =
          to_sensor * (Eigen::Vector3d(world[i].x(), world[i].y(), world[i].z()) -
                       slice.sensor_pose.position_m);
      slice.points.push_back({static_cast<float>(local.x()), static_cast<float>(local.y()),
                              static_cast<float>(local.z()), 0.f, 0});
    }
    slice.points.push_back({NAN, 0.f, 0.f, 0.f, 0});  // invalid
    revolution.slices.push_back(slice);
  }
  const OctomapInsertStats stats = layer.InsertRevolution(revolution);
  EXPECT_EQ(stats.points_invalid, 2);
  EXPECT_EQ(stats.points, static_cast<int64_t>(world0.size() + world1.size() + 2));
  // Occupied end voxels agree with the stock insertion of the same rays (free voxels differ
  // slightly: one scan here, two scans there).
  stock->insertPointCloud(world0, point3d(o0[0], o0[1], o0[2]), params.max_range_m);
  stock->insertPointCloud(world1, point3d(o1[0], o1[1], o1[2]), params.max_range_m);
  const Comparison c = Compare(*stock, layer.tree());
  EXPECT_GE(static_cast<double>(c.same_class) / c.both, 0.99);
}

TEST(OctomapLayerTest, DropsNonFiniteAndTooClosePoints) {
  OctomapLayerParams params;
  params.min_range_m = 0.5;
  OctomapLayer layer(params);
  octomap::Pointcloud cloud;
  cloud.push_back(NAN, 0.f, 1.f);
  cloud.push_back(INFINITY, 0.f, 1.f);
  cloud.push_back(0.2f, 0.f, 1.f);  // too close
  cloud.push_back(3.f, 0.f, 1.f);
  const OctomapInsertStats stats = layer.InsertScan(cloud, point3d(0.f, 0.f, 1.f));
  EXPECT_EQ(stats.points_invalid, 2);
  EXPECT_EQ(stats.points_too_close, 1);
  EXPECT_EQ(stats.occupied_voxels, 1);
  const OctomapInsertStats nan_origin = layer.InsertScan(cloud, point3d(NAN, 0.f, 0.f));
  EXPECT_EQ(nan_origin.points_invalid, 4);
  EXPECT_EQ(nan_origin.occupied_voxels, 0);
}

TEST(OctomapLayerTest, RejectsBadParams) {
  OctomapLayerParams p;
  p.resolution_m = 0.0;
  EXPECT_THROW(OctomapLayer{p}, std::invalid_argument);
  p = OctomapLayerParams();
  p.prob_hit = 0.4;
  EXPECT_THROW(OctomapLayer{p}, std::invalid_argument);
  p = OctomapLayerParams();
  p.clamp_max = 0.3;
  EXPECT_THROW(OctomapLayer{p}, std::invalid_argument);
  p = OctomapLayerParams();
  p.max_range_m = 500.0;  // 5000 voxels at 0.1 m
  EXPECT_THROW(OctomapLayer{p}, std::invalid_argument);
}

// ---- Publish form and files ---------------------------------------------------------------

class OctomapStreamTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const double o[3] = {0.0, 0.0, 1.0};
    dut_.InsertScan(Scan(o, 5, 360), point3d(0.f, 0.f, 1.f));
    ASSERT_GT(dut_.tree().size(), 1000u);
  }
  OctomapLayer dut_;
};

TEST_F(OctomapStreamTest, BinaryRoundTripKeepsOccupancy) {
  const size_t size_before = dut_.tree().size();
  const std::string bt = dut_.ToBinary();
  EXPECT_EQ(dut_.tree().size(), size_before);  // writing does not prune or change the tree
  auto read = ReadOcTree(bt, /*binary=*/true);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  const Comparison c = Compare(dut_.tree(), *read.value());
  EXPECT_EQ(c.only_a, 0);
  EXPECT_EQ(c.same_class, c.both);  // .bt keeps occupied / free per voxel
  EXPECT_EQ(Compare(*read.value(), dut_.tree()).only_a, 0);
}

TEST_F(OctomapStreamTest, FullRoundTripKeepsLogOdds) {
  auto read = ReadOcTree(dut_.ToFull(), /*binary=*/false);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  const Comparison c = Compare(dut_.tree(), *read.value());
  EXPECT_EQ(c.only_a, 0);
  EXPECT_EQ(c.same_logodds, c.both);
  EXPECT_EQ(read.value()->size(), dut_.tree().size());
}

TEST_F(OctomapStreamTest, FilesAreReadByOctomapItself) {
  const std::string bt_path = TempPath("map.bt"), ot_path = TempPath("map.ot");
  ASSERT_TRUE(dut_.WriteBinaryFile(bt_path).ok());
  ASSERT_TRUE(dut_.WriteFullFile(ot_path).ok());
  OcTree from_bt(0.1);
  ASSERT_TRUE(from_bt.readBinary(bt_path));
  EXPECT_EQ(Compare(dut_.tree(), from_bt).same_class, Compare(dut_.tree(), from_bt).both);
  std::unique_ptr<octomap::AbstractOcTree> from_ot(octomap::AbstractOcTree::read(ot_path));
  auto* ot_tree = dynamic_cast<OcTree*>(from_ot.get());
  ASSERT_NE(ot_tree, nullptr);
  EXPECT_EQ(ot_tree->size(), dut_.tree().size());
  EXPECT_FALSE(dut_.WriteBinaryFile("/nonexistent-dir/map.bt").ok());
}

TEST_F(OctomapStreamTest, LoadReplacesTheTree) {
  OctomapLayer other;
  ASSERT_TRUE(other.Load(dut_.ToFull(), /*binary=*/false).ok());
  EXPECT_EQ(other.tree().size(), dut_.tree().size());
  EXPECT_EQ(other.version(), 1);
  EXPECT_NEAR(other.tree().getClampingThresMax(), 0.97, 1e-6);
  OctomapLayerParams coarse;
  coarse.resolution_m = 0.2;
  OctomapLayer wrong_resolution(coarse);
  const common::Status status = wrong_resolution.Load(dut_.ToBinary(), /*binary=*/true);
  EXPECT_EQ(status.code(), common::StatusCode::kCorrupt);
  EXPECT_NE(status.message().find("resolution"), std::string::npos);
  EXPECT_EQ(wrong_resolution.tree().size(), 0u);
}

TEST_F(OctomapStreamTest, CorruptStreamsAreRefusedWithoutCrashing) {
  const std::string bt = dut_.ToBinary(), ot = dut_.ToFull();
  const size_t bt_data = bt.find("data\n") + 5, ot_data = ot.find("data\n") + 5;
  std::vector<std::pair<std::string, bool>> bad = {
      {"", true},
      {"hello", false},
      {bt.substr(0, bt.size() - 7), true},  // truncated
      {ot.substr(0, ot.size() - 3), false},
      {bt + "xx", true},                                          // trailing bytes
      {bt.substr(0, bt_data) + std::string(4096, '\xff'), true},  // inner nodes without end
      {ot.substr(0, ot_data) + std::string(4096, '\x01'), false},
      {ot, true},  // .ot read as .bt
  };
  std::string wrong_size = bt;
  wrong_size.replace(wrong_size.find("size "), 6, "size 9");
  bad.push_back({wrong_size, true});
  std::string wrong_type = ot;
  wrong_type.replace(wrong_type.find("id OcTree"), 9, "id ColorOcTree");
  bad.push_back({wrong_type, false});
  for (size_t i = 0; i < bad.size(); ++i) {
    auto read = ReadOcTree(bad[i].first, bad[i].second);
    EXPECT_FALSE(read.ok()) << "case " << i;
    if (!read.ok()) {
      EXPECT_EQ(read.status().code(), common::StatusCode::kCorrupt) << "case " << i;
    }
    OctomapLayer layer;
    EXPECT_FALSE(layer.Load(bad[i].first, bad[i].second).ok()) << "case " << i;
  }
}

}  // namespace
}  // namespace cairn::mapping
