// SPDX-License-Identifier: Apache-2.0
#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/vine_model_test_util.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::sim {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;
using ::testing::UnorderedElementsAre;

Polyline3 Straight(const Eigen::Vector3d& from, const Eigen::Vector3d& to, int segments,
                   double radius) {
  Polyline3 line;
  for (int i = 0; i <= segments; ++i) {
    line.points.push_back(from + (to - from) * (static_cast<double>(i) / segments));
    line.radii.push_back(radius);
  }
  return line;
}

// Trunk 1 (z 0 -> 0.9) topped by a head sphere; cane 2 from the head along +x (1 m, z = 1.0);
// forks 3 at x = 0.2 and 4 at x = 0.6 of cane 2; 5 grows from fork 4 and 6 from fork 3; water
// shoot 7 from the trunk at z = 0.3; spur 8 on the head.
Scene HandmadeScene() {
  Scene s;
  VineModel& v = s.vine;
  v.canes.push_back(CaneOf(1, std::nullopt, CaneKind::kTrunk,
                             Straight({0, 0.8, 0}, {0, 0.8, 0.9}, 9, 0.02)));
  v.head.spheres.push_back({Eigen::Vector3d(0, 0.8, 0.95), 0.05});
  v.canes.push_back(CaneOf(2, 1, CaneKind::kCane, Straight({0.05, 0.8, 1.0}, {1.05, 0.8, 1.0}, 50, 0.005)));
  v.canes.push_back(CaneOf(3, 2, CaneKind::kCane, Straight({0.25, 0.8, 1.0}, {0.25, 0.8, 1.5}, 20, 0.003)));
  v.canes.push_back(CaneOf(4, 2, CaneKind::kCane, Straight({0.65, 0.8, 1.0}, {0.65, 0.8, 1.5}, 20, 0.003)));
  v.canes.push_back(CaneOf(5, 4, CaneKind::kCane, Straight({0.65, 0.8, 1.2}, {0.9, 0.8, 1.4}, 10, 0.002)));
  v.canes.push_back(CaneOf(6, 3, CaneKind::kCane, Straight({0.25, 0.8, 1.3}, {0.0, 0.8, 1.5}, 10, 0.002)));
  v.canes.push_back(CaneOf(7, 1, CaneKind::kCane, Straight({0, 0.8, 0.3}, {-0.5, 0.8, 0.5}, 20, 0.003)));
  v.canes.push_back(CaneOf(8, 1, CaneKind::kSpur, Straight({0, 0.8, 1.0}, {0, 0.8, 1.06}, 6, 0.006)));
  EXPECT_TRUE(v.Validate().ok()) << v.Validate();
  return s;
}

std::vector<int64_t> Ids(const std::vector<CaneId>& ids) {
  std::vector<int64_t> out;
  for (CaneId id : ids) out.push_back(id.value);
  return out;
}

std::vector<int64_t> RemainingIds(const SimWorld& world) {
  std::vector<int64_t> out;
  for (const Cane& c : world.scene().vine.canes) out.push_back(c.id.value);
  return out;
}

const Cane& CaneById(const SimWorld& world, int id) {
  return world.scene().vine.canes[*world.scene().vine.IndexOf(CaneId(id))];
}

TEST(SimWorld, ApplyCutTruncatesTheCaneAtTheNearestAxisPoint) {
  SimWorld world(HandmadeScene());
  // 4 mm in front of the axis (inside the 5 mm radius), at x = 0.95 -> arc 0.9.
  absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(2), {0.95, 0.796, 1.0});
  ASSERT_TRUE(cut.ok()) << cut.status();
  EXPECT_EQ(cut->cane_id, CaneId(2));
  EXPECT_NEAR(cut->arc_length_m, 0.9, 1e-9);
  EXPECT_NEAR(cut->distance_m, 0.004, 1e-9);
  EXPECT_THAT(cut->removed, IsEmpty());
  const Polyline3& line = CaneById(world, 2).polyline;
  EXPECT_NEAR(line.Length(), 0.9, 1e-9);
  EXPECT_NEAR((line.points.back() - Eigen::Vector3d(0.95, 0.8, 1.0)).norm(), 0.0, 1e-9);
  EXPECT_EQ(line.points.size(), line.radii.size());
  EXPECT_TRUE(world.scene().vine.Validate().ok());
}

