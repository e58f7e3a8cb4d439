// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/fcl_checker.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <vector>

#include "fcl/broadphase/broadphase_dynamic_AABB_tree.h"
#include "fcl/geometry/bvh/BVH_model.h"
#include "fcl/geometry/shape/capsule.h"
#include "fcl/geometry/shape/halfspace.h"
#include "fcl/geometry/shape/sphere.h"
#include "fcl/math/bv/OBBRSS.h"
#include "fcl/narrowphase/collision.h"
#include "fcl/narrowphase/collision_object.h"
#include "fcl/narrowphase/distance.h"

namespace vb::plan {
namespace {

using Geometry = std::shared_ptr<fcl::CollisionGeometryd>;
using Mesh = fcl::BVHModel<fcl::OBBRSSd>;

// Slices around a capsule of this radius (4 stacks per quarter turn: square-ish facets).
int Slices(double radius_m) {
  if (radius_m < 0.01) return 16;
  if (radius_m < 0.03) return 24;
  return 48;
}

// Vertices on the true surface, so every facet lies inside it by at most r (1 - cos(step)),
// step the angle between neighbouring vertices.
double Tolerance(double radius_m) {
  return radius_m * (1.0 - std::cos(2.0 * M_PI / Slices(radius_m)));
}

// Appends the tessellation of capsule (a, b, r) to vertices/triangles.
void Tessellate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                std::vector<fcl::Vector3d>& vertices, std::vector<fcl::Triangle>& triangles) {
  const int n = Slices(r), m = n / 4;
  const double length = (b - a).norm();
  const Eigen::Vector3d u = length > 0 ? Eigen::Vector3d((b - a) / length) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d v = u.unitOrthogonal(), w = u.cross(v);
  const int first = static_cast<int>(vertices.size());
  // Rings from the pole beyond a to the pole beyond b; the two equators coincide for a sphere.
  std::vector<std::pair<Eigen::Vector3d, double>> rings;  // centre, ring radius
  for (int i = 1; i <= m; ++i) {
    const double phi = i * (M_PI / 2) / m;
    rings.emplace_back(a - r * std::cos(phi) * u, r * std::sin(phi));
  }
  for (int i = (length > 0 ? m : m - 1); i >= 1; --i) {
    const double phi = i * (M_PI / 2) / m;
    rings.emplace_back(b + r * std::cos(phi) * u, r * std::sin(phi));
  }
  vertices.push_back(a - r * u);
  for (const auto& [c, rr] : rings) {
    for (int k = 0; k < n; ++k) {
      const double t = 2.0 * M_PI * k / n;
      vertices.push_back(c + rr * (std::cos(t) * v + std::sin(t) * w));
    }
  }
  vertices.push_back(b + r * u);
  const int pole_a = first, pole_b = static_cast<int>(vertices.size()) - 1;
  auto at = [&](int ring, int k) { return first + 1 + ring * n + (k % n); };
  const int n_rings = static_cast<int>(rings.size());
  for (int k = 0; k < n; ++k) {
    triangles.emplace_back(pole_a, at(0, k + 1), at(0, k));
    triangles.emplace_back(pole_b, at(n_rings - 1, k), at(n_rings - 1, k + 1));
    for (int ring = 0; ring + 1 < n_rings; ++ring) {
      triangles.emplace_back(at(ring, k), at(ring, k + 1), at(ring + 1, k + 1));
      triangles.emplace_back(at(ring, k), at(ring + 1, k + 1), at(ring + 1, k));
    }
  }
}

Geometry MakeMesh(const std::vector<Capsule>& capsules, double inflate_m) {
  std::vector<fcl::Vector3d> vertices;
  std::vector<fcl::Triangle> triangles;
  for (const Capsule& c : capsules) Tessellate(c.a, c.b, c.radius + inflate_m, vertices, triangles);
  auto mesh = std::make_shared<Mesh>();
  mesh->beginModel();
  mesh->addSubModel(vertices, triangles);
  mesh->endModel();
  return mesh;
}

// A 20 m x 20 m x 1 m box mesh filling the forbidden side of a plane.
Geometry MakePlaneBox(const HalfSpace& h) {
  const Eigen::Vector3d n = h.normal.normalized();
  const Eigen::Vector3d v = n.unitOrthogonal(), w = n.cross(v);
  const Eigen::Vector3d origin = n * (h.offset - h.margin_m);
  std::vector<fcl::Vector3d> vertices;
  for (int i = 0; i < 8; ++i) {
    vertices.push_back(origin + ((i & 1) ? 10.0 : -10.0) * v + ((i & 2) ? 10.0 : -10.0) * w +
                       ((i & 4) ? 1.0 : 0.0) * n);
  }
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  std::vector<fcl::Triangle> triangles;
  for (const auto& f : faces) {
    triangles.emplace_back(f[0], f[1], f[2]);
    triangles.emplace_back(f[0], f[2], f[3]);
  }
  auto mesh = std::make_shared<Mesh>();
  mesh->beginModel();
  mesh->addSubModel(vertices, triangles);
  mesh->endModel();
  return mesh;
}

// An FCL capsule (or sphere) and the pose that puts it on segment (a, b), in the frame of a, b.
std::pair<Geometry, fcl::Transform3d> MakePrimitive(const Capsule& c, double inflate_m) {
  fcl::Transform3d pose = fcl::Transform3d::Identity();
  pose.translation() = 0.5 * (c.a + c.b);
  const double length = (c.b - c.a).norm();
  if (length <= 0) return {std::make_shared<fcl::Sphered>(c.radius + inflate_m), pose};
  pose.linear() =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), (c.b - c.a) / length)
          .toRotationMatrix();
  return {std::make_shared<fcl::Capsuled>(c.radius + inflate_m, length), pose};
}

