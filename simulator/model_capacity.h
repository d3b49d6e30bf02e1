#pragma once

#include <string>

#include <mujoco/mujoco.h>

/// @file
/// Sizing a composed scene's MuJoCo 2.2 buffers (<size nconmax njmax nstack>) for what it holds.
///
/// MuJoCo 2.2 allocates mjData once, for the model's nconmax contacts and njmax constraint rows,
/// and some of its arrays are njmax x njmax (efc_AR and its column indices, 12 bytes a cell,
/// zeroed at allocation); left to itself its compiler also makes the stack 5 (njmax + nv)^2
/// numbers. A fixed allowance per robot (formerly 300 contacts and 1800 rows) therefore grows
/// with the square of the robot count: six Pioneers took 1.7 GB of zeroed memory (seconds of
/// page faults at start) and eight could not be allocated at all ("could not create mjData").
///
/// `ContactCapacity` bounds what the scene can use from its compiled model instead: every geom
/// on a body with joints (a robot, a door) that collides touches at most
/// `kSimultaneousPartners` other geoms at once, each pair making at most the contacts MuJoCo
/// 2.2's collision function for those two types makes (one for a sphere on anything but a height
/// field, up to 8 for a box on a box or a plane, up to one per prism under the geom on a height
/// field, never above mjMAXCONPAIR); each contact takes the rows of its friction cone (1 for
/// condim 1, else 2 (condim - 1), the pyramid's count, which is never below the elliptic
/// cone's); joint and tendon limits, friction loss and equality constraints add theirs. The
/// spawn pool's parked geoms count as boxes that collide with everything (they become such at
/// run time). The stack follows MuJoCo's own compile-time rule, applied to that njmax.

namespace cairn::sim {

/// Other geoms one moving geom is assumed to touch at the same time (a wheel in a corner: the
/// floor, two walls and another robot).
inline constexpr int kSimultaneousPartners = 4;

struct ModelCapacity {
  int nconmax{0};  ///< contacts
  int njmax{0};    ///< constraint rows
  int nstack{0};   ///< mjtNum of mjData's stack
};

/// The buffers `m` needs (see the file comment). Never below MuJoCo's defaults (100 contacts,
/// 500 rows), so a scene without robots keeps what it had.
/// @param parked_geom_group geoms of this group are spawn-pool slots (boxes at run time).
ModelCapacity ContactCapacity(const mjModel* m, int parked_geom_group);

/// MuJoCo 2.2's compile-time stack size for a model with `njmax` rows (its compiler's rule when
/// <size nstack> is not given): max(1000, 5 (njmax + neq + nv)^2 + 20 (sum of the model's other
/// sizes)).
int MujocoStackHeuristic(const mjModel* m, int njmax);

/// The <size> attributes (nconmax, njmax, nstack) MJCF text already sets, each true when set.
struct SizeAttributes {
  bool nconmax{false}, njmax{false}, nstack{false};
  bool any() const { return nconmax || njmax || nstack; }
};
SizeAttributes SizeAttributesOf(const std::string& xml);

/// `xml` with the given sizes in its <size> element (one is added after <mujoco> when there is
/// none), except those `keep` says the text sets already; a negative value is not written.
std::string WithSizes(const std::string& xml, const ModelCapacity& sizes,
                      const SizeAttributes& keep);

}  // namespace cairn::sim
