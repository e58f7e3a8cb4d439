// SPDX-License-Identifier: Apache-2.0
// A simulated expert cane pruner: a fixed, documented rule set that decides which canes of a vine
// to keep and which to leave as spurs, used to label simulated vines for learning the decide
// stage's cost weights (workers/decide/scheme_learning.h; docs/decide.md "Expert rule set").
//
// The rules are what a skilled cane pruner does, after Botterill et al., "A Robot System for
// Pruning Grape Vines" (J. Field Robotics 2017) section 3.3, Corbett-Davies et al., "An expert
// system for automatically pruning vines" (IVCNZ 2012) and Saxton et al., "First steps in
// translating human cognitive processes of cane pruning grapevines into AI rules" (BIO Web of
// Conferences 3, 2014). They are deliberately *rules*, applied in order (lexicographically), not
// a weighted sum: the learner has to recover them from examples, as it will have to recover a
// human pruner's choices from tablet approvals.
//
// What the pruner measures of each cane of kind `cane` (trunk and old spurs are never chosen):
//   origin      head: the parent is the trunk (or an old spur) and the base is on the head
//               (within kExpertHeadContactM of a head sphere's surface or above the head's
//               lowest point; within kExpertTrunkTopHeadM of the trunk top if the model has no
//               head spheres);
//               trunk: any other cane growing from the trunk (a water shoot);
//               cane: grows from another cane (a secondary cane).
//   diameter    mean diameter over the first 0.10 m; `diameter_outside_mm` is its distance outside
//               the policy's preferred range [cane_diameter_min_m, cane_diameter_max_m], in mm.
//   side        -1 if the base lies left of the head centre (smaller x), +1 otherwise. The head
//               centre is the mean of the head spheres' centres (the trunk's top without them).
//   wire        the fruiting wire height: policy.fruiting_wire_z_m, else the lowest wire of the
//               model at the head centre's x, else 0.95 m.
//   direction   the initial direction (base to the point 0.10 m along the cane); its angle from
//               the along-row direction pointing away from the head on the base's side.
//
// Rules, cane style (policy.style == kCane), for k = policy.canes_to_keep kept canes:
//   K1 Only canes at least policy.min_kept_length_m long are kept.
//   K2 Balance: the canes are laid along the wire both ways, so the pruner alternates sides: each
//      pick is made on the side with fewer kept canes if that side has an eligible cane, else on
//      either side. When both sides have as many, the better cane of either side is taken.
//   K3 Within the allowed side(s), canes are ranked lexicographically by:
//      a. origin: head, then water shoot, then secondary cane (a water shoot sits low on the trunk
//         and a secondary cane falls with its parent);
//      b. diameter: distance outside the preferred range (in range is best; otherwise the nearest
//         to it: too thin is weak, too thick is vegetative and hard to bend);
//      c. reach: how far the cane falls short of policy.max_kept_length_m (a cane long enough to
//         fill the wire to the next vine is best; longer ones are shortened anyway);
//      d. height of the base above the wire (0 below it: a base above the wire must be bent down
//         onto it, which cracks canes);
//      e. placement, the pruner's judgement of how well the cane lies for tying down: the angle
//         (rad) from the outward wire direction it must be bent through plus
//         kExpertRadPerMetreFromHead x its base distance from the head centre (a base near the
//         head keeps the head compact; 1 cm counts as much as 0.1 rad, about 6 degrees, of bend);
//      f. cane id (a deterministic tie-break).
//   K4 A cane is never picked if it descends from, or is an ancestor of, a cane already kept or
//      spurred (one would fall with the other's cut).
// Spurs (both styles), n = policy.spurs, picked after the kept canes among the remaining canes at
// least policy.spur_length_m long that satisfy K4, ranked by: a. origin (as K3a: renewal spurs
// belong on the head); b. diameter outside the preferred range (a healthy spur); c. base distance
// from the head centre (spurs low and close to the trunk keep the head from creeping outward);
// d. cane id. Spurs are not balanced by side.
//
// If fewer canes are eligible than the policy asks for, all eligible ones are taken and a note
// says so. Deterministic; thread-safe (pure functions).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/ids.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"

namespace vb::sim {

inline constexpr double kExpertHeadContactM = 0.03;    // base within this of the head: from the head
inline constexpr double kExpertTrunkTopHeadM = 0.10;   // the head's reach when it has no spheres
inline constexpr double kExpertBaseSpanM = 0.10;       // diameter and direction are measured over this
inline constexpr double kExpertRadPerMetreFromHead = 10.0;  // placement (rule K3e): 1 cm = 0.1 rad
inline constexpr double kExpertDefaultWireZM = 0.95;   // fruiting wire height if nothing says

enum class ExpertOrigin { kHead = 0, kTrunk = 1, kCane = 2 };

// What the expert sees of one cane of kind `cane`.
struct ExpertCaneView {
  CaneId id;
  ExpertOrigin origin = ExpertOrigin::kHead;
  double length_m = 0.0;
  double base_diameter_m = 0.0;
  double diameter_outside_mm = 0.0;         // 0 inside the policy's preferred range
  double base_distance_from_head_m = 0.0;
  double base_below_wire_m = 0.0;           // wire_z - base_z (negative: above the wire)
  double angle_from_wire_rad = 0.0;         // in [0, pi]
  int side = 1;                             // -1 left of the head centre, +1 right
  double placement_rad = 0.0;               // rule K3e: angle + kExpertRadPerMetreFromHead x distance
  std::vector<CaneId> ancestors;            // canes (not the trunk) it grows from, nearest first
};

struct ExpertDecision {
  std::vector<CaneId> keep;   // sorted by id
  std::vector<CaneId> spurs;  // sorted by id
  // What a supervisor should know ("only 1 cane at least 0.30 m long; policy asks for 2").
  std::vector<std::string> notes;
};

// The expert's measurements of every cane of kind `cane`, in model order.
// INVALID_ARGUMENT if the model fails VineModel::Validate, has no trunk, or the policy fails
// PruningPolicy::Validate (the message names the field).
absl::StatusOr<std::vector<ExpertCaneView>> AssessCanes(const VineModel& model,
                                                        const PruningPolicy& policy);

// The expert's decision for `model` under `policy` (rules above). Errors as AssessCanes.
absl::StatusOr<ExpertDecision> ExpertPrune(const VineModel& model, const PruningPolicy& policy);

}  // namespace vb::sim