// One arm body part: its geometry and its fixed pose in its link frame.
struct ArmPart {
  int frame;
  int body;
  fcl::Transform3d link_from_part;
  std::unique_ptr<fcl::CollisionObjectd> object;
  std::vector<Capsule> capsules;  // its geometry in the link frame (for plane distances)
};

struct CollideData {
  bool hit = false;
};

bool CollideCallback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  auto* d = static_cast<CollideData*>(data);
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(o1, o2, request, result);
  if (result.isCollision()) d->hit = true;
  return d->hit;  // true stops the broadphase
}

class FclChecker : public CollisionChecker {
 public:
  FclChecker(const RobotModel& robot, const CollisionScene& scene, FclMode mode) : mode_(mode) {
    lever_m_ = JointLeverArms(robot);
    const std::vector<LinkBody> bodies = robot.BodiesWithTool();
    for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
      if (mode == FclMode::kMesh) {
        parts_.push_back(ArmPart{bodies[b].frame, b, fcl::Transform3d::Identity(),
                                 std::make_unique<fcl::CollisionObjectd>(
                                     MakeMesh(bodies[b].capsules, 0.0)),
                                 bodies[b].capsules});
        continue;
      }
      for (const Capsule& c : bodies[b].capsules) {
        auto [geometry, pose] = MakePrimitive(c, 0.0);
        parts_.push_back(ArmPart{bodies[b].frame, b, pose,
                                 std::make_unique<fcl::CollisionObjectd>(geometry), {c}});
      }
    }
    for (const auto& [bi, bj] : robot.SelfCollisionPairs()) {
      for (int i = 0; i < static_cast<int>(parts_.size()); ++i) {
        for (int j = 0; j < static_cast<int>(parts_.size()); ++j) {
          if (parts_[i].body == bi && parts_[j].body == bj) self_pairs_.emplace_back(i, j);
        }
      }
    }
    for (const Obstacle& o : scene.obstacles) {
      if (mode == FclMode::kMesh) {
        obstacles_.push_back(
            std::make_unique<fcl::CollisionObjectd>(MakeMesh({o.capsule}, o.margin_m)));
      } else {
        auto [geometry, pose] = MakePrimitive(o.capsule, o.margin_m);
        obstacles_.push_back(std::make_unique<fcl::CollisionObjectd>(geometry, pose));
      }
    }
    planes_geometry_ = scene.planes;
    for (const HalfSpace& h : scene.planes) {
      if (mode == FclMode::kMesh) {
        planes_.push_back(std::make_unique<fcl::CollisionObjectd>(MakePlaneBox(h)));
      } else {
        // FCL's half-space is the solid n . x <= d; ours is the free side, so flip it.
        planes_.push_back(std::make_unique<fcl::CollisionObjectd>(
            std::make_shared<fcl::Halfspaced>(-h.normal, -(h.offset - h.margin_m))));
      }
    }
    std::vector<fcl::CollisionObjectd*> raw;
    for (auto& o : obstacles_) raw.push_back(o.get());
    manager_.registerObjects(raw);
    manager_.setup();
  }

  bool IsFree(const Joints& q) override {
    ++checks_;
    try {
      Place(q);
      for (auto& part : parts_) {
        for (auto& plane : planes_) {
          fcl::CollisionRequestd request;
          fcl::CollisionResultd result;
          fcl::collide(part.object.get(), plane.get(), request, result);
          if (result.isCollision()) return false;
        }
        CollideData data;
        manager_.collide(part.object.get(), &data, CollideCallback);
        if (data.hit) return false;
      }
      for (const auto& [i, j] : self_pairs_) {
        fcl::CollisionRequestd request;
        fcl::CollisionResultd result;
        fcl::collide(parts_[i].object.get(), parts_[j].object.get(), request, result);
        if (result.isCollision()) return false;
      }
      return true;
    } catch (const std::exception&) {
      return false;
    }
  }

  double Clearance(const Joints& q) override {
    ++checks_;
    try {
      Place(q);
      double best = std::numeric_limits<double>::infinity();
      auto pair_distance = [&](fcl::CollisionObjectd* a, fcl::CollisionObjectd* b) {
        fcl::DistanceRequestd request(false, mode_ == FclMode::kPrimitives);
        fcl::DistanceResultd result;
        const double d = fcl::distance(a, b, request, result);
        if (d < 0 && mode_ == FclMode::kMesh) {
          // Meshes have no signed distance: report overlap as a negative number.
          best = std::min(best, -std::numeric_limits<double>::min());
          return;
        }
        best = std::min(best, d);
      };
      const auto frames = LinkFrames(q);
      for (auto& part : parts_) {
        for (auto& o : obstacles_) pair_distance(part.object.get(), o.get());
        if (mode_ == FclMode::kMesh) {
          for (auto& p : planes_) pair_distance(part.object.get(), p.get());
          continue;
        }
        // FCL 0.7's GJK distance to a half-space calls a support function libccd lacks (a
        // crash); a capsule's distance to a plane is exact and short anyway.
        for (const HalfSpace& h : planes_geometry_) {
          for (const Capsule& c : part.capsules) {
            const Eigen::Vector3d a = frames[part.frame] * c.a, b = frames[part.frame] * c.b;
            best = std::min(best, (h.offset - h.margin_m) -
                                      std::max(h.normal.dot(a), h.normal.dot(b)) - c.radius);
          }
        }
      }
      for (const auto& [i, j] : self_pairs_) {
        pair_distance(parts_[i].object.get(), parts_[j].object.get());
      }
      return best;
    } catch (const std::exception&) {
      return -std::numeric_limits<double>::infinity();
    }
  }

 private:
  void Place(const Joints& q) {
    const auto frames = LinkFrames(q);
    for (auto& part : parts_) {
      part.object->setTransform(frames[part.frame] * part.link_from_part);
      part.object->computeAABB();
    }
  }

  FclMode mode_;
  std::vector<ArmPart> parts_;
  std::vector<std::pair<int, int>> self_pairs_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> obstacles_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> planes_;
  std::vector<HalfSpace> planes_geometry_;
  fcl::DynamicAABBTreeCollisionManagerd manager_;
};

}  // namespace

double MeshToleranceM(double radius_m) { return Tolerance(radius_m); }

double MeshToleranceM(const RobotModel& robot, const CollisionScene& scene) {
  double worst = 0.0;
  for (const LinkBody& body : robot.BodiesWithTool()) {
    for (const Capsule& c : body.capsules) worst = std::max(worst, Tolerance(c.radius));
  }
  for (const Obstacle& o : scene.obstacles) {
    worst = std::max(worst, Tolerance(o.capsule.radius + o.margin_m));
  }
  return worst;
}

int MeshTriangles(const RobotModel& robot, int body) {
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  if (body < 0 || body >= static_cast<int>(bodies.size())) return 0;
  std::vector<fcl::Vector3d> vertices;
  std::vector<fcl::Triangle> triangles;
  for (const Capsule& c : bodies[body].capsules) Tessellate(c.a, c.b, c.radius, vertices, triangles);
  return static_cast<int>(triangles.size());
}

std::unique_ptr<CollisionChecker> MakeFclChecker(const RobotModel& robot,
                                                const CollisionScene& scene, FclMode mode) {
  return std::make_unique<FclChecker>(robot, scene, mode);
}

}  // namespace vb::plan
