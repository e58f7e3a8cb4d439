// SPDX-License-Identifier: Apache-2.0
#include "sim/vine_generator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/vine_test_util.h"

namespace vb::sim {
namespace {

using ::testing::HasSubstr;
using test::CanesOfKind;
using test::DistanceToAxis;
using test::ExpectSameCanes;
using test::kSeed;
using test::kVines;
using test::MustGenerate;
using test::WireZAt;

// Proper crossing of segments ab and cd in the x-z plane (the front camera's view).
bool SegmentsCrossXZ(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d) {
  auto orient = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    return (q.x() - p.x()) * (r.z() - p.z()) - (q.z() - p.z()) * (r.x() - p.x());
  };
  const double o1 = orient(a, b, c), o2 = orient(a, b, d);
  const double o3 = orient(c, d, a), o4 = orient(c, d, b);
  return o1 * o2 < 0.0 && o3 * o4 < 0.0;
}

bool CanesCross(const Polyline3& p, const Polyline3& q) {
  for (size_t i = 0; i + 1 < p.points.size(); ++i) {
    for (size_t j = 0; j + 1 < q.points.size(); ++j) {
      if (SegmentsCrossXZ(p.points[i], p.points[i + 1], q.points[j], q.points[j + 1])) return true;
    }
  }
  return false;
}

TEST(VineGenerator, IsDeterministicForSeedAndIndex) {
  const Scene a = MustGenerate(kSeed, 7);
  const Scene b = MustGenerate(kSeed, 7);
  EXPECT_EQ(a.vine_position_m, b.vine_position_m);
  ExpectSameCanes(a.vine, b.vine, 0.0);
  ASSERT_EQ(a.vine.wires.size(), b.vine.wires.size());
  for (size_t i = 0; i < a.vine.wires.size(); ++i) {
    EXPECT_EQ(a.vine.wires[i].points, b.vine.wires[i].points);
  }
  ASSERT_EQ(a.neighbours.size(), b.neighbours.size());
  for (size_t i = 0; i < a.neighbours.size(); ++i) ExpectSameCanes(a.neighbours[i], b.neighbours[i], 0.0);
}

TEST(VineGenerator, DifferentSeedsAndIndicesGiveDifferentVines) {
  const Scene a = MustGenerate(kSeed, 3);
  const Scene b = MustGenerate(kSeed + 1, 3);
  const Scene c = MustGenerate(kSeed, 4);
  auto tip = [](const Scene& s) { return s.vine.canes[1].polyline.points.back(); };
  EXPECT_GT((tip(a) - tip(b)).norm(), 1e-3);
  EXPECT_GT((tip(a) - tip(c) - Eigen::Vector3d(1.8, 0, 0)).norm(), 1e-3);
  // Neighbouring stops are different vines, not copies shifted along the row.
  const Scene d = MustGenerate(kSeed, 5);
  EXPECT_GT((d.vine.canes[0].polyline.points.back() - c.vine.canes[0].polyline.points.back() -
             Eigen::Vector3d(1.8, 0, 0)).norm(), 1e-3);
}

TEST(VineGenerator, EveryGeneratedModelValidates) {
  for (int k = -5; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    ASSERT_TRUE(s.vine.Validate().ok()) << "vine " << k << ": " << s.vine.Validate();
    ASSERT_EQ(s.neighbours.size(), 2u);
    for (const VineModel& n : s.neighbours) {
      ASSERT_TRUE(n.Validate().ok()) << n.Validate();
      EXPECT_TRUE(n.wires.empty());
      EXPECT_TRUE(n.posts.empty());
      EXPECT_FALSE(n.canes.empty());
      EXPECT_FALSE(n.head.spheres.empty());
    }
  }
}

TEST(VineGenerator, VineStandsAtItsRowPosition) {
  const VineGeneratorOptions options;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    EXPECT_EQ(s.vine_index, k);
    EXPECT_EQ(s.seed, kSeed);
    EXPECT_LE(std::abs(s.vine_position_m - k * options.vine_spacing_m), 0.1);
    const Eigen::Vector3d base = s.vine.canes[0].polyline.points.front();
    EXPECT_NEAR(base.x(), s.vine_position_m - k * options.vine_spacing_m, 1e-9);
    EXPECT_NEAR(base.z(), 0.0, 1e-12);
    EXPECT_NEAR(base.y(), options.vine_plane_y_m, 0.06);
  }
}

