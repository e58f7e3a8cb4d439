// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_scene.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "workers/plan/fallen_wood.h"

namespace vb::plan {

absl::Status SceneOptions::Validate() const {
  if (!std::isfinite(cane_segment_m) || cane_segment_m < 1e-3 || cane_segment_m > 1.0) {
    return absl::InvalidArgumentError("scene options: cane_segment_m must be in [0.001, 1] m");
  }
  if (!std::isfinite(default_margin_m) || default_margin_m < 0 || default_margin_m > 0.5) {
    return absl::InvalidArgumentError("scene options: default_margin_m must be in [0, 0.5] m");
  }
  return absl::OkStatus();
}

namespace {

// Chords between the points at arc lengths 0, step, 2 step, ... from the base, and the tip: a grid
// fixed at the base, so that a cane cut short (fallen_wood.h) keeps the very capsules it had, up
// to the one its cut falls in, and a trajectory checked on the uncut vine stays free on the cut
// one there (an equally spaced resampling would move every chord of the stub). Each chord takes
// the radius that encloses the cane between its ends: the larger end radius, or more where the
// original polyline bends away from the chord. (The distance to a segment is convex and the radius
// linear along each original piece, so enclosing the original vertices and the chord ends
// encloses the whole cane.)
void AppendChords(const Polyline3& original, ObstacleKind kind, int64_t owner_id,
                  const Eigen::Isometry3d& base_from_platform, double step, double margin,
                  std::vector<Obstacle>* out) {
  const std::vector<double> arc = original.ArcLengths();
  const double length = arc.back();
  std::vector<double> grid;
  for (int k = 0; k * step < length - 1e-6; ++k) grid.push_back(k * step);
  grid.push_back(length);
  if (grid.size() < 2) grid.insert(grid.begin(), 0.0);  // a cane of (almost) no length
  size_t i = 0;
  for (size_t k = 0; k + 1 < grid.size(); ++k) {
    const Eigen::Vector3d a = original.PointAt(grid[k], arc);
    const Eigen::Vector3d b = original.PointAt(grid[k + 1], arc);
    double radius = std::max(original.RadiusAt(grid[k], arc),
                             original.RadiusAt(grid[k + 1], arc));
    while (i < arc.size() && arc[i] <= grid[k]) ++i;
    for (size_t j = i; j < arc.size() && arc[j] < grid[k + 1]; ++j)
      radius = std::max(radius, PointSegmentDistance(original.points[j], a, b) + original.radii[j]);
    out->push_back(Obstacle{kind, owner_id,
                            Capsule{base_from_platform * a, base_from_platform * b, radius},
                            margin});
  }
}

void AppendCaneChords(const Cane& cane, const Eigen::Isometry3d& base_from_platform, double step,
                      double margin, std::vector<Obstacle>* out) {
  AppendChords(cane.polyline, ObstacleKind::kCane, cane.id.value, base_from_platform, step, margin,
               out);
}

bool SameObstacle(const Obstacle& x, const Obstacle& y) {
  return x.kind == y.kind && x.owner_id == y.owner_id && x.capsule.a == y.capsule.a &&
         x.capsule.b == y.capsule.b && x.capsule.radius == y.capsule.radius;
}

}  // namespace

absl::StatusOr<CollisionScene> CollisionScene::Build(const VineModel& model,
                                                     const PlatformGeometry& platform,
                                                     const RobotModel& robot,
                                                     const SceneOptions& options) {
  if (auto s = options.Validate(); !s.ok()) return s;
  if (auto s = model.Validate(); !s.ok()) return s;
  if (auto s = platform.Validate(); !s.ok()) return s;
  if (auto s = robot.Validate(); !s.ok()) return s;
  // VineModel::Validate does not cover every field the scene uses.
  for (size_t i = 0; i < model.head.spheres.size(); ++i) {
    const Sphere& s = model.head.spheres[i];
    if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius < 0) {
      return absl::InvalidArgumentError(absl::StrCat("head.spheres[", i, "]: bad geometry"));
    }
  }
  for (size_t i = 0; i < model.wires.size(); ++i) {
    const Wire& w = model.wires[i];
    bool ok = w.points.size() >= 2 && std::isfinite(w.radius) && w.radius >= 0;
    for (const auto& p : w.points) ok = ok && p.allFinite();
    if (!ok) return absl::InvalidArgumentError(absl::StrCat("wires[", i, "]: bad geometry"));
  }
  for (size_t i = 0; i < model.posts.size(); ++i) {
    const Post& p = model.posts[i];
    if (!p.base.allFinite() || !p.top.allFinite() || !std::isfinite(p.radius) || p.radius < 0) {
      return absl::InvalidArgumentError(absl::StrCat("posts[", i, "]: bad geometry"));
    }
  }

