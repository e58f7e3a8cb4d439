// SPDX-License-Identifier: Apache-2.0
// Cut motions: for each cut, the joint path that carries the tool through the cane (pre-cut pose
// clear of the cane -> through the cut -> post-cut), collision-free except for the cut cane near
// the cut, with the largest clearance among the sampled tool poses; where none exists, the cut
// slides outward along its cane (bounded). Botterill et al. 2017 section 3.4 (cut motions are
// planned first and bound the rest of the plan). Thread-safe (pure functions; each call builds
// its own checkers).
//
// Pose sampling (tool.h gives the TCP frame): at the cut point p with unit cane tangent d (arm
// base frame), the TCP frame is y = side * d (side = +1 / -1, `approach_sides`), z = the tool axis
// at angle theta about the cane (`orientations` samples of theta over a full turn, theta = 0
// pointing from the arm base toward the cane), x = y cross z; with tilts, the frame is then
// rotated about x by each sampled tilt (the sweep stays across the cane, the cut becomes oblique;
// tilt 0, a perpendicular cut, is sampled first), then about z by each sampled roll (the jaws'
// plane turns about the tool axis; the cut becomes oblique the other way). Rolled poses are tried
// at a cut point only when no unrolled one there gives a free motion. The stroke (tool.h StrokeOf) is
// followed in Cartesian steps of `cartesian_step_m` with IK on the same branch: each step takes
// the IK solution nearest the previous configuration, and a joint jump above
// `max_joint_jump_rad` rejects the branch (the arm would leave the straight TCP line).
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "core/cut_plan.h"
#include "core/deadline.h"
#include "core/vine_model.h"
#include "Eigen/Core"
#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

struct CutMotionOptions {
  int orientations = 16;                // tool-axis angles sampled about the cane, full turn
  int approach_sides = 2;               // 1: TCP y along the cane tangent only; 2: both signs
  double max_tilt_rad = 0.0;            // tool tilt about TCP x (oblique cut), sampled +-
  int tilt_steps = 0;                   // tilts sampled per sign: k * max_tilt_rad / tilt_steps
  double max_roll_rad = 0.0;            // tool roll about TCP z (oblique cut), sampled +-
  int roll_steps = 0;                   // rolls sampled per sign: k * max_roll_rad / roll_steps
  double sweep_m = 0.10;                // mill end: TCP sweep length across the cane, centred
  double approach_m = 0.06;             // secateur: approach (and retract) distance along TCP z
  double cartesian_step_m = 0.005;      // TCP spacing of the configurations along the stroke
  double max_joint_jump_rad = 0.2;      // largest joint change per Cartesian step (continuity)
  double max_slide_m = 0.05;            // how far a cut may slide outward when nothing is free
  double slide_step_m = 0.01;           // slide increment
  double cut_cane_free_radius_m = 0.04; // cut-cane capsules within this of the cut may touch
  double max_step_m = 0.005;            // IsMotionFree resolution between path configurations
  int alternatives = 3;                 // other motions kept per cut (CutMotion::alternatives)
  // A motion's clearance (min over its configurations) must exceed this. Off by default: 1 mm
  // halves the gain of rolls on tuning seeds (docs/plan.md), though the scene's capsules only
  // approximate the canes (a truncated cane is resampled into other capsules).
  double min_clearance_m = 0.0;
  // With approach_sides = 2 and a tool symmetric under a half turn about its axis
  // (motion_choice.h RollSymmetric; joint 6 limits holding [-pi, pi]), the other side's poses are
  // the first side's rolled by pi: sample the first side only and take each free stroke's twin
  // (joint 6 + or - pi) as the other side's, with the same clearance (half the work; the motions
  // are those of both sides up to rounding). false: sample and check both sides. The twin is not
  // checked again, which is exact for checkers of capsule models (RollSymmetric compares them);
  // PlanVine turns it off for CheckerKind::kFclMesh, whose tessellation the roll does not map
  // onto itself.
  bool share_rolled_twins = true;

  // INVALID_ARGUMENT naming the field ("options.sweep_m: ..."): counts < 1 (sides > 2, tilt_steps
  // or roll_steps < 0, alternatives < 0), max_tilt_rad or max_roll_rad outside [0, pi/2),
  // non-finite or non-positive lengths (max_slide_m and min_clearance_m may be 0), slide_step_m > 0
  // when sliding.
  absl::Status Validate() const;
};

