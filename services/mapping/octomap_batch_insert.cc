#include "services/mapping/octomap_batch_insert.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>

namespace cairn::mapping::internal {

namespace {

using octomap::OcTreeKey;

using octomap::point3d;

double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The scan's bounding box is split in bricks of 8^3 voxels; a box needing more brick slots
// than this is inserted in several batches.
constexpr size_t kMaxDirectorySlots = size_t{1} << 24;

uint64_t Spread3(uint64_t v) {
  v &= 0xFFFF;
  v = (v | (v << 32)) & 0x001F00000000FFFFull;
  v = (v | (v << 16)) & 0x001F0000FF0000FFull;
  v = (v | (v << 8)) & 0x100F00F00F00F00Full;
  v = (v | (v << 4)) & 0x10C30C30C30C30C3ull;
  v = (v | (v << 2)) & 0x1249249249249249ull;
  return v;
}

uint64_t Compact3(uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v | (v >> 2)) & 0x10C30C30C30C30C3ull;
  v = (v | (v >> 4)) & 0x100F00F00F00F00Full;
  v = (v | (v >> 8)) & 0x001F0000FF0000FFull;
  v = (v | (v >> 16)) & 0x001F00000000FFFFull;
  v = (v | (v >> 32)) & 0xFFFFull;
  return v;
}

OcTreeKey KeyOfCode(uint64_t code) {
  return OcTreeKey(static_cast<octomap::key_type>(Compact3(code)),
                   static_cast<octomap::key_type>(Compact3(code >> 1)),
                   static_cast<octomap::key_type>(Compact3(code >> 2)));
}

// Bit of voxel (x, y, z) & 7 inside its brick: the 9-bit Morton code, so that walking a
// brick's bits in order walks its voxels in octree order.
constexpr unsigned kSpread3Bits[8] = {0, 1, 8, 9, 64, 65, 72, 73};
inline unsigned BrickBit(unsigned lx, unsigned ly, unsigned lz) {
  return kSpread3Bits[lx & 7] | (kSpread3Bits[ly & 7] << 1) | (kSpread3Bits[lz & 7] << 2);
}

}  // namespace

uint64_t MortonCode(const OcTreeKey& key) {
  return Spread3(key[0]) | (Spread3(key[1]) << 1) | (Spread3(key[2]) << 2);
}

size_t OctomapBatchInserter::SlotOf(unsigned lx, unsigned ly, unsigned lz) const {
  return ((static_cast<size_t>(lz >> 3) * box_bricks_[1]) + (ly >> 3)) * box_bricks_[0] + (lx >> 3);
}

OctomapBatchInserter::Brick* OctomapBatchInserter::BrickAt(size_t slot) {
  int32_t& index = directory_[slot];
  if (index < 0) {
    index = static_cast<int32_t>(bricks_.size());
    bricks_.emplace_back();
    std::memset(&bricks_.back(), 0, sizeof(Brick));
    // The brick is the octree node at depth 13 holding these voxels: its Morton code with the
    // nine voxel bits left out, in front of the brick's index for sorting.
    const size_t bx = slot % box_bricks_[0];
    const size_t by = (slot / box_bricks_[0]) % box_bricks_[1];
    const size_t bz = slot / (static_cast<size_t>(box_bricks_[0]) * box_bricks_[1]);
    const OcTreeKey corner(static_cast<octomap::key_type>(box_min_[0] + 8 * bx),
                           static_cast<octomap::key_type>(box_min_[1] + 8 * by),
                           static_cast<octomap::key_type>(box_min_[2] + 8 * bz));
    brick_order_.push_back((MortonCode(corner) >> 9 << 24) | static_cast<uint64_t>(index));
  }
  return &bricks_[static_cast<size_t>(index)];
}

