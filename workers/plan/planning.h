// SPDX-License-Identifier: Apache-2.0
// Internal to PlanVine (plan_vine.cc): what its passes share -- the legs planned so far (transit
// and cut motion of each cut), the scenes, checkers and path planners of the pass in use, and the
// transit queries made in them (in the scene with margins, then without, each path accepted only
// once proven free of the scene without margins, motion_prover.h). Not thread-safe (one per
// PlanVine call).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/cut_plan.h"
#include "core/deadline.h"
#include "core/vine_model.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/motion_prover.h"
#include "workers/plan/path_planner.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"

namespace vb::plan {

// Seconds since `since` (steady clock).
double Seconds(std::chrono::steady_clock::time_point since);

// A planned cut: the transit that reaches it and its cut motion.
struct Leg {
  std::vector<Joints> transit;
  CutMotion motion;
  Cut cut;  // as made (a slid cut's point is where the tool cuts)
  std::shared_ptr<CollisionChecker> checker;  // the transit's scene (blends are checked in it)
  std::shared_ptr<MotionProver> proof;  // that scene without margins (blends proven in it)
  int pass = 0;                         // PlanStats::passes when it was planned
};

// Edges of paths planned again when a path found at options.path.max_step_m is not proven free.
constexpr double kFineStepM = 0.002;

// What the passes share.
struct Planning {
  const VineModel& vine;  // uncut
  const CutPlan& plan;
  const RobotModel& robot;
  const PlatformGeometry& platform;
  const PlanOptions& options;
  const Deadline& deadline;
  PlanResult& result;
  std::vector<Leg> legs;
  // The scene of the uncut vine, built once for the home check and taken by the first pass.
  std::optional<CollisionScene> uncut_scene;
  // The last pass's inflated scene, its checker and its path planner (for the way home).
  std::shared_ptr<CollisionChecker> checker;
  std::unique_ptr<PathPlanner> planner;
  // The same pass's scene without margins; its checker (which proves paths free) is built at the
  // pass's first transit, its planner at the first that needs it (options.margin_fallback).
  std::optional<CollisionScene> plain_scene;
  std::shared_ptr<CollisionChecker> plain_checker;
  std::unique_ptr<PathPlanner> plain_planner;
  std::unique_ptr<PathPlanner> fine_planner;  // the same at kFineStepM, for unproven paths
  std::shared_ptr<MotionProver> prover;        // proves transits free of the same scene
  std::unique_ptr<CollisionChecker> self_checker;  // the arm alone (ShiftedForReach)
  // The scenes in use take every leg of the passes before this one as made (and hold the stubs
  // of this one's).
  int scene_pass = 0;
  // The last resort (PlanOptions::last_resort_max_slide_m) has searched the blocked cuts once.
  bool last_resort_used = false;

  const Joints& At() const { return legs.empty() ? options.home : legs.back().motion.path.back(); }

  void UsePassScenes(const CollisionScene& plain, const CollisionScene& inflated);

  // A transit from where the arm is to any of `goals` (one query, PlanToAny): in the inflated
  // scene, then, if no path is found there, in the scene without margins. A path is accepted only
  // once proven free of the pass's scene without margins (MotionProver: the planners check
  // edges at max_step_m, between which an edge may cross a cane by a fraction of a millimetre);
  // one that is not is tried again without margins, then at a finer step. Every query is
  // recorded (an unproven path as no path, PathRecord::unproven).
  struct Reached {
    std::vector<Joints> waypoints;
    int goal_index = 0;
    std::shared_ptr<CollisionChecker> checker;  // of the scene the path was found in
    std::shared_ptr<MotionProver> proof;        // the pass's scene without margins
  };
  std::optional<Reached> Path(std::vector<Joints> goals, CutId to);

  // A solved path whose waypoint segments are not proven free becomes kNoPathWithinDeadline
  // (unproven); the proof's time and checks count as the query's. `sampled`: found by `planner`
  // (its segments sampled in the inflated scene, MotionProver::IsSampledPathFree).
  struct ProvenPath : PathResult {
    bool unproven = false;
  };
  void Prove(ProvenPath& path, bool sampled = false);

  void Record(const ProvenPath& path, CutId to, const std::vector<Joints>& goals, bool plain);

  void Unplanned(CutId id, std::string_view reason) {
    result.trajectory.unplanned.push_back({id, std::string(reason)});
  }
};


}  // namespace vb::plan