TEST(VineGenerator, TrunkAndHeadHavePlausibleShape) {
  const VineGeneratorOptions options;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    const Cane& trunk = s.vine.canes.front();
    ASSERT_EQ(trunk.id, CaneId(1));
    EXPECT_EQ(trunk.kind, CaneKind::kTrunk);
    EXPECT_FALSE(trunk.parent_id.has_value());
    EXPECT_EQ(CanesOfKind(s.vine, CaneKind::kTrunk).size(), 1u);
    const Polyline3& line = trunk.polyline;
    const double top_z = line.points.back().z();
    EXPECT_GE(top_z, options.trunk_height_min_m - 1e-9);
    EXPECT_LE(top_z, options.trunk_height_max_m + 1e-9);
    for (size_t i = 1; i < line.points.size(); ++i) {
      EXPECT_GT(line.points[i].z(), line.points[i - 1].z());  // grows up, no kinks back down
    }
    for (double r : line.radii) {
      EXPECT_GE(2 * r, 0.9 * options.trunk_diameter_min_m * 0.8);
      EXPECT_LE(2 * r, 1.05 * options.trunk_diameter_max_m);
    }
    EXPECT_LT(line.radii.back(), line.radii.front());  // tapers
    EXPECT_GT(line.radii.back(), 0.7 * line.radii.front());  // ... a little

    // Head: 5-15 spheres clustered on the trunk top, its top just below the fruiting wire.
    const auto& spheres = s.vine.head.spheres;
    EXPECT_GE(spheres.size(), 5u);
    EXPECT_LE(spheres.size(), 15u);
    double head_top = -1.0;
    for (const Sphere& sp : spheres) {
      head_top = std::max(head_top, sp.center.z() + sp.radius);
      EXPECT_LT((sp.center - line.points.back()).norm(), 0.25);
    }
    ASSERT_FALSE(s.vine.wires.empty());
    double fruiting_z = 10.0;
    for (const Wire& w : s.vine.wires) fruiting_z = std::min(fruiting_z, WireZAt(w, line.points.back().x()));
    EXPECT_LE(head_top, fruiting_z + 1e-6) << "vine " << k;
    EXPECT_GE(head_top, fruiting_z - 0.1) << "vine " << k;
  }
}

TEST(VineGenerator, CaneCountsAndSizesStayInRange) {
  const VineGeneratorOptions options;
  double min_length = 10, max_length = 0, min_d = 1, max_d = 0;
  int forks = 0, water_shoots = 0;
  std::set<size_t> counts;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    const auto canes = CanesOfKind(s.vine, CaneKind::kCane);
    EXPECT_GE(canes.size(), 8u);
    EXPECT_LE(canes.size(), 25u);
    counts.insert(canes.size());
    for (const Cane* c : canes) {
      const Polyline3& line = c->polyline;
      const double length = line.Length();
      EXPECT_GE(length, 0.97 * options.cane_length_min_m) << "cane " << c->id.value;
      EXPECT_LE(length, 1.03 * options.cane_length_max_m) << "cane " << c->id.value;
      const double d = 2 * line.radii.front();
      EXPECT_GE(d, options.cane_diameter_min_m - 1e-9);
      EXPECT_LE(d, options.cane_diameter_max_m + 1e-9);
      const double ratio = line.radii.back() / line.radii.front();
      EXPECT_GE(ratio, 0.38);
      EXPECT_LE(ratio, 0.62);
      for (double r : line.radii) EXPECT_LE(r, 1.05 * line.radii.front());
      min_length = std::min(min_length, length);
      max_length = std::max(max_length, length);
      min_d = std::min(min_d, d);
      max_d = std::max(max_d, d);
      if (*c->parent_id != CaneId(1)) ++forks;
      if (*c->parent_id == CaneId(1) &&
          DistanceToAxis(s.vine.canes[0].polyline, line.points.front()) < 1e-6) {
        ++water_shoots;
      }
    }
    const auto spurs = CanesOfKind(s.vine, CaneKind::kSpur);
    EXPECT_GE(spurs.size(), 1u);
    EXPECT_LE(spurs.size(), 4u);
    for (const Cane* sp : spurs) {
      EXPECT_EQ(*sp->parent_id, CaneId(1));
      EXPECT_GE(sp->polyline.Length(), 0.029);
      EXPECT_LE(sp->polyline.Length(), 0.101);
      EXPECT_GE(2 * sp->polyline.radii.front(), 0.0099);
      EXPECT_GE(sp->polyline.points.size(), 3u);
    }
  }
  // The ranges are actually used, not just respected.
  EXPECT_LT(min_length, 0.45);
  EXPECT_GT(max_length, 1.4);
  EXPECT_LT(min_d, 0.006);
  EXPECT_GT(max_d, 0.012);
  EXPECT_GT(counts.size(), 8u);
  EXPECT_GT(forks, kVines / 2);
  EXPECT_GT(water_shoots, kVines / 4);
}