  // Finite but absurd coordinates would make the chord grid (and memory) explode: no part of a
  // stop's vine lies this far from the platform origin.
  constexpr double kMaxReachM = 10.0;
  auto far = [&](const Polyline3& line) {
    for (const Eigen::Vector3d& p : line.points) {
      if (p.norm() > kMaxReachM) return true;
    }
    return false;
  };
  for (size_t i = 0; i < model.canes.size(); ++i) {
    if (far(model.canes[i].polyline)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "canes[", i, "].points: a point lies more than ", kMaxReachM, " m from the platform"));
    }
  }
  for (size_t i = 0; i < model.obstacles.size(); ++i) {
    if (far(model.obstacles[i].polyline)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "obstacles[", i, "].points: a point lies more than ", kMaxReachM, " m from the platform"));
    }
  }

  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const double margin = options.default_margin_m;
  CollisionScene scene;
  auto add = [&](ObstacleKind kind, int64_t owner, const Eigen::Vector3d& a,
                 const Eigen::Vector3d& b, double radius) {
    scene.obstacles.push_back(
        Obstacle{kind, owner, Capsule{base_from_platform * a, base_from_platform * b, radius},
                 margin});
  };
  for (const Cane& cane : model.canes)
    AppendCaneChords(cane, base_from_platform, options.cane_segment_m, margin, &scene.obstacles);
  // The wood the model left out: avoided as canes are (chords on the same grid), cut nowhere.
  for (size_t i = 0; i < model.obstacles.size(); ++i) {
    AppendChords(model.obstacles[i].polyline, ObstacleKind::kLeftOutWood,
                 static_cast<int64_t>(i) + 1, base_from_platform, options.cane_segment_m, margin,
                 &scene.obstacles);
  }
  for (const Sphere& s : model.head.spheres) add(ObstacleKind::kHead, 0, s.center, s.center, s.radius);
  for (const Wire& w : model.wires) {
    for (size_t k = 0; k + 1 < w.points.size(); ++k) {
      add(ObstacleKind::kWire, w.id.value, w.points[k], w.points[k + 1], w.radius);
    }
  }
  for (const Post& p : model.posts) add(ObstacleKind::kPost, p.id.value, p.base, p.top, p.radius);
  for (const Sphere& s : platform.fixed_spheres) {
    add(ObstacleKind::kPlatform, 0, s.center, s.center, s.radius);
  }
  for (const Capsule& c : platform.fixed_capsules) {
    add(ObstacleKind::kPlatform, 0, c.a, c.b, c.radius);
  }

  // Free sides in the platform frame (n . x <= offset), then into the base frame:
  // n_p . (R x_b + t) <= o  <=>  (R^T n_p) . x_b <= o - n_p . t.
  const std::pair<Eigen::Vector3d, double> planes_in_platform[] = {
      {-Eigen::Vector3d::UnitZ(), -platform.ground_z_m},
      {Eigen::Vector3d::UnitZ(), platform.roof_z_m},
      {-Eigen::Vector3d::UnitY(), -platform.camera_side_wall_y_m},
      {Eigen::Vector3d::UnitY(), platform.backdrop_y_m}};
  const Eigen::Matrix3d r = robot.platform_from_arm_base.linear();
  const Eigen::Vector3d t = robot.platform_from_arm_base.translation();
  for (const auto& [n, o] : planes_in_platform) {
    scene.planes.push_back(HalfSpace{r.transpose() * n, o - n.dot(t), margin});
  }
  return scene;
}

CollisionScene CollisionScene::WithoutCaneNear(CaneId cane_id,
                                               const Eigen::Vector3d& point_in_base,
                                               double radius_m) const {
  const std::vector<int> near = CaneNearIndices(cane_id, point_in_base, radius_m);
  CollisionScene out;
  out.planes = planes;
  out.obstacles.reserve(obstacles.size() - near.size());
  size_t next = 0;  // into near
  for (size_t i = 0; i < obstacles.size(); ++i) {
    if (next < near.size() && near[next] == static_cast<int>(i)) {
      ++next;
      continue;
    }
    out.obstacles.push_back(obstacles[i]);
  }
  return out;
}

std::vector<int> CollisionScene::CaneNearIndices(CaneId cane_id,
                                                 const Eigen::Vector3d& point_in_base,
                                                 double radius_m) const {
  std::vector<int> near;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    if (IsCaneNear(obstacles[i], cane_id, point_in_base, radius_m)) near.push_back(static_cast<int>(i));
  }
  return near;
}

absl::StatusOr<std::vector<Obstacle>> StubChords(const VineModel& model, std::span<const Cut> made,
                                                 const Cut& cut, const RobotModel& robot,
                                                 const SceneOptions& options) {
  if (auto s = options.Validate(); !s.ok()) return s;
  if (auto s = model.Validate(); !s.ok()) return s;
  if (auto s = robot.Validate(); !s.ok()) return s;
  if (!cut.point.allFinite()) return absl::InvalidArgumentError("cut.point: non-finite");
  const VineModel before = WithoutFallenWood(model, made);
  const std::optional<size_t> i = before.IndexOf(cut.cane_id);
  if (!i) return std::vector<Obstacle>{};
  std::vector<Cut> with_cut(made.begin(), made.end());
  with_cut.push_back(cut);
  const VineModel after = WithoutFallenWood(model, with_cut);
  const std::optional<size_t> j = after.IndexOf(cut.cane_id);
  if (!j) return std::vector<Obstacle>{};  // it falls whole
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  std::vector<Obstacle> uncut, stub;
  AppendCaneChords(before.canes[*i], base_from_platform, options.cane_segment_m,
                   options.default_margin_m, &uncut);
  AppendCaneChords(after.canes[*j], base_from_platform, options.cane_segment_m,
                   options.default_margin_m, &stub);
  std::vector<Obstacle> out;
  for (const Obstacle& o : stub)
    if (std::none_of(uncut.begin(), uncut.end(),
                     [&](const Obstacle& u) { return SameObstacle(o, u); }))
      out.push_back(o);
  return out;
}

}  // namespace vb::plan
