// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/cut_stroke.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "workers/plan/motion_choice.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan::stroke {
namespace {

double MaxJointChange(const Joints& a, const Joints& b) { return (a - b).cwiseAbs().maxCoeff(); }

// The IK solution for the TCP at `waypoint` (TCP frame of the cut) nearest `previous`, if it is
// within `max_jump` of it in every joint; *branch: previous's IK branch in, the solution's out.
// The solution on previous's branch is tried first: when it is within c <= max_jump of previous
// and every other branch is more than 2c from it (InverseKinematicsBranch's bound), every other
// solution is more than c from previous, so it is the one the search over all solutions picks,
// bit for bit; otherwise all branches are solved and searched.
std::optional<Joints> NearestSolution(const Candidate& start, const Eigen::Vector3d& waypoint,
                                      const Eigen::Isometry3d& tcp_from_flange,
                                      const JointLimits& limits, const Joints& previous,
                                      double max_jump, int* branch) {
  Eigen::Isometry3d base_from_tcp = start.base_from_tcp;
  base_from_tcp.translation() += start.base_from_tcp.linear() * waypoint;
  const Eigen::Isometry3d base_from_flange = base_from_tcp * tcp_from_flange;
  Joints same_branch;
  double apart = 0;
  if (InverseKinematicsBranch(base_from_flange, limits, &previous, *branch, &same_branch,
                              &apart)) {
    const double change = MaxJointChange(same_branch, previous);
    if (change <= max_jump && apart > 2 * change + 1e-9) return same_branch;
  }
  const IkSolutions ik = InverseKinematics(base_from_flange, limits, &previous);
  int best = -1;
  double best_change = max_jump;
  for (int k = 0; k < ik.count; ++k) {
    const double change = MaxJointChange(ik.q[k], previous);
    if (change <= best_change) {
      best_change = change;
      best = k;
    }
  }
  if (best < 0) return std::nullopt;
  *branch = ik.branch[best];
  return ik.q[best];
}

}  // namespace

TwinMap MakeTwinMap(const RobotModel& robot, const CutMotionOptions& options,
                    const std::vector<Eigen::Vector3d>& waypoints) {
  TwinMap map;
  if (!options.share_rolled_twins || options.approach_sides != 2 || !RollSymmetric(robot))
    return map;
  // Joint 6 takes q6 + pi or q6 - pi, whichever is within [-pi, pi] like the IK's nearest-0
  // choice at the cut; the limits must hold that whole range (a stroke drifting past them is
  // checked per configuration).
  if (robot.limits.lower[5] > -M_PI || robot.limits.upper[5] < M_PI) return map;
  // The twin's waypoint i is at the original's rolled TCP offset (-x, -y, z): the same index for
  // the secateur's stroke along z, the reversed one for the mill end's sweep along x.
  // A waypoint that the roll leaves in place keeps its index (the secateur's retract repeats its
  // approach: the first match would be the approach's); the map must be one to one.
  const int n = static_cast<int>(waypoints.size());
  map.waypoint.assign(n, -1);
  std::vector<char> used(n, 0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d rolled(-waypoints[i].x(), -waypoints[i].y(), waypoints[i].z());
    if (waypoints[i] == rolled) map.waypoint[i] = i;
    for (int j = 0; j < n && map.waypoint[i] < 0; ++j) {
      if (waypoints[j] == rolled && !used[j]) map.waypoint[i] = j;
    }
    if (map.waypoint[i] < 0 || used[map.waypoint[i]]) return TwinMap{};
    used[map.waypoint[i]] = 1;
  }
  map.on = true;
  return map;
}

bool TwinPath(const TwinMap& map, const std::vector<Joints>& path, int cut_index,
              const JointLimits& limits, std::vector<Joints>* twin) {
  const double turn = path[cut_index][5] > 0 ? -M_PI : M_PI;
  twin->resize(path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    Joints q = path[i];
    q[5] += turn;
    if (q[5] < limits.lower[5] || q[5] > limits.upper[5]) return false;
    (*twin)[map.waypoint[i]] = q;
  }
  return true;
}

