// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/safety_margins.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "workers/plan/collision_checker.h"

namespace vb::plan {

absl::Status MarginOptions::Validate() const {
  auto bad = [](const char* field) {
    return absl::InvalidArgumentError(
        absl::StrCat("margin options: ", field, " must be finite and >= 0"));
  };
  if (!std::isfinite(max_margin_m) || max_margin_m < 0) return bad("max_margin_m");
  if (!std::isfinite(slack_m) || slack_m < 0) return bad("slack_m");
  if (!std::isfinite(max_step_m) || !(max_step_m > 0))
    return absl::InvalidArgumentError("margin options: max_step_m must be finite and > 0");
  return absl::OkStatus();
}

namespace {

// One arm body capsule at one configuration, in the base frame, with its bounding sphere.
struct PlacedCapsule {
  Eigen::Vector3d a, b, centre;
  double radius = 0.0;
  double bound = 0.0;  // radius of the bounding sphere about `centre`
};

struct Pose {
  std::vector<PlacedCapsule> bodies;
  const ProtectedMotion* motion = nullptr;
};

Pose Place(const std::vector<LinkBody>& bodies, const Joints& q, const ProtectedMotion* motion) {
  const auto frames = LinkFrames(q);
  Pose pose;
  pose.motion = motion;
  for (const LinkBody& body : bodies) {
    for (const Capsule& c : body.capsules) {
      PlacedCapsule p;
      p.a = frames[body.frame] * c.a;
      p.b = frames[body.frame] * c.b;
      p.centre = 0.5 * (p.a + p.b);
      p.radius = c.radius;
      p.bound = 0.5 * (p.b - p.a).norm() + c.radius;
      pose.bodies.push_back(p);
    }
  }
  return pose;
}

// The same rule as CollisionScene::WithoutCaneNear: the cut cane's capsules near the cut point.
bool Ignored(const Obstacle& o, const ProtectedMotion& m) {
  return m.ignored_cane.value != 0 && o.kind == ObstacleKind::kCane &&
         o.owner_id == m.ignored_cane.value &&
         PointSegmentDistance(m.ignored_point_in_base, o.capsule.a, o.capsule.b) <=
             m.ignored_radius_m;
}

}  // namespace

MarginSummary InflateMargins(const RobotModel& robot, std::span<const ProtectedMotion> motions,
                             const MarginOptions& options, CollisionScene* scene) {
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  // The checkers' own interpolation (CollisionChecker::IsMotionFree), so the poses are theirs.
  const JointLevers lever_m = JointLeverArms(robot);
  std::vector<Pose> poses;
  for (const ProtectedMotion& motion : motions) {
    for (size_t i = 0; i < motion.path.size(); ++i) {
      poses.push_back(Place(bodies, motion.path[i], &motion));
      if (i + 1 == motion.path.size()) break;
      const Joints& a = motion.path[i];
      const Joints& b = motion.path[i + 1];
      const int steps = MotionSteps(a, b, options.max_step_m, lever_m);
      for (int s = 1; s < steps; ++s)
        poses.push_back(Place(bodies, a + (b - a) * (double(s) / steps), &motion));
    }
  }

  const double reach = options.max_margin_m + options.slack_m;
  std::vector<double> vine_margins;
  for (Obstacle& o : scene->obstacles) {
    const Eigen::Vector3d centre = 0.5 * (o.capsule.a + o.capsule.b);
    const double bound = 0.5 * (o.capsule.b - o.capsule.a).norm() + o.capsule.radius;
    double clearance = std::numeric_limits<double>::infinity();
    for (const Pose& pose : poses) {
      if (Ignored(o, *pose.motion)) continue;
      for (const PlacedCapsule& p : pose.bodies) {
        // Bounding spheres farther apart than the largest margin cannot limit it.
        if ((p.centre - centre).norm() - p.bound - bound > reach) continue;
        const double d = SegmentSegmentDistance(p.a, p.b, o.capsule.a, o.capsule.b) - p.radius -
                         o.capsule.radius;
        clearance = std::min(clearance, d);
      }
    }
    o.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
    if (o.kind != ObstacleKind::kPlatform) vine_margins.push_back(o.margin_m);
  }
  for (HalfSpace& plane : scene->planes) {
    double clearance = std::numeric_limits<double>::infinity();
    for (const Pose& pose : poses) {
      for (const PlacedCapsule& p : pose.bodies) {
        const double d = plane.offset - std::max(plane.normal.dot(p.a), plane.normal.dot(p.b)) -
                         p.radius;
        clearance = std::min(clearance, d);
      }
    }
    plane.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
  }

  MarginSummary summary;
  summary.configurations = static_cast<int>(poses.size());
  if (!vine_margins.empty()) {
    std::sort(vine_margins.begin(), vine_margins.end());
    summary.min_margin_m = vine_margins.front();
    summary.median_margin_m = vine_margins[vine_margins.size() / 2];
  }
  return summary;
}

}  // namespace vb::plan
