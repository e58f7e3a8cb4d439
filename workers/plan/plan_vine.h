// SPDX-License-Identifier: Apache-2.0
// The plan stage of one vine: a vine model and its cut plan in, a timed joint trajectory that
// visits every cut it can out. Steps (Botterill et al. 2017 section 3.4, made fast):
//   1. the collision scene of the model and the platform (collision_scene.h);
//   2. a cut motion for every cut, ranked by clearance, slid outward where none is free
//      (cut_motion.h);
//   3. adaptive safety margins around the chosen cut motions (safety_margins.h);
//   4. the order of the cuts: exact Held-Karp on estimated move times (cut_order.h);
//   5. RRT-Connect paths between consecutive cut motions in the inflated scene, shortcut
//      (path_planner.h); a cut whose path fails is dropped and the next one is joined to the last
//      cut reached;
//   6. passes: cuts with no collision-free cut motion are tried again on the vine as the cuts
//      made so far leave it (their wood has fallen, fallen_wood.h), after those cuts, up to
//      max_passes times -- near the head the canes that block a cut are mostly canes that go;
//   7. time parameterisation within the joint velocity and acceleration limits
//      (time_parameterization.h), home -> cuts -> home.
// Every cut ends planned or with its reason in Trajectory::unplanned. Thread-safe (pure function).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/deadline.h"
#include "core/trajectory.h"
#include "core/vine_model.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/path_planner.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/safety_margins.h"

namespace vb::plan {

enum class CheckerKind { kPrimitives, kFclPrimitives, kFclMesh };
std::string_view CheckerKindName(CheckerKind kind);  // "primitives", "fcl_primitives", "fcl_mesh"
std::unique_ptr<CollisionChecker> MakeChecker(CheckerKind kind, const RobotModel& robot,
                                              const CollisionScene& scene);

struct PlanOptions {
  CheckerKind checker = CheckerKind::kPrimitives;  // the fast one; FCL for baselines
  SceneOptions scene;
  // Cut motions as tuned on simulated vines (tuning seeds 1110-1129, docs/plan.md): a cut may
  // slide up to 0.10 m outward and be oblique by up to 30 degrees (tilt) when no perpendicular
  // one is free, and the tool may roll about its axis by up to 45 degrees (two steps) where no
  // unrolled pose is free at a slide; oblique cuts heal as well on dormant canes, and near the
  // head the canes crowd. (More alternative motions per cut plan more cuts, but pick motions
  // that graze canes; docs/plan.md "Cut motions".)
  CutMotionOptions cut_motion = [] {
    CutMotionOptions o;
    o.max_slide_m = 0.10;
    o.max_tilt_rad = 30.0 * 3.141592653589793 / 180.0;
    o.tilt_steps = 1;
    o.max_roll_rad = 45.0 * 3.141592653589793 / 180.0;
    o.roll_steps = 2;
    return o;
  }();
  MarginOptions margins;
  // Paths between cuts. A path that RRT-Connect does not find in 0.1 s is usually not there (the
  // goal is walled in: 1 s finds 1 more of 11 on tuning seeds); the cut's alternative motions
  // are tried next.
  PathOptions path = [] {
    PathOptions o;
    o.time_limit_s = 0.1;
    return o;
  }();
  // Where the arm starts and ends: folded clear of the cameras' view (DefaultHome()).
  Joints home = Joints::Zero();
  bool return_home = true;
  int max_passes = 3;          // 1: every cut motion is planned on the uncut vine
  // Cut strokes move at this fraction of the joint velocity and acceleration limits: the tool
  // must not be driven through wood at transit speed (an estimate, not a measured feed rate).
  double cut_speed_fraction = 0.25;
  double sample_dt_s = 0.05;   // trajectory samples at most this far apart (waypoints always kept)
  // INVALID_ARGUMENT naming the field ("options.path.time_limit_s: ...").
  absl::Status Validate() const;
};

// The arm's parking configuration for the default mount (robot_model.h).
Joints DefaultHome();

// One path between two consecutive configurations of the plan (timing of step 5).
struct PathRecord {
  CutId to_cut;               // 0 for the path back home
  PathOutcome outcome = PathOutcome::kSolved;
  double planning_s = 0.0;
  int64_t checks = 0;
  bool direct = false;        // the straight line was free
  Joints start = Joints::Zero(), goal = Joints::Zero();  // the query (for baselines to replay)
};

struct PlanStats {
  double scene_s = 0.0, cut_motions_s = 0.0, margins_s = 0.0, ordering_s = 0.0, paths_s = 0.0,
         timing_s = 0.0, total_s = 0.0;
  int cuts = 0, planned = 0, unreachable = 0;
  int passes = 0;                         // passes that planned at least one cut
  int64_t checks = 0;                     // configuration checks in the whole plan
  std::vector<PathRecord> paths;
  MarginSummary margins;
  // Estimated move time (s) of the transits in the chosen order, the given order and the
  // nearest-neighbour order, all on the same estimates; order_exact: Held-Karp (not heuristic).
  double order_cost_s = 0.0, given_order_cost_s = 0.0, nearest_neighbour_cost_s = 0.0;
  bool order_exact = true;
  std::vector<std::string> notes;         // e.g. "cut 4: slid 0.02 m outward along cane 7"
};

struct PlanResult {
  Trajectory trajectory;
  // The planned cuts as they will be made: a slid cut's point is where the tool cuts.
  std::vector<Cut> cuts;
  PlanStats stats;
};

// INVALID_ARGUMENT naming the field for an invalid model, plan (CutPlan::ValidateAgainst), robot,
// platform or options, or a home configuration outside the limits; FAILED_PRECONDITION if the home
// configuration is in collision. Everything that goes wrong with one cut is that cut's outcome in
// trajectory.unplanned, not an error. DEADLINE_EXCEEDED / CANCELLED only if the deadline expires
// before any trajectory exists; once cut motions exist, cuts not reached in time are unplanned
// with reason "no_path_within_deadline".
absl::StatusOr<PlanResult> PlanVine(const VineModel& model, const CutPlan& plan,
                                    const RobotModel& robot, const PlatformGeometry& platform,
                                    const PlanOptions& options = {},
                                    const Deadline& deadline = Deadline::Infinite());

}  // namespace vb::plan
