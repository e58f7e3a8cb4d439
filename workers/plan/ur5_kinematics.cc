// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/ur5_kinematics.h"

#include <cmath>

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

namespace {

// Rz(theta) Tz(d) Tx(a) Rx(alpha), written out.
Eigen::Isometry3d DhTransform(double theta, double d, double a, double alpha) {
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Matrix4d m;
  m << ct, -st * ca, st * sa, a * ct,
       st, ct * ca, -ct * sa, a * st,
       0, sa, ca, d,
       0, 0, 0, 1;
  Eigen::Isometry3d t;
  t.matrix() = m;
  return t;
}

}  // namespace

std::array<Eigen::Isometry3d, 7> LinkFrames(const Joints& q, const DhParameters& dh) {
  std::array<Eigen::Isometry3d, 7> frames;
  frames[0] = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    frames[i + 1] = frames[i] * DhTransform(q[i], dh.d[i], dh.a[i], dh.alpha[i]);
  }
  return frames;
}

Eigen::Isometry3d ForwardKinematics(const Joints& q, const DhParameters& dh) {
  return LinkFrames(q, dh)[6];
}

}  // namespace vb::plan
