// SPDX-License-Identifier: Apache-2.0
// Adaptive safety margins (Botterill et al. 2017 section 3.4): once the cut motions are chosen,
// every obstacle is inflated as far as it can be (up to a maximum) without touching any of them,
// so that the paths planned between cuts keep the arm as far from the vine as the cuts allow:
// far from everything the cuts do not approach, and only as close as needed near the cuts.
// Thread-safe (pure functions).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "core/ids.h"
#include "Eigen/Core"
#include "Eigen/Geometry"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// Configurations the margins must leave free. `ignored_cane` (with `ignored_point_in_base` and
// `ignored_radius_m`) names the cut cane near the cut, which the configurations may touch: its
// capsules that CollisionScene::WithoutCaneNear leaves out (IsCaneNear) do not limit their margins
// for this motion; 0 ignores nothing.
struct ProtectedMotion {
  std::vector<Joints> path;       // checked along straight joint segments, as IsMotionFree does
  CaneId ignored_cane;
  Eigen::Vector3d ignored_point_in_base = Eigen::Vector3d::Zero();
  double ignored_radius_m = 0.0;
};

struct MarginOptions {
  double max_margin_m = 0.03;   // no obstacle is inflated further (the default)
  double slack_m = 0.001;       // margins stop this short of touching a protected configuration
  double max_step_m = 0.01;     // interpolation of protected paths (as the checker's motion checks)
  // INVALID_ARGUMENT naming the field: non-finite or negative values, max_step_m <= 0.
  absl::Status Validate() const;
};

struct MarginSummary {
  double min_margin_m = 0.0;       // smallest margin given to any vine obstacle
  double median_margin_m = 0.0;    // median over vine obstacles (canes, head, wires, posts)
  int configurations = 0;          // protected configurations examined
};

// LinkFrames (ur5_kinematics.h) with the sines and cosines of the DH twists computed once instead
// of at every call: the same frames bit for bit (the same matrices and products), with half the
// trigonometric calls. InflateMargins places every protected configuration with it. Thread-safe.
class TwistCachedFrames {
 public:
  explicit TwistCachedFrames(const DhParameters& dh = Ur5Dh());
  std::array<Eigen::Isometry3d, 7> operator()(const Joints& q) const;

 private:
  DhParameters dh_;
  std::array<double, 6> ca_{}, sa_{};
};

// Sets every obstacle's and plane's margin_m to min(max_margin_m, clearance to the protected
// configurations - slack_m), never below its current margin's floor of 0. Obstacles already
// touching a protected configuration get margin 0. `scene` is modified in place.
MarginSummary InflateMargins(const RobotModel& robot, std::span<const ProtectedMotion> motions,
                             const MarginOptions& options, CollisionScene* scene);

}  // namespace vb::plan