TEST(SimWorld, ApplyCutRemovesCanesBeyondTheCutWithTheirDescendants) {
  SimWorld world(HandmadeScene());
  // Between the forks: fork 4 (at arc 0.6) and its child 5 fall; fork 3 (arc 0.2) and 6 stay.
  absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(2), {0.45, 0.8, 1.0});
  ASSERT_TRUE(cut.ok()) << cut.status();
  EXPECT_THAT(Ids(cut->removed), UnorderedElementsAre(4, 5));
  EXPECT_THAT(RemainingIds(world), ElementsAre(1, 2, 3, 6, 7, 8));
  EXPECT_NEAR(CaneById(world, 2).polyline.Length(), 0.4, 1e-9);
  EXPECT_EQ(world.scene().vine.head.spheres.size(), 1u);
  EXPECT_TRUE(world.scene().vine.Validate().ok());
}

TEST(SimWorld, ApplyCutAtTheBaseRemovesTheWholeCane) {
  SimWorld world(HandmadeScene());
  absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(2), {0.0495, 0.8, 1.0});
  ASSERT_TRUE(cut.ok()) << cut.status();
  ASSERT_FALSE(cut->removed.empty());
  EXPECT_EQ(cut->removed.front(), CaneId(2));  // the cane itself first
  EXPECT_THAT(Ids(cut->removed), UnorderedElementsAre(2, 3, 4, 5, 6));
  EXPECT_THAT(RemainingIds(world), ElementsAre(1, 7, 8));
  EXPECT_TRUE(world.scene().vine.Validate().ok());
}

TEST(SimWorld, ApplyCutOnTheTrunkDropsTheHeadAndWhatGrowsAboveTheCut) {
  {
    SimWorld world(HandmadeScene());
    // Above the water shoot: the head and everything on it falls; the water shoot stays.
    absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(1), {0.0, 0.8, 0.5});
    ASSERT_TRUE(cut.ok()) << cut.status();
    EXPECT_THAT(Ids(cut->removed), UnorderedElementsAre(2, 3, 4, 5, 6, 8));
    EXPECT_THAT(RemainingIds(world), ElementsAre(1, 7));
    EXPECT_THAT(world.scene().vine.head.spheres, IsEmpty());
    EXPECT_NEAR(CaneById(world, 1).polyline.Length(), 0.5, 1e-9);
  }
  {
    SimWorld world(HandmadeScene());
    absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(1), {0.01, 0.8, 0.2});
    ASSERT_TRUE(cut.ok()) << cut.status();
    EXPECT_THAT(Ids(cut->removed), UnorderedElementsAre(2, 3, 4, 5, 6, 7, 8));
    EXPECT_TRUE(world.scene().vine.Validate().ok());
  }
}

TEST(SimWorld, ApplyCutAcceptsPointsOnTheSurfaceWithinTolerance) {
  SimWorld world(HandmadeScene());
  // Cane 3 has radius 3 mm: a point 12 mm from its axis is 9 mm from the surface.
  absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(3), {0.262, 0.8, 1.4}, 0.01);
  ASSERT_TRUE(cut.ok()) << cut.status();
  EXPECT_NEAR(cut->distance_m, 0.012, 1e-9);
  EXPECT_NEAR(cut->arc_length_m, 0.4, 1e-9);
  EXPECT_THAT(Ids(cut->removed), IsEmpty());  // cane 6 grows at arc 0.3, below the cut
}

TEST(SimWorld, ApplyCutRejectsUnknownCane) {
  SimWorld world(HandmadeScene());
  absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(99), {0.5, 0.8, 1.0});
  EXPECT_EQ(cut.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(cut.status().message()), ::testing::HasSubstr("99"));
}