void OctomapBatchInserter::WalkFree(const octomap::OcTree& tree, const point3d& origin,
                                    const point3d& end, const OcTreeKey& key_origin,
                                    const OcTreeKey& key_end) {
  // The voxels of OcTree::computeRayKeys(origin, end): its DDA with the same float/double
  // arithmetic and the same tie-breaking, the end voxel excluded. Each voxel is marked in the
  // brick bitmap as it is visited. The key is packed 16 bits per axis (a step is one add, the
  // end test one compare), the voxel's bit in its brick is stepped in place (Morton order,
  // one 3-bit field per axis) and the brick is looked up again only when the field wraps.
  if (key_origin == key_end) return;
  constexpr uint64_t kKeyMask = 0xFFFFFFFFFFFFull;
  auto pack = [](unsigned x, unsigned y, unsigned z) {
    return uint64_t{x} | (uint64_t{y} << 16) | (uint64_t{z} << 32);
  };
  uint64_t current = pack(key_origin[0], key_origin[1], key_origin[2]);
  const uint64_t target = pack(key_end[0], key_end[1], key_end[2]);
  const unsigned lx = key_origin[0] - box_min_[0], ly = key_origin[1] - box_min_[1],
                 lz = key_origin[2] - box_min_[2];
  size_t slot = SlotOf(lx, ly, lz);
  Brick* brick = BrickAt(slot);
  unsigned bit = BrickBit(lx, ly, lz);
  brick->free_bits[bit >> 6] |= uint64_t{1} << (bit & 63);

  point3d direction = end - origin;
  const float length = static_cast<float>(direction.norm());
  direction /= length;
  const double resolution = tree.getResolution();
  const unsigned kFieldMask[3] = {0x49, 0x92, 0x124};
  const int64_t slot_stride[3] = {1, static_cast<int64_t>(box_bricks_[0]),
                                  static_cast<int64_t>(box_bricks_[0]) * box_bricks_[1]};
  double t_max[3];
  double t_delta[3];
  uint64_t key_step[3];  // packed +-1 on one axis (two's complement wraps correctly)
  int64_t slot_step[3];
  bool positive[3];
  for (unsigned i = 0; i < 3; ++i) {
    const int sign = (direction(i) > 0.0) - (direction(i) < 0.0);
    positive[i] = sign > 0;
    key_step[i] = sign > 0 ? uint64_t{1} << (16 * i) : -(uint64_t{1} << (16 * i));
    slot_step[i] = sign * slot_stride[i];
    if (sign != 0) {
      double voxel_border = tree.keyToCoord(key_origin[i]);
      voxel_border += static_cast<float>(sign * resolution * 0.5);
      t_max[i] = (voxel_border - origin(i)) / direction(i);
      t_delta[i] = resolution / std::fabs(direction(i));
    } else {
      t_max[i] = DBL_MAX;
      t_delta[i] = DBL_MAX;
    }
  }
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  const double dx = t_delta[0], dy = t_delta[1], dz = t_delta[2];
  const double limit = length;
  while (true) {
    // Same choice as computeRayKeys: x if tx < ty and tx < tz, else y if ty < tz, else z.
    unsigned axis;
    if (tx < ty) {
      if (tx < tz) {
        axis = 0;
        tx += dx;
      } else {
        axis = 2;
        tz += dz;
      }
    } else if (ty < tz) {
      axis = 1;
      ty += dy;
    } else {
      axis = 2;
      tz += dz;
    }
    current = (current + key_step[axis]) & kKeyMask;
    if (current == target) return;
    // Past the end point without meeting its voxel (rounding): stop, as computeRayKeys does.
    if (std::min(std::min(tx, ty), tz) > limit) return;
    const unsigned m = kFieldMask[axis];
    const unsigned field = bit & m;
    if (positive[axis]) {
      if (field == m) brick = BrickAt(slot += static_cast<size_t>(slot_step[axis]));
      bit = (((bit | ~m) + 1) & m) | (bit & ~m);
    } else {
      if (field == 0) brick = BrickAt(slot += static_cast<size_t>(slot_step[axis]));
      bit = (((bit & m) - 1) & m) | (bit & ~m);
    }
    brick->free_bits[bit >> 6] |= uint64_t{1} << (bit & 63);
  }
}

