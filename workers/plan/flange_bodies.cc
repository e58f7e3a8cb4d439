// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/flange_bodies.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/geometry.h"

namespace vb::plan {

FlangeBodies::FlangeBodies(const RobotModel& robot) {
  const Eigen::Vector3d tcp = robot.tool.flange_from_tcp.translation();
  for (const LinkBody& body : robot.BodiesWithTool()) {
    if (body.frame != 6) continue;
    for (const Capsule& c : body.capsules) {
      // Whatever the pose, the capsule's axis stays within [near_m, far_m] of the TCP.
      Body body;
      body.capsule = c;
      body.near_m = PointSegmentDistance(tcp, c.a, c.b);
      body.far_m = std::max((c.a - tcp).norm(), (c.b - tcp).norm());
      bodies_.push_back(std::move(body));
    }
  }
  // The tool's capsules (added last) are the likeliest to touch the vine: test them first.
  std::reverse(bodies_.begin(), bodies_.end());
}

void FlangeBodies::Select(const CollisionScene& scene, const Eigen::Vector3d& tcp_point,
                          double tcp_travel_m) {
  struct Near {
    NearObstacle o;
    double nearest, farthest;  // of its axis from tcp_point
  };
  double reach = 0;  // of any flange body from the TCP
  for (const Body& body : bodies_) reach = std::max(reach, body.far_m + body.capsule.radius);
  std::vector<Near> near;
  near.reserve(scene.obstacles.size());
  for (const Obstacle& o : scene.obstacles) {
    const double radius = o.capsule.radius + o.margin_m;
    // The obstacle's ball first (cheaper than the point-segment distance; 1e-6 m of slack, far
    // above the rounding, so it only skips what the exact test below skips).
    const Eigen::Vector3d centre = 0.5 * (o.capsule.a + o.capsule.b);
    const double far = reach + tcp_travel_m + radius + 0.5 * (o.capsule.b - o.capsule.a).norm() +
                       1e-6;
    if ((centre - tcp_point).squaredNorm() > far * far) continue;
    const double nearest = PointSegmentDistance(tcp_point, o.capsule.a, o.capsule.b);
    if (nearest - radius > reach + tcp_travel_m + 1e-9) continue;
    near.push_back({{o.capsule.a, o.capsule.b, 0.5 * (o.capsule.a + o.capsule.b), radius,
                     0.5 * (o.capsule.b - o.capsule.a).norm() + radius},
                    nearest,
                    std::max((o.capsule.a - tcp_point).norm(), (o.capsule.b - tcp_point).norm())});
  }
  // Nearest first, ties in scene order (a stable sort, on (distance, index) keys: the entries
  // are large).
  std::vector<std::pair<double, int>> keys(near.size());
  for (size_t i = 0; i < near.size(); ++i) keys[i] = {near[i].nearest, static_cast<int>(i)};
  std::sort(keys.begin(), keys.end());
  std::vector<int> order(near.size());
  for (size_t i = 0; i < near.size(); ++i) order[i] = keys[i].second;
  for (Body& body : bodies_) {
    for (int travel = 0; travel < 2; ++travel) {
      const double t = travel ? tcp_travel_m : 0.0;
      std::vector<NearObstacle>& list = body.near[travel];
      list.clear();
      for (int i : order) {
        const Near& n = near[i];
        // Contact needs the axes within the radii (+1e-9 m against rounding) somewhere in the
        // shell [near_m - t, far_m + t] about tcp_point.
        const double reach = body.capsule.radius + n.o.radius + 1e-9;
        if (n.nearest > body.far_m + t + reach) continue;
        if (n.farthest < body.near_m - t - reach) continue;
        list.push_back(n.o);
      }
    }
  }
  // Planes that no flange body can cross from here are left out: every point of a body's axis is
  // within far_m of the TCP, itself within the travel of tcp_point, so the test's max over its
  // ends of n . x, plus its radius and the margin, is at most n . tcp_point + travel + reach +
  // margin (1e-9 m of slack against rounding).
  for (int travel = 0; travel < 2; ++travel) {
    const double t = travel ? tcp_travel_m : 0.0;
    planes_[travel].clear();
    for (const HalfSpace& h : scene.planes) {
      if (h.normal.dot(tcp_point) + t + reach + h.margin_m + 1e-9 < h.offset + kToleranceM)
        continue;
      planes_[travel].push_back(h);
    }
  }
}

bool FlangeBodies::Collides(const Eigen::Isometry3d& base_from_flange, bool along_stroke) const {
  for (const Body& body : bodies_) {
    const Capsule& c = body.capsule;
    const Eigen::Vector3d a = base_from_flange * c.a, b = base_from_flange * c.b;
    const Eigen::Vector3d centre = 0.5 * (a + b), ab = b - a;
    const double ab_squared = ab.squaredNorm();
    const double bound = 0.5 * std::sqrt(ab_squared) + c.radius;
    for (const HalfSpace& h : planes_[along_stroke ? 1 : 0]) {
      if (std::max(h.normal.dot(a), h.normal.dot(b)) + c.radius + h.margin_m >
          h.offset + kToleranceM) {
        return true;
      }
    }
    std::vector<NearObstacle>& list = body.near[along_stroke ? 1 : 0];
    for (size_t i = 0; i < list.size(); ++i) {
      const NearObstacle& o = list[i];
      // Bounding spheres apart: the capsules are too (cheaper than the segment distance).
      const double apart = bound + o.bound;
      if ((centre - o.centre).squaredNorm() > apart * apart) continue;
      // Tighter, still cheaper than the segment distance: the obstacle's ball against the
      // flange capsule's segment, squared (1e-9 m of slack against rounding; contact needs
      // less than the radii minus kToleranceM).
      const double u =
          ab_squared > 0 ? std::clamp((o.centre - a).dot(ab) / ab_squared, 0.0, 1.0) : 0.0;
      const double ball = c.radius + o.bound + 1e-9;
      const double centre_squared = (a + u * ab - o.centre).squaredNorm();
      if (centre_squared > ball * ball) continue;
      // The obstacle's centre is on its axis, so the axes are at most that far apart: well
      // within the radii (1e-9 m below the contact test's bound, far above the rounding of
      // either distance), it collides without the segment distance.
      const double inside = c.radius + o.radius - kToleranceM - 1e-9;
      if ((inside > 0 && centre_squared < inside * inside) ||
          SegmentSegmentDistance(a, b, o.a, o.b) < c.radius + o.radius - kToleranceM) {
        if (i > 0) std::swap(list[i], list[i / 2]);
        return true;
      }
    }
  }
  return false;
}

}  // namespace vb::plan
