// A core file that includes a generated LCM type. It is compiled by the CTest
// include_rule.core_library_cannot_see_lcm_types, which passes only when the compiler refuses it:
// core libraries do not link cairn::lcmtypes, so the generated headers are out of their reach.
#include "cairn/lcmt_pose.hpp"

int IncludeRuleProbe() { return static_cast<int>(sizeof(cairn::lcmt_pose)); }