enum class CutMotionOutcome {
  kPlanned,                // path holds a collision-free cut motion
  kUnreachable,            // no sampled cut pose has an IK solution within limits, at any slide
  kNoCollisionFreeMotion,  // cut poses are reachable, but no whole stroke is free, at any slide
  kInvalidInput,           // bad options, robot, or cut (message names it)
  kDeadline,               // the deadline expired before this cut was planned
};
std::string_view CutMotionOutcomeName(CutMotionOutcome outcome);  // "planned", "unreachable", ...

struct CutMotion {
  CutId cut_id;
  CutMotionOutcome outcome = CutMotionOutcome::kInvalidInput;
  std::string message;
  // Pre-cut (tool clear of the cane) -> through the cut -> post-cut; consecutive configurations
  // are one Cartesian step apart and their straight joint interpolation passed IsMotionFree.
  // Empty unless planned.
  std::vector<Joints> path;
  // Other collision-free motions for the same (slid) cut point, by decreasing clearance, whose cut
  // configurations differ from the path's and from each other by >= 0.5 rad in some joint: the
  // planner tries them when no path reaches `path` (e.g. an arm threaded behind the wires).
  std::vector<std::vector<Joints>> alternatives;
  int cut_index = -1;              // path[cut_index] puts the TCP on the (slid) cut point
  double clearance_m = 0;          // min Clearance() over the path configurations (ranking key)
  double slid_m = 0;               // how far the cut point moved outward along the cane
  Eigen::Vector3d cut_point_in_platform = Eigen::Vector3d::Zero();  // after sliding
};

// Builds the checker for one scene (MakePrimitiveChecker by default; an FCL checker for
// baselines). Must not return null. PlanCutMotions calls it once on the whole scene; when that
// returns a PrimitiveChecker, every cut and slide reuses it with the cut cane near the cut left
// out (PrimitiveChecker::Exclude, the same answers), otherwise it is called again per slide on
// scene.WithoutCaneNear(...).
using CheckerFactory = std::function<std::unique_ptr<CollisionChecker>(const RobotModel&,
                                                                      const CollisionScene&)>;

// One CutMotion per cut, in order. For each cut: sample TCP poses about the cane, solve IK (all
// branches), follow the stroke, and check every configuration and motion with a checker on
// scene.WithoutCaneNear(cut cane, cut point, cut_cane_free_radius_m) -- with a secateur, whose
// cane lies between the open jaws, the flange bodies must also stay clear of the cut cane's
// capsules left out there, at every stroke pose (exact test); keep the collision-free
// motion with the largest clearance. If none, slide the cut outward (toward the tip) along the
// cane of `model` by slide_step_m up to max_slide_m, the cane's tip, and short of the base of the
// first child of the cut cane beyond the cut (which falls with the cut as given, and would stay
// on the vine past it; the child's base projected onto the cane), and report slid_m.
// `scene` is in the arm base frame (robot.platform_from_arm_base maps base -> platform); cuts and
// `model` are in the platform frame. Invalid options or robot: every cut kInvalidInput. A cut with
// non-finite numbers, a non-unit direction, or a cane id absent from `model`: that cut
// kInvalidInput. Once `deadline` expires, the current and later cuts are kDeadline.
std::vector<CutMotion> PlanCutMotions(const RobotModel& robot, const VineModel& model,
                                      const CollisionScene& scene, std::span<const Cut> cuts,
                                      const CutMotionOptions& options, const Deadline& deadline);
std::vector<CutMotion> PlanCutMotions(const RobotModel& robot, const VineModel& model,
                                      const CollisionScene& scene, std::span<const Cut> cuts,
                                      const CutMotionOptions& options, const Deadline& deadline,
                                      const CheckerFactory& make_checker);

// The sampled TCP frames of a cut at `point` with unit cane tangent `direction` (both in the arm
// base frame), in sampling order (orientation-major, then side); see the convention above.
std::vector<Eigen::Isometry3d> SampleCutPoses(const Eigen::Vector3d& point,
                                              const Eigen::Vector3d& direction,
                                              const CutMotionOptions& options);

// The TCP positions of the stroke of `stroke` in the TCP frame of the cut pose, in path order;
// `cut_index` receives the index of the cut point (the origin). Exposed for tests and the
// trajectory writer.
std::vector<Eigen::Vector3d> StrokeWaypoints(CutStroke stroke, const CutMotionOptions& options,
                                             int* cut_index);

}  // namespace vb::plan
