// SPDX-License-Identifier: Apache-2.0
// Helpers shared by the vine generator tests (test-only; not part of vb_sim).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::sim::test {

inline constexpr uint64_t kSeed = 20260714;
inline constexpr int kVines = 50;

inline Scene MustGenerate(uint64_t seed, int index, const VineGeneratorOptions& options = {}) {
  absl::StatusOr<Scene> scene = GenerateScene(seed, index, options);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene.ok() ? *std::move(scene) : Scene{};
}

inline std::vector<const Cane*> CanesOfKind(const VineModel& model, CaneKind kind) {
  std::vector<const Cane*> out;
  for (const Cane& c : model.canes) {
    if (c.kind == kind) out.push_back(&c);
  }
  return out;
}

inline double DistanceToAxis(const Polyline3& line, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    best = std::min(best, PointSegmentDistance(p, line.points[i], line.points[i + 1]));
  }
  return best;
}

// Height of the wire polyline at platform x (linear between its points).
inline double WireZAt(const Wire& wire, double x) {
  for (size_t i = 0; i + 1 < wire.points.size(); ++i) {
    const Eigen::Vector3d& a = wire.points[i];
    const Eigen::Vector3d& b = wire.points[i + 1];
    if (x >= a.x() && x <= b.x()) return a.z() + (b.z() - a.z()) * (x - a.x()) / (b.x() - a.x());
  }
  return std::numeric_limits<double>::quiet_NaN();
}

inline void ExpectSameCanes(const VineModel& a, const VineModel& b, double dx) {
  ASSERT_EQ(a.canes.size(), b.canes.size());
  for (size_t i = 0; i < a.canes.size(); ++i) {
    const Polyline3& pa = a.canes[i].polyline;
    const Polyline3& pb = b.canes[i].polyline;
    ASSERT_EQ(a.canes[i].id, b.canes[i].id);
    ASSERT_EQ(a.canes[i].parent_id, b.canes[i].parent_id);
    ASSERT_EQ(a.canes[i].kind, b.canes[i].kind);
    ASSERT_EQ(pa.points.size(), pb.points.size());
    for (size_t k = 0; k < pa.points.size(); ++k) {
      ASSERT_LT((pa.points[k] - (pb.points[k] + Eigen::Vector3d(dx, 0, 0))).norm(), 1e-9);
      ASSERT_DOUBLE_EQ(pa.radii[k], pb.radii[k]);
    }
  }
  ASSERT_EQ(a.head.spheres.size(), b.head.spheres.size());
  for (size_t i = 0; i < a.head.spheres.size(); ++i) {
    EXPECT_LT((a.head.spheres[i].center - b.head.spheres[i].center -
               Eigen::Vector3d(dx, 0, 0)).norm(), 1e-9);
  }
}

}  // namespace vb::sim::test