void OctomapBatchInserter::PrepareRays(const octomap::OcTree& tree, double max_range_m,
                                       OctomapBatchStats* stats) {
  // Per ray: the end the DDA walks to (truncated beyond max range, as insertPointCloud), the
  // keys of both ends. (A member, so that its memory is reused: a large allocation per scan
  // would make malloc consolidate the many small chunks the tree's nodes free.)
  std::vector<Prepared>& prepared = prepared_;
  prepared.clear();
  for (const Ray& ray : rays_) {
    Prepared p{ray.origin, ray.end, OcTreeKey(0, 0, 0), OcTreeKey(0, 0, 0), false, false};
    ++stats->rays;
    if (max_range_m < 0.0 || (ray.end - ray.origin).norm() <= max_range_m) {
      p.hit = tree.coordToKeyChecked(ray.end, p.end_key);
    } else {
      const point3d direction = (ray.end - ray.origin).normalized();
      p.end = ray.origin + direction * static_cast<float>(max_range_m);
      ++stats->rays_truncated;
    }
    OcTreeKey walk_end(0, 0, 0);
    p.walk =
        tree.coordToKeyChecked(p.origin, p.origin_key) && tree.coordToKeyChecked(p.end, walk_end);
    if (p.walk) {
      p.end_key = walk_end;
    } else if (!p.hit) {
      ++stats->rays_outside;
      continue;
    }
    prepared.push_back(p);
  }
  rays_.clear();
}

size_t OctomapBatchInserter::StartBatch(size_t first, OctomapBatchStats* stats) {
  // The bounding box of every key the batch's rays can visit (a DDA stays inside its ends'
  // box), as many rays from `first` on as one brick directory holds.
  std::vector<Prepared>& prepared = prepared_;
  unsigned lo[3] = {65535, 65535, 65535}, hi[3] = {0, 0, 0};
  size_t last = first;
  for (; last < prepared.size(); ++last) {
    const Prepared& p = prepared[last];
    unsigned nlo[3], nhi[3];
    for (int a = 0; a < 3; ++a) {
      unsigned kmin = p.end_key[a], kmax = p.end_key[a];
      if (p.walk) {
        kmin = std::min<unsigned>(kmin, p.origin_key[a]);
        kmax = std::max<unsigned>(kmax, p.origin_key[a]);
      }
      nlo[a] = std::min(lo[a], kmin);
      nhi[a] = std::max(hi[a], kmax);
    }
    size_t slots = 1;
    for (int a = 0; a < 3; ++a) slots *= ((nhi[a] - nlo[a]) >> 3) + 2;
    if (slots > kMaxDirectorySlots) {
      if (last > first) break;
      // A single ray longer than any directory (no maximum range): skipped.
      prepared[last].walk = false;
      prepared[last].hit = false;
      ++stats->rays_outside;
      continue;
    }
    std::copy(nlo, nlo + 3, lo);
    std::copy(nhi, nhi + 3, hi);
  }
  // One voxel of margin: where an end point lies on a voxel border, the DDA's float border and
  // coordToKey's floor may disagree, and the walk then visits the voxel next to the end voxel
  // (as computeRayKeys does).
  for (int a = 0; a < 3; ++a) {
    const unsigned box_lo = lo[a] > 0 ? lo[a] - 1 : 0;
    const unsigned box_hi = std::min(hi[a] + 1, 65535u);
    box_min_[a] = box_lo & ~7u;  // brick aligned: a brick is an octree node at depth 13
    box_bricks_[a] = ((box_hi - box_min_[a]) >> 3) + 1;
  }
  directory_.assign(static_cast<size_t>(box_bricks_[0]) * box_bricks_[1] * box_bricks_[2], -1);
  bricks_.clear();
  brick_order_.clear();
  return last;
}