TEST(VineGenerator, CaneBasesLieOnTheirParents) {
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    for (const Cane& c : s.vine.canes) {
      if (c.kind == CaneKind::kTrunk) continue;
      const Eigen::Vector3d& base = c.polyline.points.front();
      const auto parent = s.vine.IndexOf(*c.parent_id);
      ASSERT_TRUE(parent.has_value());
      ASSERT_LT(s.vine.canes[*parent].id, c.id);  // parents come first
      const double on_axis = DistanceToAxis(s.vine.canes[*parent].polyline, base);
      bool on_head = false;
      if (*c.parent_id == CaneId(1)) {
        for (const Sphere& sp : s.vine.head.spheres) {
          on_head |= std::abs((base - sp.center).norm() - sp.radius) < 1e-9;
        }
      }
      EXPECT_TRUE(on_axis < 1e-9 || on_head) << "vine " << k << " cane " << c.id.value;
    }
  }
}

TEST(VineGenerator, CanesAreSmoothAndDenselySampled) {
  for (int k = 0; k < 20; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    for (const Cane& c : s.vine.canes) {
      if (c.kind == CaneKind::kTrunk) continue;
      const auto& p = c.polyline.points;
      const double max_step = c.kind == CaneKind::kSpur ? 0.0125 : 0.031;
      for (size_t i = 1; i < p.size(); ++i) {
        EXPECT_LE((p[i] - p[i - 1]).norm(), max_step + 1e-9);
        if (i + 1 < p.size()) {
          const Eigen::Vector3d u = (p[i] - p[i - 1]).normalized();
          const Eigen::Vector3d v = (p[i + 1] - p[i]).normalized();
          EXPECT_LT(std::acos(std::clamp(u.dot(v), -1.0, 1.0)), 0.6)
              << "vine " << k << " cane " << c.id.value << " point " << i;
        }
      }
    }
  }
}

TEST(VineGenerator, CanesRestOnWiresWithoutPassingThroughThem) {
  for (int k = 0; k < 30; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    for (const Cane& c : s.vine.canes) {
      if (c.kind == CaneKind::kTrunk) continue;
      const auto arc = c.polyline.ArcLengths();
      for (size_t i = 0; i < c.polyline.points.size(); ++i) {
        if (arc[i] < 0.02) continue;  // the base sits on its parent
        for (const Wire& w : s.vine.wires) {
          for (size_t j = 0; j + 1 < w.points.size(); ++j) {
            EXPECT_GE(PointSegmentDistance(c.polyline.points[i], w.points[j], w.points[j + 1]),
                      c.polyline.radii[i] + w.radius - 2e-4)
                << "vine " << k << " cane " << c.id.value << " point " << i;
          }
        }
      }
    }
  }
}

TEST(VineGenerator, CanesStayNearTheVinePlaneAndAboveGround) {
  const VineGeneratorOptions options;
  size_t inside = 0, total = 0;
  double max_offset = 0;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    for (const Cane& c : s.vine.canes) {
      for (const Eigen::Vector3d& p : c.polyline.points) {
        EXPECT_GE(p.z(), 0.0);
        const double offset = std::abs(p.y() - options.vine_plane_y_m);
        max_offset = std::max(max_offset, offset);
        inside += offset < 0.15;
        ++total;
      }
    }
  }
  EXPECT_GT(static_cast<double>(inside) / total, 0.95);
  EXPECT_LT(max_offset, 0.3);
  EXPECT_GT(max_offset, 0.05);  // not flat: canes have depth
}

TEST(VineGenerator, CanesCrossEachOtherInTheImagePlane) {
  int crossing = 0;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    const auto canes = CanesOfKind(s.vine, CaneKind::kCane);
    bool found = false;
    for (size_t i = 0; i < canes.size() && !found; ++i) {
      for (size_t j = i + 1; j < canes.size() && !found; ++j) {
        // Skip parent/child pairs: they meet at the fork by construction.
        if (canes[i]->parent_id == canes[j]->id || canes[j]->parent_id == canes[i]->id) continue;
        found = CanesCross(canes[i]->polyline, canes[j]->polyline);
      }
    }
    crossing += found;
  }
  EXPECT_GE(crossing, kVines * 8 / 10);
}

