#pragma once

#include <cstdint>
#include <vector>

#include <octomap/OcTree.h>

/// @file
/// Fast scan insertion into an octomap::OcTree (internal to OctomapLayer; exposed for tests and
/// the benchmark).
///
/// The result equals OcTree::insertPointCloud(scan, origin, max_range) (discretize = false):
/// the same voxels get the same single update per scan (free voxels of every ray minus the
/// occupied end voxels, occupied wins), and the ray voxels are chosen by the same 3-D DDA with
/// the same float/double arithmetic as OcTree::computeRayKeys, so the trees agree voxel for
/// voxel. Where the time goes differs:
///
/// - Deduplication. The stock code inserts every ray voxel into an std::unordered_set
///   (a heap node per voxel, millions per scan). Here each voxel sets a bit in a bitmap over
///   the scan's bounding box, stored in 8 x 8 x 8 bricks (each brick is an octree node at
///   depth 13 and its 512 bits are in Morton order), so a ray walks through a few cache lines
///   and its position in the bitmap is stepped along with the key.
/// - Tree update. The stock code calls updateNode once per voxel, each a search from the root
///   plus a recursive descent that recomputes the inner nodes on the way up. Here the bricks
///   are sorted by their Morton code and their bits read in order, which lists the voxels in
///   octree order without sorting them; one depth-first walk then visits every node on the
///   way once, updates the leaves and prunes or recomputes each inner node once on the way
///   back up, exactly as the stock non-lazy updates leave it.

namespace cairn::mapping::internal {

/// What one batch did.
struct OctomapBatchStats {
  int64_t rays{0};
  int64_t rays_truncated{0};   ///< longer than max range: free space only
  int64_t rays_outside{0};     ///< an end outside the tree's key range: skipped
  int64_t occupied_voxels{0};  ///< distinct occupied voxels updated
  int64_t free_voxels{0};      ///< distinct free voxels updated
  double voxels_s{0.0};        ///< thread CPU time finding the voxels (rays, deduplication)
  double tree_s{0.0};          ///< thread CPU time sorting and updating the tree
};

/// Reusable scratch for batched insertion (keeps its buffers between scans). Not thread-safe.
class OctomapBatchInserter {
 public:
  OctomapBatchInserter() = default;
  OctomapBatchInserter(const OctomapBatchInserter&) = delete;
  OctomapBatchInserter& operator=(const OctomapBatchInserter&) = delete;

  /// Adds one measured point with its sensor origin (world metres, float as OctoMap uses).
  void AddPoint(const octomap::point3d& origin, const octomap::point3d& point) {
    rays_.push_back({origin, point});
  }
  void Reserve(size_t points) { rays_.reserve(points); }
  size_t size() const { return rays_.size(); }

  /// Inserts every added point into `tree` as one scan and clears the list. `max_range_m` < 0
  /// means unlimited (as in insertPointCloud), but a ray spanning more than about 2^24 bricks
  /// of bitmap is then skipped (counted in rays_outside). `prune` collapses nodes whose eight
  /// children are equal leaves, as the stock non-lazy update does.
  OctomapBatchStats Insert(octomap::OcTree* tree, double max_range_m, bool prune = true);

 private:
  struct Ray {
    octomap::point3d origin;
    octomap::point3d end;
  };
  struct Prepared {
    octomap::point3d origin;
    octomap::point3d end;  // truncated at the maximum range
    octomap::OcTreeKey origin_key;
    octomap::OcTreeKey end_key;
    bool walk;  // free voxels to add
    bool hit;   // the end voxel is occupied
  };
  struct Brick {
    uint64_t free_bits[8];
    uint64_t occupied_bits[8];
  };
  // The stages of Insert: rays with their keys; the next batch's box and directory (returns the
  // end of the batch); its occupied and free voxels in the bitmap; the voxels in octree order.
  void PrepareRays(const octomap::OcTree& tree, double max_range_m, OctomapBatchStats* stats);
  size_t StartBatch(size_t first, OctomapBatchStats* stats);
  void MarkVoxels(const octomap::OcTree& tree, size_t first, size_t last);
  void ListItems(OctomapBatchStats* stats);
  // Scan-local voxel sets over the bounding box from box_min_, box_bricks_ bricks per axis.
  size_t SlotOf(unsigned lx, unsigned ly, unsigned lz) const;  // box-local voxel -> slot
  Brick* BrickAt(size_t slot);                                 // allocates on first use
  void WalkFree(const octomap::OcTree& tree, const octomap::point3d& origin,
                const octomap::point3d& end, const octomap::OcTreeKey& key_origin,
                const octomap::OcTreeKey& key_end);
  void ApplySorted(octomap::OcTree* tree, bool prune);
  void ApplyNode(octomap::OcTree* tree, octomap::OcTreeNode* node, bool just_created,
                 unsigned depth, const uint64_t* begin, const uint64_t* end, bool prune);
  // An inner node after its children were updated: pruned or set to their maximum.
  static void BackUp(octomap::OcTree* tree, octomap::OcTreeNode* node, bool prune);

  std::vector<Ray> rays_;
  std::vector<Prepared> prepared_;
  std::vector<int32_t> directory_;  // brick index per 8^3 block of the box, -1 = none
  std::vector<Brick> bricks_;
  unsigned box_min_[3]{0, 0, 0};
  unsigned box_bricks_[3]{0, 0, 0};
  std::vector<uint64_t> brick_order_;  // (brick Morton code >> 9) << 24 | brick index
  std::vector<uint64_t> items_;        // (Morton code << 1) | occupied, in octree order
  float hit_logodds_{0.f};
  float miss_logodds_{0.f};
  float clamp_min_{0.f};
  float clamp_max_{0.f};
};

/// Interleaves a key's bits: bit 3·l + a of the code is bit l of key[a], so sorting codes sorts
/// keys in the order of a depth-first walk of the octree (child index x | y << 1 | z << 2).
uint64_t MortonCode(const octomap::OcTreeKey& key);

}  // namespace cairn::mapping::internal