void OctomapBatchInserter::MarkVoxels(const octomap::OcTree& tree, size_t first, size_t last) {
  // Occupied end voxels first, so that the free set can exclude them as it is built.
  for (size_t i = first; i < last; ++i) {
    const Prepared& p = prepared_[i];
    if (!p.hit) continue;
    const unsigned lx = p.end_key[0] - box_min_[0], ly = p.end_key[1] - box_min_[1],
                   lz = p.end_key[2] - box_min_[2];
    Brick* brick = BrickAt(SlotOf(lx, ly, lz));
    const unsigned bit = BrickBit(lx, ly, lz);
    brick->occupied_bits[bit >> 6] |= uint64_t{1} << (bit & 63);
  }
  // Free voxels: the DDA of every ray, each voxel once, occupied ones left out.
  for (size_t i = first; i < last; ++i) {
    const Prepared& p = prepared_[i];
    if (p.walk) WalkFree(tree, p.origin, p.end, p.origin_key, p.end_key);
  }
}

void OctomapBatchInserter::ListItems(OctomapBatchStats* stats) {
  // Octree order: bricks sorted by their Morton code, the voxels of a brick in bit order; free
  // voxels are those crossed and not occupied.
  std::sort(brick_order_.begin(), brick_order_.end());
  items_.clear();
  for (const uint64_t entry : brick_order_) {
    const Brick& brick = bricks_[static_cast<size_t>(entry & 0xFFFFFF)];
    const uint64_t brick_code = (entry >> 24) << 9;
    for (unsigned w = 0; w < 8; ++w) {
      const uint64_t occupied = brick.occupied_bits[w];
      uint64_t any = brick.free_bits[w] | occupied;
      stats->occupied_voxels += __builtin_popcountll(occupied);
      stats->free_voxels += __builtin_popcountll(brick.free_bits[w] & ~occupied);
      while (any) {
        const unsigned b = static_cast<unsigned>(__builtin_ctzll(any));
        any &= any - 1;
        const uint64_t code = brick_code | (w << 6) | b;
        items_.push_back((code << 1) | ((occupied >> b) & 1u));
      }
    }
  }
}

OctomapBatchStats OctomapBatchInserter::Insert(octomap::OcTree* tree, double max_range_m,
                                               bool prune) {
  OctomapBatchStats stats;
  hit_logodds_ = tree->getProbHitLog();
  miss_logodds_ = tree->getProbMissLog();
  clamp_min_ = tree->getClampingThresMinLog();
  clamp_max_ = tree->getClampingThresMaxLog();
  PrepareRays(*tree, max_range_m, &stats);
  // Batches of rays whose bounding box one brick directory holds (usually one batch).
  size_t first = 0;
  while (first < prepared_.size()) {
    const size_t last = StartBatch(first, &stats);
    const double t_voxels = ThreadCpuSeconds();
    MarkVoxels(*tree, first, last);
    const double t_tree = ThreadCpuSeconds();
    stats.voxels_s += t_tree - t_voxels;
    // The voxels in octree order, then one depth-first walk of the tree.
    ListItems(&stats);
    ApplySorted(tree, prune);
    stats.tree_s += ThreadCpuSeconds() - t_tree;
    first = last;
  }
  return stats;
}

void OctomapBatchInserter::ApplySorted(octomap::OcTree* tree, bool prune) {
  if (items_.empty()) return;
  const uint64_t* begin = items_.data();
  const uint64_t* end = begin + items_.size();
  if (tree->getRoot() == nullptr) {
    // An empty tree: the first update creates the root (and its path) the stock way.
    const uint64_t first = *begin++;
    tree->updateNode(KeyOfCode(first >> 1), (first & 1) ? hit_logodds_ : miss_logodds_,
                     /*lazy_eval=*/false);
    if (begin == end) return;
  }
  ApplyNode(tree, tree->getRoot(), /*just_created=*/false, 0, begin, end, prune);
}

