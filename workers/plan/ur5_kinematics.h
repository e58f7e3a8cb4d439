// SPDX-License-Identifier: Apache-2.0
// UR5 kinematics in the ur_kinematics DH convention (ARCHITECTURE.md "Reference values"): forward
// kinematics of every link frame and closed-form inverse kinematics returning all solutions.
// Frames: `base` is the arm's base frame (DH frame 0), `flange` the tool flange (DH frame 6).
// Thread-safe (pure functions).
#pragma once

#include <array>

#include "absl/status/status.h"
#include "Eigen/Core"
#include "Eigen/Geometry"

namespace vb::plan {

using Joints = Eigen::Matrix<double, 6, 1>;  // rad, shoulder pan .. wrist 3

// Standard DH: link i transform = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), theta_i = q_i.
struct DhParameters {
  std::array<double, 6> d{};
  std::array<double, 6> a{};
  std::array<double, 6> alpha{};
};

// d1 0.089159, a2 -0.425, a3 -0.39225, d4 0.10915, d5 0.09465, d6 0.0823; alpha [pi/2,0,0,pi/2,-pi/2,0].
const DhParameters& Ur5Dh();

struct JointLimits {
  Joints lower = Joints::Constant(-2.0 * 3.141592653589793);   // rad
  Joints upper = Joints::Constant(2.0 * 3.141592653589793);    // rad
  Joints max_velocity = Joints::Constant(3.141592653589793);   // rad/s (UR5: 180 deg/s)
  // rad/s^2. The UR5 has no joint acceleration limit of its own, only torque limits; Universal
  // Robots' ROS 2 driver gives MoveIt 5 rad/s^2 per joint for time parameterisation, "chosen
  // conservatively to work in most use cases" (ur_moveit_config/config/joint_limits.yaml).
  // URScript movej's 1.4 rad/s^2 is a programming default, not a limit (docs/plan.md, "Time
  // parameterisation").
  Joints max_acceleration = Joints::Constant(5.0);

  // INVALID_ARGUMENT naming the joint: non-finite, lower >= upper, velocity or acceleration <= 0.
  absl::Status Validate() const;
  bool Contains(const Joints& q) const;
};

// base_from_link[i] for i = 0 (the base itself, identity) .. 6 (the flange).
std::array<Eigen::Isometry3d, 7> LinkFrames(const Joints& q, const DhParameters& dh = Ur5Dh());

// One DH link transform Rz(theta) Tz(d) Tx(a) Rx(alpha), written out, from the sines and cosines
// of theta and alpha (LinkFrames's, and safety_margins' TwistCachedFrames with alpha's cached).
inline Eigen::Isometry3d DhTransform(double ct, double st, double ca, double sa, double a,
                                     double d) {
  Eigen::Matrix4d m;
  m << ct, -st * ca, st * sa, a * ct,
       st, ct * ca, -ct * sa, a * st,
       0, sa, ca, d,
       0, 0, 0, 1;
  Eigen::Isometry3d t;
  t.matrix() = m;
  return t;
}
// base_from_flange.
Eigen::Isometry3d ForwardKinematics(const Joints& q, const DhParameters& dh = Ur5Dh());

// Up to 8 joint configurations reaching one flange pose, in the order shoulder branch (2) x
// wrist branch (2) x elbow branch (2), dropped branches compacted away.
struct IkSolutions {
  std::array<Joints, 8> q;
  std::array<signed char, 8> branch{};  // q[i]'s branch: 4 shoulder + 2 wrist + elbow (0 or 1 each)
  int count = 0;
};

// All closed-form solutions (at most 8: shoulder x wrist x elbow branches) of
// ForwardKinematics(q) == base_from_flange, for the UR5 geometry (Ur5Dh(); the derivation relies
// on a1 = a4 = a5 = a6 = 0 and parallel joints 2-4), after Hawkins, "Analytic Inverse Kinematics
// for the Universal Robots UR-5/UR-10 Arms", 2013. Each joint is moved by multiples of 2*pi to the
// equivalent nearest `near` (or nearest 0 if null) that lies within `limits`; a solution with a
// joint that cannot be brought into the limits is dropped. At a wrist singularity (|sin q5| ~ 0)
// q6 is taken from `near` (or 0) and q4 absorbs the rest of the rotation. Poses at the boundary of
// the workspace (within 1e-9 of it) are accepted and give coinciding branches once each.
// Unreachable or non-finite pose (or non-finite `near`): count 0. Thread-safe.
IkSolutions InverseKinematics(const Eigen::Isometry3d& base_from_flange, const JointLimits& limits,
                              const Joints* near = nullptr);

// The solution of one branch (IkSolutions::branch numbering) of InverseKinematics, the same bit
// for bit, without computing the other branches; false if that branch has no solution within the
// limits (or does not exist at this pose, or `branch` is not in 0..7). *apart_rad receives a
// lower bound on how far every other branch's solution is from it in some joint, modulo whole
// turns (+inf if there is no other branch): a solution within c of some configuration in every
// joint is the unique nearest one to it whenever *apart_rad > 2c. For following a path branch by
// branch (cut_motion.cc).
bool InverseKinematicsBranch(const Eigen::Isometry3d& base_from_flange, const JointLimits& limits,
                             const Joints* near, int branch, Joints* q, double* apart_rad);

// Wraps every joint of q by multiples of 2*pi to the equivalent nearest `near` (or 0) inside
// `limits`; false (q unspecified) if some joint has no equivalent inside them.
bool WrapIntoLimits(const JointLimits& limits, const Joints* near, Joints* q);

}  // namespace vb::plan