TEST(VineGenerator, SomeCanesLieAlongTheWires) {
  // A cane lies along a wire if >= 15 cm of it run within 2 cm above/beside the wire.
  int draped_vines = 0;
  for (int k = 0; k < kVines; ++k) {
    const Scene s = MustGenerate(kSeed, k);
    bool draped = false;
    for (const Cane& c : s.vine.canes) {
      if (c.kind != CaneKind::kCane) continue;
      for (const Wire& w : s.vine.wires) {
        double run = 0.0;
        const auto& p = c.polyline.points;
        for (size_t i = 1; i < p.size() && !draped; ++i) {
          const double dz = p[i].z() - WireZAt(w, p[i].x());
          const bool near = std::abs(dz) < 0.02 && std::abs(p[i].y() - w.points[0].y()) < 0.02;
          run = near ? run + (p[i] - p[i - 1]).norm() : 0.0;
          draped = run >= 0.15;
        }
      }
    }
    draped_vines += draped;
  }
  EXPECT_GE(draped_vines, kVines / 2);
}

TEST(VineGenerator, OptionsShapeTheVine) {
  VineGeneratorOptions options;
  options.canes_min = options.canes_max = 12;
  options.fork_probability = 0.0;
  options.old_spurs_min = options.old_spurs_max = 0;
  options.foliage_wires_min = options.foliage_wires_max = 3;
  for (int k = 0; k < 10; ++k) {
    const Scene s = MustGenerate(kSeed, k, options);
    EXPECT_EQ(CanesOfKind(s.vine, CaneKind::kCane).size(), 12u);
    EXPECT_TRUE(CanesOfKind(s.vine, CaneKind::kSpur).empty());
    for (const Cane& c : s.vine.canes) {
      if (c.parent_id) {
        EXPECT_EQ(*c.parent_id, CaneId(1)) << "no forks";
      }
    }
    EXPECT_EQ(s.vine.wires.size(), 4u);
  }
}

TEST(VineGeneratorOptions, DefaultsAreValid) { EXPECT_TRUE(VineGeneratorOptions().Validate().ok()); }

TEST(VineGeneratorOptions, InvalidOptionsRejectNamingTheField) {
  struct Case {
    std::string field;
    void (*mutate)(VineGeneratorOptions&);
  };
  const std::vector<Case> cases = {
      {"vine_spacing_m", [](VineGeneratorOptions& o) { o.vine_spacing_m = 0; }},
      {"vine_plane_y_m", [](VineGeneratorOptions& o) { o.vine_plane_y_m = -1; }},
      {"trunk_height_min_m", [](VineGeneratorOptions& o) { o.trunk_height_min_m = 1.5; }},
      {"trunk_diameter_max_m", [](VineGeneratorOptions& o) { o.trunk_diameter_max_m = NAN; }},
      {"canes_min", [](VineGeneratorOptions& o) { o.canes_min = 0; }},
      {"canes_min", [](VineGeneratorOptions& o) { o.canes_min = 30; }},
      {"fork_probability", [](VineGeneratorOptions& o) { o.fork_probability = 1.5; }},
      {"cane_length_min_m", [](VineGeneratorOptions& o) { o.cane_length_min_m = -0.1; }},
      {"cane_length_min_m", [](VineGeneratorOptions& o) { o.cane_length_min_m = 2.0; }},
      {"cane_diameter_min_m", [](VineGeneratorOptions& o) { o.cane_diameter_min_m = 0.02; }},
      {"old_spurs_min", [](VineGeneratorOptions& o) { o.old_spurs_min = -1; }},
      {"old_spurs_min", [](VineGeneratorOptions& o) { o.old_spurs_min = 5; }},
      {"head_radius_m", [](VineGeneratorOptions& o) { o.head_radius_m = 0; }},
      {"fruiting_wire_min_m", [](VineGeneratorOptions& o) { o.fruiting_wire_min_m = 1.1; }},
      {"foliage_wires_min", [](VineGeneratorOptions& o) { o.foliage_wires_min = -1; }},
      {"foliage_wires_min", [](VineGeneratorOptions& o) { o.foliage_wires_min = 4; }},
      {"wire_radius_m", [](VineGeneratorOptions& o) { o.wire_radius_m = 0; }},
      {"post_spacing_m", [](VineGeneratorOptions& o) { o.post_spacing_m = INFINITY; }},
      {"post_radius_m", [](VineGeneratorOptions& o) { o.post_radius_m = -0.04; }},
      {"post_height_m", [](VineGeneratorOptions& o) { o.post_height_m = 0.95; }},
      {"backdrop_y_m", [](VineGeneratorOptions& o) { o.backdrop_y_m = 0.5; }},
  };
  for (const Case& c : cases) {
    VineGeneratorOptions options;
    c.mutate(options);
    const absl::Status status = options.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.field;
    EXPECT_THAT(std::string(status.message()), HasSubstr(c.field));
    const absl::StatusOr<Scene> scene = GenerateScene(kSeed, 0, options);
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << c.field;
  }
}

}  // namespace
}  // namespace vb::sim