TEST(SimWorld, ApplyCutRejectsFallenCane) {
  SimWorld world(HandmadeScene());
  ASSERT_TRUE(world.ApplyCut(CaneId(2), {0.45, 0.8, 1.0}).ok());
  EXPECT_EQ(world.ApplyCut(CaneId(5), {0.7, 0.8, 1.24}).status().code(),
            absl::StatusCode::kNotFound);
}

TEST(SimWorld, ApplyCutRejectsFarPointAndLeavesTheWorldUnchanged) {
  SimWorld world(HandmadeScene());
  const absl::StatusOr<CutResult> cut = world.ApplyCut(CaneId(2), {0.5, 0.8, 1.03}, 0.01);
  EXPECT_EQ(cut.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(RemainingIds(world), ElementsAre(1, 2, 3, 4, 5, 6, 7, 8));
  EXPECT_NEAR(CaneById(world, 2).polyline.Length(), 1.0, 1e-9);
}

TEST(SimWorld, ApplyCutRejectsNonFiniteInput) {
  SimWorld world(HandmadeScene());
  EXPECT_EQ(world.ApplyCut(CaneId(2), {NAN, 0.8, 1.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(world.ApplyCut(CaneId(2), {0.5, INFINITY, 1.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(world.ApplyCut(CaneId(2), {0.5, 0.8, 1.0}, -0.01).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(world.ApplyCut(CaneId(2), {0.5, 0.8, 1.0}, NAN).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(world.scene().vine.canes.size(), 8u);
}

TEST(SimWorld, SpurPruningAGeneratedVineKeepsItValid) {
  // Cut every cane 5 cm above its base, as spur pruning would: forks beyond 5 cm fall, and the
  // model stays valid after every cut.
  for (int k = 0; k < 10; ++k) {
    absl::StatusOr<Scene> scene = GenerateScene(7, k);
    ASSERT_TRUE(scene.ok()) << scene.status();
    SimWorld world(*std::move(scene));
    std::vector<CaneId> canes;
    for (const Cane& c : world.scene().vine.canes) {
      if (c.kind == CaneKind::kCane) canes.push_back(c.id);
    }
    for (CaneId id : canes) {
      const auto index = world.scene().vine.IndexOf(id);
      if (!index) continue;  // fell with its parent
      const Polyline3& line = world.scene().vine.canes[*index].polyline;
      const Eigen::Vector3d at = line.PointAt(0.05);
      absl::StatusOr<CutResult> cut = world.ApplyCut(id, at);
      ASSERT_TRUE(cut.ok()) << cut.status();
      EXPECT_NEAR(cut->arc_length_m, 0.05, 1e-6);
      ASSERT_TRUE(world.scene().vine.Validate().ok()) << world.scene().vine.Validate();
    }
    for (const Cane& c : world.scene().vine.canes) {
      if (c.kind == CaneKind::kCane) {
        EXPECT_LE(c.polyline.Length(), 0.05 + 1e-6);
      }
    }
    EXPECT_FALSE(world.scene().vine.head.spheres.empty());
    EXPECT_GE(world.scene().vine.wires.size(), 3u);
    // Forks growing beyond 5 cm of their parent fell with it.
    for (const Cane& c : world.scene().vine.canes) {
      if (c.parent_id && *c.parent_id != CaneId(1)) {
        const Polyline3& parent =
            world.scene().vine.canes[*world.scene().vine.IndexOf(*c.parent_id)].polyline;
        double d = 1e9;
        for (size_t i = 0; i + 1 < parent.points.size(); ++i) {
          d = std::min(d, PointSegmentDistance(c.polyline.points.front(), parent.points[i],
                                               parent.points[i + 1]));
        }
        EXPECT_LT(d, 1e-6) << "a remaining fork must still grow from the remaining parent";
      }
    }
  }
}

}  // namespace
}  // namespace vb::sim
