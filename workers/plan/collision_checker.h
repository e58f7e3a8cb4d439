// SPDX-License-Identifier: Apache-2.0
// The collision-checker interface the planner is written against (after OMPL's
// StateValidityChecker / MotionValidator), with its implementations: our primitive checker
// (spheres of the arm against capsules, spheres and planes, sorted by distance from the base and
// culled per link by reach, after Botterill et al. 2017 section 3.4 and VAMP, Thomason et al.
// ICRA 2024) and the FCL baselines (triangle meshes or FCL primitives of the same geometry).
// A checker is built for one robot and one scene; its scene never changes, except that a
// PrimitiveChecker can leave some of its obstacles out (PrimitiveChecker::Exclude). Not
// thread-safe (it counts checks); use one per thread.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>

#include "absl/status/statusor.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// lever_m[i]: an upper bound on the distance from joint i's axis of any point of any body that
// joint i moves (capsule surfaces with their radii, the tool included), over all configurations.
using JointLevers = std::array<double, 6>;
// A single reach for every joint (the former bound; it ignores the tool's length).
inline constexpr double kDefaultReachM = 1.2;
constexpr JointLevers UniformLevers(double reach_m) {
  return {reach_m, reach_m, reach_m, reach_m, reach_m, reach_m};
}

// Per-joint lever arms of `robot`'s bodies (BodiesWithTool) on the UR5 DH chain, in O(capsules).
//
// Why stepping by them is conservative: on a straight joint-space segment a point p of a body in
// DH frame k moves with velocity sum_{i<=k} dq_i/dt z_{i-1} x (p - o_{i-1}), whose norm is at most
// sum_i |dq_i/dt| dist(p, axis i) <= sum_i |dq_i/dt| lever_m[i]; integrated over one interval,
// no point travels (path length, hence chord) more than sum_i |dq_i| lever_m[i] with dq the
// interval's joint step. MotionSteps picks intervals that keep this <= max_step_m.
//
// Why the levers bound dist(p, axis i): a capsule point lies within `radius` of its segment and
// the distance to a line is convex along a segment, so endpoint distances plus the radius bound
// it. Each endpoint, fixed in frame k, is carried down the chain as a cylinder about z_j that
// contains it for every q_{j+1..k}: radius rho_j and height [lo_j, hi_j] in frame j (exact at
// j = k). Frame j -> j-1 is Rz(q_j) Tz(d_j) Tx(a_j) Rx(alpha_j); Rz and Tz leave the distance to
// z_{j-1} unchanged, so for p = (x, y, z) with x^2 + y^2 <= rho^2, |z| <= Z:
//   dist^2 = (x + a)^2 + (y cos(alpha) - z sin(alpha))^2
//          <= (rho + |a|)^2 + 2 rho Z |sin(alpha) cos(alpha)| + Z^2 sin^2(alpha) =: rho_{j-1}^2,
// and the new height d + y sin(alpha) + z cos(alpha) lies in
//   [d + min(lo cos, hi cos) - rho |sin|, d + max(lo cos, hi cos) + rho |sin|].
// rho_{j-1} bounds the endpoint's distance from joint j's axis (z_{j-1}) whatever q is. The bound
// is exact for the wrist joints (the tool's distance from the joint 5 axis, its radius for joint
// 6) and looser toward the base, where it merges the arm's offsets into one cylinder.
JointLevers JointLeverArms(const RobotModel& robot);

// A cylinder about the base z axis (DH frame 0): radius_m, heights [lo_z_m, hi_z_m].
struct ReachCylinder {
  double radius_m = 0, lo_z_m = 0, hi_z_m = 0;
};
// A cylinder that holds point `p` of DH frame `frame` (0..6, UR5 chain) in every configuration:
// the chain bound of JointLeverArms carried down to frame 0. For per-link reach culling
// (Botterill et al. 2017 section 3.4).
ReachCylinder ReachOfPoint(int frame, const Eigen::Vector3d& p);

class CollisionChecker {
 public:
  virtual ~CollisionChecker() = default;

  // True if at q no arm body (tool included) touches an obstacle inflated by its margin, and no
  // self-collision pair touches. Joint limits are not checked here. Counts one check.
  virtual bool IsFree(const Joints& q) = 0;
  // out[i] = IsFree(qs[i]); implementations may check configurations together. Counts qs.size().
  virtual void AreFree(std::span<const Joints> qs, std::span<bool> out);
  // True if every configuration on the straight joint-space segment from a to b, interpolated so
  // that no point of the arm moves more than `max_step_m` between checks (a conservative bound
  // from joint steps and the lever arms lever_m(), see MotionSteps), is free. Both ends included.
  virtual bool IsMotionFree(const Joints& a, const Joints& b, double max_step_m);
  // Smallest distance between the surface of any arm body and any obstacle (inflated by its
  // margin), or between self-collision pairs; negative when they overlap. Counts one check.
  virtual double Clearance(const Joints& q) = 0;
  // min(cap, Clearance(q)), exactly, when that exceeds `floor`; otherwise some value <= floor
  // (the caller rejects q whatever it is). For rankings that only need the clearance below a
  // bound already found and above a bar: implementations may skip what cannot change the answer.
  // The default computes Clearance(q). Counts one check.
  virtual double ClearanceAbove(const Joints& q, double floor, double cap);

  // The per-joint lever arms IsMotionFree interpolates with: JointLeverArms(robot) for checkers
  // built from a robot, kDefaultReachM for every joint otherwise.
  const JointLevers& lever_m() const { return lever_m_; }

  int64_t checks() const { return checks_; }
  void ResetChecks() { checks_ = 0; }

 protected:
  int64_t checks_ = 0;
  JointLevers lever_m_ = UniformLevers(kDefaultReachM);
};

// Number of intervals to split the joint segment a -> b into so that no point of the arm within
// `reach_m` of any joint axis moves more than max_step_m per interval (>= 1).
int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m = kDefaultReachM);
// The same with a lever arm per joint: ceil(sum_i |b_i - a_i| lever_m[i] / max_step_m), >= 1
// (2^20 for a non-finite travel or max_step_m <= 0).
int MotionSteps(const Joints& a, const Joints& b, double max_step_m, const JointLevers& lever_m);

enum class FclMode { kMesh, kPrimitives };

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel& robot,
                                                      const CollisionScene& scene);
// FCL baselines. kMesh tessellates every capsule, sphere and plane patch (~1-5k triangles per arm
// link at the default density); kPrimitives uses FCL's capsules, spheres and half-spaces.
std::unique_ptr<CollisionChecker> MakeFclChecker(const RobotModel& robot,
                                                const CollisionScene& scene, FclMode mode);

}  // namespace vb::plan
