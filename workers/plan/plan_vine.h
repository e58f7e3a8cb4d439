// SPDX-License-Identifier: Apache-2.0
// The plan stage of one vine: a vine model and its cut plan in, a timed joint trajectory that
// visits every cut it can out. Steps (Botterill et al. 2017 section 3.4, made fast):
//   1. the collision scene of the model and the platform (collision_scene.h);
//   2. a cut motion for every cut, ranked by clearance, slid outward where none is free
//      (cut_motion.h);
//   3. adaptive safety margins around the chosen cut motions (safety_margins.h);
//   4. the order of the cuts and the motion each is made with, together: exact Held-Karp and a
//      dynamic programme over each cut's motions along the order, alternated, on estimated move
//      times with whole-turn shifts (cut_order.h OrderAndChoose, motion_choice.h);
//   5. paths between consecutive cut motions in the inflated scene, one query per cut to all of
//      its alternative motions, cheapest remaining plan first (PathPlanner::PlanToAny: straight
//      segments, then RRT-Connect, shortcut); a query that fails there is run again in the scene
//      without margins (margin_fallback); a cut no path reaches waits for the next pass
//      (retry_unreached), or is dropped in the last one, and the next cut is joined to the last
//      cut reached; a cut from which two transits in a row fail walls the arm in: it is undone
//      once and tried again at the end of the pass;
//   6. passes: cuts with no collision-free cut motion or no path are tried again on the vine as
//      the cuts made so far leave it (their wood has fallen, fallen_wood.h), after those cuts, up
//      to max_passes times -- near the head the canes that block a cut are mostly canes that go.
//      A pass's transits and blends are planned in the vine at its start joined with the stub
//      each of its cuts leaves (collision_scene.h StubChords), which holds the vine after any of
//      them; a cut motion that touches another cut's stub is dropped (a cut left without any
//      waits for the next pass);
//   7. time parameterisation within the joint velocity and acceleration limits, home -> cuts ->
//      home: transits blended through their waypoints where the blends are free (blend.h) and
//      proven free without margins (motion_prover.h), strokes along their dense path, slow only
//      in wood (time_parameterization.h).
// Every transit is accepted only once proven free of its pass's scene without margins
// (motion_prover.h); a cut given up for want of a way home takes the scenes back to the vine as
// the cuts left make it when it was made in an earlier pass than theirs.
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
#include "workers/plan/blend.h"
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
  // head the canes crowd. Eight alternative motions per cut rather than three: on tuning seeds
  // 1110-1199, 66 s of execution per vine instead of 72 s at 1.4 rad/s^2 and fewer failed
  // queries, the same
  // share of cuts planned (docs/plan.md "The plan stage"). At 5 rad/s^2 (s12), 3-6 planned fewer
  // cuts, executed in 35.7-39.9 s, and cost the same CPU per vine (paths dearer by as much).
  CutMotionOptions cut_motion = [] {
    CutMotionOptions o;
    o.alternatives = 8;
    o.max_slide_m = 0.10;
    o.max_tilt_rad = 30.0 * 3.141592653589793 / 180.0;
    o.tilt_steps = 1;
    o.max_roll_rad = 45.0 * 3.141592653589793 / 180.0;
    o.roll_steps = 2;
    return o;
  }();
  // Cuts that no cut motion frees in a pass that plans none (the passes would end there: mostly
  // canes at the head that block each other) are searched once more, sliding up to this far (meant
  // to exceed cut_motion.max_slide_m, else it repeats the pass's search; 0: off), before they are
  // given up. On tuning seeds 1110-1199 (cut motions alone, vb_cut_motion_bench) 48 of 53 such cuts
  // are then planned (40 up to 0.15 m, 29 of them within 0.12 m; 0.15 m until s14); the search runs
  // only for those cuts, so it costs no measurable time (docs/plan.md, "The plan stage" and "Reach,
  // again").
  double last_resort_max_slide_m = 0.20;
  MarginOptions margins;
  // Paths between cuts, one query per cut to all its alternative motions. A path that
  // RRT-Connect does not find in 0.1 s is usually not there (the goals are walled in: 1 s found
  // none of 14 more on tuning seeds 1110-1129).
  PathOptions path = [] {
    PathOptions o;
    o.time_limit_s = 0.1;
    // Trees of 500 states: RRT-Connect's successes on tuning seeds 1110-1149 needed fewer in all
    // but a few percent of queries; failures stop there instead of at the time limit.
    o.max_tree_states = 500;
    // Tree edges checked at 0.03 m, the path found at max_step_m (0.01 m): on tuning seeds
    // 1110-1129 the same paths and outcomes with 23% fewer checks per path.
    o.tree_max_step_m = 0.03;
    // A query like one the pass's planner already failed (same regions) fails at once: each
    // pass has its own planners (docs/plan.md "Paths", remembered failures).
    o.remember_failures = true;
    // Goals walled in: give up once the trees hold 100 states and the goals' at most a tenth
    // (docs/plan.md "Paths"; on tuning seeds 1110-1199 the same cuts planned, -26% checks in
    // failed queries).
    o.walled_in_after_states = 100;
    o.walled_in_goal_fraction = 0.1;
    // Elbow flips to a cut give up at 300 states (the way home keeps 500; docs/plan.md "Paths").
    o.flip_max_tree_states = 300;
    return o;
  }();
  // A transit that finds no path in the scene inflated by the margins is planned again in the
  // scene without them (still collision-free): the margins are a preference (Botterill et al.
  // 2017 section 3.4), and inflating them up to every chosen cut motion can close the corridor
  // between two cuts. false: such a cut is given up.
  bool margin_fallback = true;
  // A cut that no transit reaches (walled in by wood) is tried again in the next pass, on the vine
  // without the wood of the cuts made before it, as cuts with no collision-free motion are.
  bool retry_unreached = true;
  // Each cut's motion (the best, its alternatives and their rolled twins) is chosen jointly with
  // the order (cut_order.h OrderAndChoose) on turn-aware move times (motion_choice.h), and each
  // transit's query tries a cut's motions by the cheapest remaining plan through them
  // (ChooseAlongOrder from where the arm is); false: the order on the best motions, then at each
  // step the motion nearest in move time.
  bool choose_motions_with_order = true;
  // Adds each motion's twin rolled by pi about the tool axis (motion_choice.h RolledTwin) when
  // the tool is symmetric under that roll (RollSymmetric): the same cut, another wrist roll. Off:
  // on tuning seeds 1110-1199 it saved no execution time and doubled the goals of each query
  // (docs/plan.md "Ordering").
  bool rolled_twins = false;
  // A cut from which two transits in a row find no path walls the arm in: it is undone once,
  // the failed cuts are tried again from the cut before, and it goes to the end of the pass's
  // order. false: the failed cuts wait for the next pass (or are given up in the last).
  bool undo_walled_in = true;
  // Where the arm starts and ends: folded clear of the cameras' view (DefaultHome()).
  Joints home = Joints::Zero();
  bool return_home = true;
  // 1: every cut motion is planned on the uncut vine. 6 rather than 3 on tuning seeds 1110-1199:
  // 0.937 -> 0.941 of reachable cuts planned, the same median time (a pass that makes no cut ends
  // the passes, so extra passes cost only where they help).
  int max_passes = 6;
  // The part of a mill-end sweep in wood moves at this fraction of the joint velocity limits:
  // the tool must not be driven through wood at transit speed (an estimate, not a measured feed
  // rate). In wood: TCP within the cane's radius plus cut_feed_margin_m of the cut point (covers
  // the bit's radius and the model's error). The rest of a stroke, and a secateur's approach and
  // retract (its jaws close with the arm at rest at the cut), move at the full limits.
  double cut_speed_fraction = 0.25;
  double cut_feed_margin_m = 0.02;
  // Transits pass their interior waypoints on blends (blend.h) checked in the scene the transit
  // was planned in (margins included), at path.max_step_m; false: the arm stops at each.
  bool blend_transits = true;
  BlendOptions blend;          // its max_step_m is replaced by path.max_step_m
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
  bool without_margins = false;  // planned in the scene without margins (margin_fallback)
  // The query (for baselines to replay): one start, the goals of one PlanToAny (a cut's
  // alternative motions), goal the one reached (the first when none was).
  Joints start = Joints::Zero(), goal = Joints::Zero();
  std::vector<Joints> goals;
  // A path was found but not proven free of the pass's scene without margins
  // (motion_prover.h): outcome kNoPathWithinDeadline, and the query was run again.
  bool unproven = false;
  // No path: RRT-Connect gave up with the goals walled in, or refused a repeat of a failed query
  // (PathResult::walled_in, repeated_failure).
  bool walled_in = false, repeated_failure = false;
  // No path: an elbow flip given up at PathOptions::flip_max_tree_states (PathResult::flip_bound).
  bool flip_bound = false;
};

struct PlanStats {
  double scene_s = 0.0, cut_motions_s = 0.0, margins_s = 0.0, ordering_s = 0.0, paths_s = 0.0,
         timing_s = 0.0, total_s = 0.0;
  // Parts of the stages above: the pass's stubs and the motions that touch them and the last
  // resort (in cut_motions_s), the way home (in paths_s). setup_s is outside every stage:
  // validation, the self-collision checker and the vine without fallen wood between passes.
  double stubs_s = 0.0, last_resort_s = 0.0, home_s = 0.0, setup_s = 0.0;
  int cuts = 0, planned = 0, unreachable = 0;
  int passes = 0;                         // passes that planned at least one cut
  int walled_in_undone = 0;               // cuts undone because they walled the arm in
  int64_t checks = 0;                     // configuration checks in the whole plan
  // Transit timing: interior waypoints, those where the arm stops (a blend collided at every
  // size) and blend halvings.
  int blend_vias = 0, blend_stops = 0, blend_shrinks = 0;
  // Paths found but not proven free (PathRecord::unproven), and blended transits not proven free
  // between their samples, timed to stop at each waypoint instead.
  int unproven_paths = 0, unproven_blends = 0;
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
