// SPDX-License-Identifier: Apache-2.0
// Internal to the cut-motion search (cut_motion.cc): one stroke followed from a cut
// configuration through the IK, its half-turn twin, and its evaluation (every motion free, the
// min clearance). Not for other users; cut_motion.h states the stage's contract.
#pragma once

#include <optional>
#include <vector>

#include "Eigen/Geometry"

#include "workers/plan/collision_checker.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/primitive_checker.h"
#include "workers/plan/robot_model.h"

namespace vb::plan::stroke {

// One reachable, collision-free configuration at the cut pose: where a stroke may start.
struct Candidate {
  Joints q;
  double clearance_m = 0;  // Clearance(q), computed once its stroke is known to be free
  Eigen::Isometry3d base_from_tcp;
  int pose = 0;    // index of the sampled cut pose
  int branch = 0;  // IK branch of q (IkSolutions::branch)
};

// Half-turn twins. With approach_sides = 2, the pose sampled on the other side of the cane is a
// sampled pose rolled by pi about the TCP z axis (y -> -y, x -> -x, z kept; the other side at
// tilt +t is the first side at tilt -t, same orientation and roll, bit for bit: SampleCutPoses).
// When the bodies the flange carries are symmetric under that roll and the TCP is on the flange
// axis (motion_choice.h RollSymmetric), the other side's IK solutions are the first side's with
// joint 6 turned by pi, and every configuration, motion and clearance of the twin is the same
// geometry as the original's: the arm below the flange does not move, and the flange bodies map
// onto each other. So only the first side is sampled, and each of its strokes stands for its
// twin too (found, checked and ranked once).
struct TwinMap {
  bool on = false;
  std::vector<int> waypoint;  // waypoint[i]: the twin's index of the TCP at waypoints[i]
};

// The twin waypoint map of `waypoints` (off unless options.share_rolled_twins, two approach
// sides, a roll-symmetric flange (RollSymmetric) and joint 6 limits holding [-pi, pi]).
TwinMap MakeTwinMap(const RobotModel& robot, const CutMotionOptions& options,
                    const std::vector<Eigen::Vector3d>& waypoints);

// The twin of a free stroke `path` (see TwinMap): joint 6 turned by pi toward 0 at the cut, the
// same turn along the stroke (the IK's nearest solution keeps it: steps are far below pi), in the
// twin's waypoint order. False where a configuration leaves the joint limits (the IK then has no
// continuous solution either).
bool TwinPath(const TwinMap& map, const std::vector<Joints>& path, int cut_index,
              const JointLimits& limits, std::vector<Joints>* twin);

// How FollowStroke ended: every configuration free, no continuous IK solution, or a collision.
enum class StrokeResult { kFree, kNoIk, kCollides };

// Follows the stroke from the cut configuration outward in both directions, each step on the IK
// solution nearest the previous configuration, checking each configuration as it goes (IK costs
// more than a check, so a collision stops the walk early). kNoIk on a missing solution or a jump.
// With a `mirrored` stroke (retract = approach reversed, IsMirrored) the walk out of the cut
// toward the end retraces the walk toward the start step for step (same waypoints, same nearest
// solutions), so only the first half is walked and copied.
StrokeResult FollowStroke(const Candidate& start, const std::vector<Eigen::Vector3d>& waypoints,
                          int cut_index, bool mirrored, const Eigen::Isometry3d& tcp_from_flange,
                          const JointLimits& limits, double max_jump, CollisionChecker& checker,
                          std::vector<Joints>* path);

// Min clearance over `path` (whose configurations are free; path[cut_index]'s clearance is
// `cut_clearance`) if it stays above `must_beat` and every motion between consecutive
// configurations is free; nullopt otherwise (it cannot win). A mirrored path's second half
// repeats its first (the same configurations, the same motions reversed): only the first half and
// the cut are evaluated.
std::optional<double> EvaluatePath(CollisionChecker& checker, PrimitiveChecker* primitive,
                                   const std::vector<Joints>& path, int cut_index, bool mirrored,
                                   double cut_clearance, double must_beat, double max_step_m);

// True if the stroke returns the way it came: waypoints[cut_index + j] == waypoints[cut_index - j]
// for every j, and it ends where it started (the secateur's approach and retract).
bool IsMirrored(const std::vector<Eigen::Vector3d>& waypoints, int cut_index);

}  // namespace vb::plan::stroke
