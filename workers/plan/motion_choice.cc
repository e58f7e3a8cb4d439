// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/motion_choice.h"

#include <algorithm>
#include <cmath>

#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

constexpr double kTurn = 2.0 * M_PI;

bool SameCapsule(const Capsule& a, const Capsule& b, double tol) {
  if (std::abs(a.radius - b.radius) > tol) return false;
  return ((a.a - b.a).norm() <= tol && (a.b - b.b).norm() <= tol) ||
         ((a.a - b.b).norm() <= tol && (a.b - b.a).norm() <= tol);
}

}  // namespace

bool RollSymmetric(const RobotModel& robot) {
  constexpr double kTol = 1e-9;
  std::vector<Capsule> moved = robot.tool.capsules;  // in the flange frame
  for (const LinkBody& link : robot.links)
    if (link.frame == 6) moved.insert(moved.end(), link.capsules.begin(), link.capsules.end());
  auto roll = [](const Eigen::Vector3d& v) { return Eigen::Vector3d(-v.x(), -v.y(), v.z()); };
  for (const Capsule& c : moved) {
    const Capsule rolled{roll(c.a), roll(c.b), c.radius};
    if (std::none_of(moved.begin(), moved.end(),
                     [&](const Capsule& d) { return SameCapsule(rolled, d, kTol); }))
      return false;
  }
  const Eigen::Vector3d tcp = robot.tool.flange_from_tcp.translation();
  const Eigen::Vector3d tcp_z = robot.tool.flange_from_tcp.linear().col(2);
  return std::hypot(tcp.x(), tcp.y()) <= kTol && (tcp_z - Eigen::Vector3d::UnitZ()).norm() <= kTol;
}

std::optional<std::vector<Joints>> RolledTwin(const std::vector<Joints>& path, int cut_index,
                                              CutStroke stroke, const JointLimits& limits,
                                              int* twin_cut_index) {
  if (path.empty() || cut_index < 0 || static_cast<size_t>(cut_index) >= path.size())
    return std::nullopt;
  double lo = path.front()[5], hi = lo;
  for (const Joints& q : path) {
    lo = std::min(lo, q[5]);
    hi = std::max(hi, q[5]);
  }
  double roll = 0.0;
  for (double d : {M_PI, -M_PI}) {
    if (lo + d >= limits.lower[5] && hi + d <= limits.upper[5]) {
      roll = d;
      break;
    }
  }
  if (roll == 0.0) return std::nullopt;
  std::vector<Joints> twin = path;
  for (Joints& q : twin) q[5] += roll;
  int index = cut_index;
  if (stroke == CutStroke::kSweep) {
    std::reverse(twin.begin(), twin.end());
    index = static_cast<int>(path.size()) - 1 - cut_index;
  }
  if (twin_cut_index) *twin_cut_index = index;
  return twin;
}

Joints NearestTurn(const Joints& q, const Joints& near, const JointLimits& limits) {
  Joints out = q;
  for (int j = 0; j < 6; ++j) {
    if (!(limits.upper[j] - limits.lower[j] > kTurn)) continue;
    for (int k : {-1, 1}) {
      const double v = q[j] + k * kTurn;
      if (v >= limits.lower[j] && v <= limits.upper[j] &&
          std::abs(v - near[j]) < std::abs(out[j] - near[j]))
        out[j] = v;
    }
  }
  return out;
}

double TurnAwareMoveTimeS(const Joints& from, const Joints& to, const JointLimits& limits) {
  return MoveTimeS(from, NearestTurn(to, from, limits), limits);
}

bool SameUpToTurns(const Joints& a, const Joints& b, double tol_rad) {
  for (int j = 0; j < 6; ++j) {
    const double d = std::remainder(a[j] - b[j], kTurn);
    if (std::abs(d) > tol_rad) return false;
  }
  return true;
}

}  // namespace vb::plan
