// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/ur5_kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"

namespace vb::plan {

const DhParameters& Ur5Dh() {
  static const DhParameters dh = {
      {0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823},
      {0.0, -0.425, -0.39225, 0.0, 0.0, 0.0},
      {M_PI / 2, 0.0, 0.0, M_PI / 2, -M_PI / 2, 0.0}};
  return dh;
}

absl::Status JointLimits::Validate() const {
  for (int i = 0; i < 6; ++i) {
    const std::string joint = absl::StrCat("joint ", i + 1);
    if (!std::isfinite(lower[i]) || !std::isfinite(upper[i]) || !(lower[i] < upper[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("joint limits: ", joint, ": need finite lower < upper"));
    }
    if (!(max_velocity[i] > 0) || !std::isfinite(max_velocity[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("joint limits: ", joint, ": max_velocity must be finite and > 0"));
    }
    if (!(max_acceleration[i] > 0) || !std::isfinite(max_acceleration[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("joint limits: ", joint, ": max_acceleration must be finite and > 0"));
    }
  }
  return absl::OkStatus();
}

bool JointLimits::Contains(const Joints& q) const {
  return (q.array() >= lower.array()).all() && (q.array() <= upper.array()).all();
}

std::array<Eigen::Isometry3d, 7> LinkFrames(const Joints& q, const DhParameters& dh) {
  std::array<Eigen::Isometry3d, 7> frames;
  frames[0] = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    frames[i + 1] = frames[i] * DhTransform(std::cos(q[i]), std::sin(q[i]), std::cos(dh.alpha[i]),
                                            std::sin(dh.alpha[i]), dh.a[i], dh.d[i]);
  }
  return frames;
}

Eigen::Isometry3d ForwardKinematics(const Joints& q, const DhParameters& dh) {
  return LinkFrames(q, dh)[6];
}

// Inverse kinematics (Hawkins 2013, re-derived for the standard-DH frames above).
//
// Notation: p6 and x6, y6, z6 are the flange origin and axes in the base frame, s1 = sin q1 etc.
// Joints 2, 3 and 4 rotate about one common direction, z1 = (s1, -c1, 0) in the base frame, so
// every point from frame 2 onward has a constant offset along z1:
//   wrist centre p5 = p6 - d6 z6 satisfies  p5 . z1 = d4         -> q1 (2 branches)
//   z6 . z1 = cos q5, and p6 . z1 = d4 + d6 cos q5             -> q5 (2 branches)
//   z1 seen from the flange frame is (s5 c6, -s5 s6, c5)       -> q6
//   frame 4 seen from frame 1, T14 = T01^-1 T06 T56^-1 T45^-1, is a planar 3R chain:
//   p14 = (a2 c2 + a3 c23, a2 s2 + a3 s23, d4) -> q3 (2 branches), q2; its x axis is at q2+q3+q4.
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
// How far past the workspace boundary (acos/asin argument beyond +-1) a pose may lie and still be
// treated as on it: absorbs rounding of poses that were computed by FK at the boundary.
constexpr double kBoundaryTolerance = 1e-9;
// Below this |sin q5| the wrist axes 4 and 6 are parallel to machine precision and q6 is free.
constexpr double kWristSingularSin = 1e-12;

// acos of x, clamped when x is within tolerance of +-1; false when it is further out.
bool SafeAcos(double x, double* angle) {
  if (!(std::abs(x) <= 1.0 + kBoundaryTolerance)) return false;
  *angle = std::acos(std::clamp(x, -1.0, 1.0));
  return true;
}

// The transform of DH link i with joint angle theta, inverted (rigid inverse).
Eigen::Isometry3d DhInverse(const DhParameters& dh, int i, double theta) {
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(dh.alpha[i]), sa = std::sin(dh.alpha[i]);
  Eigen::Matrix3d r;
  r << ct, -st * ca, st * sa,
       st, ct * ca, -ct * sa,
       0, sa, ca;
  const Eigen::Vector3d p(dh.a[i] * ct, dh.a[i] * st, dh.d[i]);
  Eigen::Isometry3d inv = Eigen::Isometry3d::Identity();
  inv.linear() = r.transpose();
  inv.translation() = -(r.transpose() * p);
  return inv;
}

}  // namespace

bool WrapIntoLimits(const JointLimits& limits, const Joints* near, Joints* q) {
  for (int i = 0; i < 6; ++i) {
    const double v = (*q)[i];
    const double target = near != nullptr ? (*near)[i] : 0.0;
    // v + k 2pi in [lower, upper]  <=>  k in [k_min, k_max].
    const double k_min = std::ceil((limits.lower[i] - v) / kTwoPi);
    const double k_max = std::floor((limits.upper[i] - v) / kTwoPi);
    if (!(k_min <= k_max)) return false;
    const double k = std::clamp(std::round((target - v) / kTwoPi), k_min, k_max);
    double wrapped = v + k * kTwoPi;
    // Rounding in the division can put a value exactly on a limit a hair outside it.
    wrapped = std::clamp(wrapped, limits.lower[i], limits.upper[i]);
    (*q)[i] = wrapped;
  }
  return true;
}

namespace {

// The distance between two angles modulo whole turns, for a difference x in [0, 2 pi].
double TurnDistance(double x) { return std::min(std::abs(x), std::abs(kTwoPi - std::abs(x))); }

// InverseKinematics, restricted to branch `only` (4 b1 + 2 b5 + b3; -1: all). Every branch is
// computed by the same operations whichever are asked for, so one branch's solution is bit for
// bit the one the full solve gives. *apart (if not null): the smallest TurnDistance between the
// asked branch's value and another branch's in the joint where they split (q1, q5 or q3).
IkSolutions Solve(const Eigen::Isometry3d& base_from_flange, const JointLimits& limits,
                  const Joints* near, int only, double* apart) {
  IkSolutions out;
  const DhParameters& dh = Ur5Dh();
  if (!base_from_flange.matrix().allFinite()) return out;
  if (near != nullptr && !near->allFinite()) return out;

  const Eigen::Matrix3d& r06 = base_from_flange.linear();
  const Eigen::Vector3d p6 = base_from_flange.translation();
  const Eigen::Vector3d x6 = r06.col(0), y6 = r06.col(1), z6 = r06.col(2);
  const Eigen::Vector3d p5 = p6 - dh.d[5] * z6;

  // q1: rho sin(q1 - psi) = d4 with (p5x, p5y) = rho (cos psi, sin psi).
  const double rho = std::hypot(p5.x(), p5.y());
  if (!(rho > 0.0)) return out;  // wrist centre on the base axis: shoulder singular, no solution
  const double sin_arg = dh.d[3] / rho;
  if (!(std::abs(sin_arg) <= 1.0 + kBoundaryTolerance)) return out;
  const double psi = std::atan2(p5.y(), p5.x());
  const double shoulder = std::asin(std::clamp(sin_arg, -1.0, 1.0));
  const std::array<double, 2> q1s = {psi + shoulder, psi + M_PI - shoulder};
  const int shoulder_branches = std::abs(sin_arg) >= 1.0 ? 1 : 2;

  if (apart != nullptr) {
    *apart = std::numeric_limits<double>::infinity();
    if (shoulder_branches == 2) *apart = TurnDistance(M_PI - 2.0 * shoulder);
  }
  for (int b1 = 0; b1 < shoulder_branches; ++b1) {
    if (only >= 0 && b1 != only / 4) continue;
    const double q1 = q1s[b1];
    const double s1 = std::sin(q1), c1 = std::cos(q1);
    double q5_abs = 0;
    if (!SafeAcos((p6.x() * s1 - p6.y() * c1 - dh.d[3]) / dh.d[5], &q5_abs)) continue;
    const int wrist_branches = q5_abs == 0.0 || q5_abs == M_PI ? 1 : 2;
    if (apart != nullptr && wrist_branches == 2)
      *apart = std::min(*apart, TurnDistance(2 * q5_abs));
    for (int b5 = 0; b5 < wrist_branches; ++b5) {
      if (only >= 0 && b5 != (only / 2) % 2) continue;
      const double q5 = b5 == 0 ? q5_abs : -q5_abs;
      const double s5 = std::sin(q5);
      double q6;
      if (std::abs(s5) < kWristSingularSin) {
        q6 = near != nullptr ? (*near)[5] : 0.0;
      } else {
        // s5 c6 = x6 . z1, -s5 s6 = y6 . z1; atan2 needs only the sign of s5.
        const double sign = s5 > 0 ? 1.0 : -1.0;
        q6 = std::atan2(-sign * (y6.x() * s1 - y6.y() * c1), sign * (x6.x() * s1 - x6.y() * c1));
      }
      const Eigen::Isometry3d t14 = DhInverse(dh, 0, q1) * base_from_flange *
                                    DhInverse(dh, 5, q6) * DhInverse(dh, 4, q5);
      const double px = t14.translation().x(), py = t14.translation().y();
      const double a2 = dh.a[1], a3 = dh.a[2];
      double q3_abs = 0;
      if (!SafeAcos((px * px + py * py - a2 * a2 - a3 * a3) / (2.0 * a2 * a3), &q3_abs)) continue;
      const int elbow_branches = q3_abs == 0.0 || q3_abs == M_PI ? 1 : 2;
      if (apart != nullptr && elbow_branches == 2)
        *apart = std::min(*apart, TurnDistance(2 * q3_abs));
      const double q234 = std::atan2(t14.linear()(1, 0), t14.linear()(0, 0));
      for (int b3 = 0; b3 < elbow_branches; ++b3) {
        if (only >= 0 && b3 != only % 2) continue;
        const double q3 = b3 == 0 ? q3_abs : -q3_abs;
        const double q2 =
            std::atan2(py, px) - std::atan2(a3 * std::sin(q3), a2 + a3 * std::cos(q3));
        Joints q;
        q << q1, q2, q3, q234 - q2 - q3, q5, q6;
        if (!WrapIntoLimits(limits, near, &q)) continue;
        out.branch[out.count] = static_cast<signed char>(4 * b1 + 2 * b5 + b3);
        out.q[out.count++] = q;
      }
    }
  }
  return out;
}

}  // namespace

IkSolutions InverseKinematics(const Eigen::Isometry3d& base_from_flange, const JointLimits& limits,
                              const Joints* near) {
  return Solve(base_from_flange, limits, near, -1, nullptr);
}

bool InverseKinematicsBranch(const Eigen::Isometry3d& base_from_flange, const JointLimits& limits,
                             const Joints* near, int branch, Joints* q, double* apart_rad) {
  if (branch < 0 || branch > 7) return false;
  const IkSolutions one = Solve(base_from_flange, limits, near, branch, apart_rad);
  if (one.count == 0) return false;
  *q = one.q[0];
  return true;
}

}  // namespace vb::plan
