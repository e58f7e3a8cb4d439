// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/trajectory_check.h"

#include <algorithm>

#include "workers/plan/collision_checker.h"
#include "workers/plan/fallen_wood.h"

namespace vb::plan {

int64_t CountTrajectoryCollisions(const Trajectory& trajectory, std::span<const Cut> cuts,
                                  const VineModel& model, const PlatformGeometry& platform,
                                  const RobotModel& robot, CheckerKind kind, double max_step_m,
                                  double cut_radius_m, std::vector<int>* bad_segments) {
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  if (bad_segments != nullptr) bad_segments->assign(trajectory.segments.size(), 0);
  std::vector<Cut> made;
  VineModel now = model;
  auto scene = CollisionScene::Build(now, platform, robot);
  std::unique_ptr<CollisionChecker> transit_checker;
  if (scene.ok()) transit_checker = MakeChecker(kind, robot, *scene);
  int64_t collisions = 0;
  for (size_t s = 0; s < trajectory.segments.size(); ++s) {
    const TrajectorySegment& segment = trajectory.segments[s];
    if (!scene.ok()) {
      ++collisions;
      if (bad_segments != nullptr) ++(*bad_segments)[s];
      continue;
    }
    const Cut* cut = nullptr;
    std::unique_ptr<CollisionChecker> cut_checker;
    CollisionChecker* checker = transit_checker.get();
    if (segment.kind == SegmentKind::kCut) {
      auto it = std::find_if(cuts.begin(), cuts.end(),
                             [&](const Cut& c) { return c.id.value == segment.cut_id.value; });
      if (it != cuts.end()) {
        cut = &*it;
        cut_checker = MakeChecker(
            kind, robot,
            scene->WithoutCaneNear(cut->cane_id, base_from_platform * cut->point, cut_radius_m));
        checker = cut_checker.get();
      }
    }
    for (size_t p = 0; p < segment.points.size(); ++p) {
      const Joints b = Eigen::Map<const Joints>(segment.points[p].q.data());
      const Joints a =
          p == 0 ? b : Joints(Eigen::Map<const Joints>(segment.points[p - 1].q.data()));
      const int steps = p == 0 ? 1 : MotionSteps(a, b, max_step_m);
      for (int k = p == 0 ? 0 : 1; k <= steps; ++k) {
        if (checker->IsFree(a + (b - a) * (double(k) / steps))) continue;
        ++collisions;
        if (bad_segments != nullptr) ++(*bad_segments)[s];
      }
    }
    if (cut != nullptr) {
      // The cut is made: its wood falls before the next segment.
      made.push_back(*cut);
      now = WithoutFallenWood(model, made);
      scene = CollisionScene::Build(now, platform, robot);
      if (scene.ok()) transit_checker = MakeChecker(kind, robot, *scene);
    }
  }
  return collisions;
}

}  // namespace vb::plan