StrokeResult FollowStroke(const Candidate& start, const std::vector<Eigen::Vector3d>& waypoints,
                          int cut_index, bool mirrored, const Eigen::Isometry3d& tcp_from_flange,
                          const JointLimits& limits, double max_jump, CollisionChecker& checker,
                          std::vector<Joints>* path) {
  // Cheap rejection first: the stroke's two ends, reached directly from the cut configuration
  // (the nearest solution there is the one the walk would reach on a regular branch; a miss here
  // only drops a candidate, it never admits a colliding one).
  const int last = static_cast<int>(waypoints.size()) - 1;
  for (int end : {0, last}) {
    if (end == cut_index || (mirrored && end == last)) continue;
    const double allowed = max_jump * std::abs(end - cut_index);
    int branch = start.branch;
    const auto q = NearestSolution(start, waypoints[end], tcp_from_flange, limits, start.q,
                                   allowed, &branch);
    if (q.has_value() && !checker.IsFree(*q)) return StrokeResult::kCollides;
  }
  path->assign(waypoints.size(), start.q);
  for (int direction : {1, -1}) {
    if (mirrored && direction == 1) continue;
    Joints previous = start.q;
    int branch = start.branch;
    for (int i = cut_index + direction; i >= 0 && i <= last; i += direction) {
      const auto q = NearestSolution(start, waypoints[i], tcp_from_flange, limits, previous,
                                     max_jump, &branch);
      if (!q.has_value()) return StrokeResult::kNoIk;
      if (!checker.IsFree(*q)) return StrokeResult::kCollides;
      previous = *q;
      (*path)[i] = previous;
    }
  }
  if (mirrored) {
    for (int j = 1; cut_index + j <= last; ++j) (*path)[cut_index + j] = (*path)[cut_index - j];
  }
  return StrokeResult::kFree;
}

std::optional<double> EvaluatePath(CollisionChecker& checker, PrimitiveChecker* primitive,
                                   const std::vector<Joints>& path, int cut_index, bool mirrored,
                                   double cut_clearance, double must_beat, double max_step_m) {
  const size_t end = mirrored ? static_cast<size_t>(cut_index) + 1 : path.size();
  double clearance = cut_clearance;
  if (!(clearance > must_beat)) return std::nullopt;
  for (size_t i = 0; i < end; ++i) {
    if (static_cast<int>(i) == cut_index) continue;
    // Only whether it stays above must_beat, and then the min, matter: the checker may stop early.
    clearance = checker.ClearanceAbove(path[i], must_beat, clearance);
    if (!(clearance > must_beat)) return std::nullopt;
  }
  if (primitive != nullptr) {
    // Each configuration is an end of two motions: its lanes' verdict once for all (AreFree
    // decides it exactly as IsMotionFree's batch of ends does), then the motions' interiors.
    std::array<bool, 64> free{};
    for (size_t i = 0; i < end; i += free.size()) {
      const size_t count = std::min(free.size(), end - i);
      primitive->AreFree(std::span<const Joints>(&path[i], count), std::span<bool>(free.data(), count));
      for (size_t k = 0; k < count; ++k)
        if (!free[k]) return std::nullopt;
    }
    for (size_t i = 1; i < end; ++i) {
      if (!primitive->IsMotionInteriorFree(path[i - 1], path[i], max_step_m)) return std::nullopt;
    }
    return clearance;
  }
  for (size_t i = 1; i < end; ++i) {
    if (!checker.IsMotionFree(path[i - 1], path[i], max_step_m)) return std::nullopt;
  }
  return clearance;
}

bool IsMirrored(const std::vector<Eigen::Vector3d>& waypoints, int cut_index) {
  const int last = static_cast<int>(waypoints.size()) - 1;
  if (cut_index <= 0 || last != 2 * cut_index) return false;
  for (int j = 1; j <= cut_index; ++j) {
    if (waypoints[cut_index + j] != waypoints[cut_index - j]) return false;
  }
  return true;
}

}  // namespace vb::plan::stroke