// Once per inner node visited: inlined into ApplyNode (as when it was its last part).
[[gnu::always_inline]] inline void OctomapBatchInserter::BackUp(octomap::OcTree* tree,
                                                                octomap::OcTreeNode* node,
                                                                bool prune) {
  // Collapse eight equal leaves, else take the children's maximum (as the stock non-lazy update
  // leaves inner nodes: pruneNode, else updateOccupancyChildren).
  float max_child = -std::numeric_limits<float>::max();
  bool collapsible = true;
  float first_value = 0.f;
  for (unsigned i = 0; i < 8; ++i) {
    if (!tree->nodeChildExists(node, i)) {
      collapsible = false;
      continue;
    }
    const octomap::OcTreeNode* child = tree->getNodeChild(node, i);
    const float v = child->getLogOdds();
    max_child = std::max(max_child, v);
    if (i == 0) first_value = v;
    if (collapsible && (v != first_value || tree->nodeHasChildren(child))) collapsible = false;
  }
  if (prune && collapsible && tree->pruneNode(node)) return;
  node->setLogOdds(max_child);
}

void OctomapBatchInserter::ApplyNode(octomap::OcTree* tree, octomap::OcTreeNode* node,
                                     bool just_created, unsigned depth, const uint64_t* begin,
                                     const uint64_t* end, bool prune) {
  const unsigned tree_depth = tree->getTreeDepth();
  if (depth == tree_depth) {
    // A leaf: one update (keys are distinct), clamped, as OccupancyOcTreeBase's
    // updateNodeLogOdds does it (add, then clamp).
    float l = node->getLogOdds() + ((*begin & 1) ? hit_logodds_ : miss_logodds_);
    if (l < clamp_min_) {
      l = clamp_min_;
    } else if (l > clamp_max_) {
      l = clamp_max_;
    }
    node->setLogOdds(l);
    return;
  }
  if (!just_created && !tree->nodeHasChildren(node)) {
    // A pruned leaf. updateNode leaves it untouched when it is already clamped in the
    // direction of every update; otherwise it is expanded into eight equal children.
    const float l = node->getLogOdds();
    bool changes = false;
    for (const uint64_t* it = begin; it != end && !changes; ++it) {
      changes = (*it & 1) ? l < clamp_max_ : l > clamp_min_;
    }
    if (!changes) return;
    tree->expandNode(node);
  }
  // Children in order: the items of child c are a contiguous run with the same prefix. The
  // runs are found first so that the existing children can be fetched from memory together.
  const unsigned shift = 3 * (tree_depth - 1 - depth) + 1;
  const uint64_t* run_begin[9];
  unsigned run_child[8];
  unsigned runs = 0;
  for (const uint64_t* it = begin; it != end;) {
    const uint64_t prefix = *it >> shift;
    const uint64_t bound = (prefix + 1) << shift;
    const uint64_t* run_end = it + 1;
    if (end - it > 16) {
      run_end = std::lower_bound(it + 1, end, bound);
    } else {
      while (run_end != end && *run_end < bound) ++run_end;
    }
    run_begin[runs] = it;
    run_child[runs] = static_cast<unsigned>(prefix & 7);
    if (tree->nodeChildExists(node, run_child[runs])) {
      __builtin_prefetch(tree->getNodeChild(node, run_child[runs]));
    }
    ++runs;
    it = run_end;
  }
  run_begin[runs] = end;
  for (unsigned r = 0; r < runs; ++r) {
    const unsigned child = run_child[r];
    bool created = false;
    if (!tree->nodeChildExists(node, child)) {
      tree->createNodeChild(node, child);
      created = true;
    }
    ApplyNode(tree, tree->getNodeChild(node, child), created, depth + 1, run_begin[r],
              run_begin[r + 1], prune);
  }
  BackUp(tree, node, prune);
}

}  // namespace cairn::mapping::internal
