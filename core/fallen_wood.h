// SPDX-License-Identifier: Apache-2.0
// What falls when a cane is cut: the cane's part beyond the cut and every cane growing from that
// part, with all their descendants. The one rule behind the simulator's world update
// (sim/world.h, what a re-capture shows) and the planner's vine after its cuts
// (workers/plan/fallen_wood.h, what later motions need not avoid). Decide keeps its own reading
// of which canes a decided cut removes (workers/decide: pruning weight, cut placement), which
// never cuts the trunk. Thread-safe (pure functions).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "core/ids.h"
#include "core/vine_model.h"

namespace vb {

struct FallingWood {
  // Canes that fall whole, each once: the cut cane first when the cut leaves less than
  // kMinCaneStubM of it, then the cut cane's children that fall with the cut, then all their
  // descendants.
  std::vector<CaneId> canes;
  bool cut_cane_whole = false;  // the cut cane is the first of `canes`
  bool head = false;            // the head falls too (its spheres go)
};

// The wood that falls when cane `index` of `vine` is cut `arc_length_m` along its axis from its
// base. A child falls when its base projects onto the cut cane's axis beyond the cut (all children
// fall when the cut cane falls whole). A child of the trunk whose base lies off the trunk's axis
// (farther than the trunk's radius there + 1 mm: a cane of the head) hangs on the trunk's top, and
// a cut of the trunk more than kMinCaneStubM below its top drops the head with those canes.
// Requires index < vine.canes.size().
FallingWood WoodFallingFromCut(const VineModel& vine, size_t index, double arc_length_m);

// Applies cuts given as (cane index, arc length) pairs to `vine`: on each cane the lowest cut
// decides; each cut's falling wood (WoodFallingFromCut on the vine before any cut) is removed, cut
// canes that do not fall are truncated there (Polyline3::TruncateAt), and the head's spheres are
// cleared when it falls. Indices outside `vine.canes` are ignored. The result passes
// VineModel::Validate() if `vine` does. `falls`, if given, receives each cane's lowest cut's
// FallingWood (one per cut cane, in no set order).
VineModel AfterCuts(const VineModel& vine, const std::vector<std::pair<size_t, double>>& cuts,
                    std::vector<FallingWood>* falls = nullptr);

}  // namespace vb
