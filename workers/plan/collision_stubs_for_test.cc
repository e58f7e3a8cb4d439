// SPDX-License-Identifier: Apache-2.0
// TEMPORARY (plan-kin only): minimal stand-ins for the collision-checking definitions that the
// "coll" branch implements (collision_checker.cc, collision_scene.cc, robot_model.cc), so that
// cut_motion_test links before that branch is merged. Linked into vb_plan_test only; deleted by
// the merge of plan-coll.
#include <cmath>

#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"

namespace vb::plan {

void CollisionChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  for (size_t i = 0; i < qs.size(); ++i) out[i] = IsFree(qs[i]);
}

bool CollisionChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  const int n = MotionSteps(a, b, max_step_m);
  for (int i = 0; i <= n; ++i) {
    if (!IsFree(a + (b - a) * (static_cast<double>(i) / n))) return false;
  }
  return true;
}

int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m) {
  return std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().sum() * reach_m / max_step_m)));
}

CollisionScene CollisionScene::WithoutCaneNear(CaneId cane_id, const Eigen::Vector3d& point,
                                               double radius_m) const {
  CollisionScene out;
  out.planes = planes;
  for (const Obstacle& o : obstacles) {
    if (o.kind == ObstacleKind::kCane && o.owner_id == cane_id.value &&
        PointSegmentDistance(point, o.capsule.a, o.capsule.b) < radius_m) {
      continue;
    }
    out.obstacles.push_back(o);
  }
  return out;
}

absl::Status RobotModel::Validate() const { return limits.Validate(); }

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel&, const CollisionScene&) {
  return nullptr;
}

}  // namespace vb::plan
