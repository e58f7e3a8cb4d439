// SPDX-License-Identifier: Apache-2.0
// Cut motions' first test of a cut pose (cut_motion.cc). The bodies fixed to the flange (wrist 3
// and the tool, DH frame 6) sit where the TCP pose puts them, whatever the IK branch: a TCP pose
// where one of them overlaps an obstacle has no free configuration, and its IK and checks can be
// skipped. In clutter almost every sampled cut pose is such a pose (>99% of the IK solutions at
// the cut collided on seeds 1110-1117).
// Not thread-safe: one object per thread (Select rewrites its lists).
#pragma once

#include <vector>

#include "Eigen/Geometry"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"

namespace vb::plan {

class FlangeBodies {
 public:
  explicit FlangeBodies(const RobotModel& robot);

  // Keeps, per flange body, the obstacles of `scene` that it can touch with the TCP on
  // `tcp_point` (Collides(..., false)) or within `tcp_travel_m` of it (Collides(..., true)),
  // closest to `tcp_point` first: a blocked pose is usually blocked by the wood nearest the cut.
  void Select(const CollisionScene& scene, const Eigen::Vector3d& tcp_point, double tcp_travel_m);

  // True if a flange body overlaps a selected obstacle or a plane by more than kToleranceM at
  // `base_from_flange` (the TCP on the selected point, or within the travel of it when
  // `along_stroke`). Exact, in double: a checker that works in float (the primitive checker's
  // ~1e-6 m) rejects every such pose too.
  bool Collides(const Eigen::Isometry3d& base_from_flange, bool along_stroke) const;

 private:
  static constexpr double kToleranceM = 1e-5;
  struct NearObstacle {
    Eigen::Vector3d a, b, centre;
    double radius;  // with the margin
    double bound;   // bounding sphere about `centre`
  };
  struct Body {
    Capsule capsule;  // flange frame
    double near_m, far_m;  // nearest and farthest point of its axis from the TCP
    // Select's obstacles: at the cut point, along the stroke. Collides moves an obstacle that
    // hits one step toward the front (the order changes no answer; neighbouring poses mostly
    // hit the same obstacle).
    mutable std::vector<NearObstacle> near[2];
  };
  std::vector<Body> bodies_;
  std::vector<HalfSpace> planes_[2];  // those a body may cross: at the cut point, along the stroke
};

}  // namespace vb::plan
