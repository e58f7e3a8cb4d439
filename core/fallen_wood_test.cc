// SPDX-License-Identifier: Apache-2.0
#include "core/fallen_wood.h"

#include <optional>

#include "core/vine_model_test_util.h"
#include "gtest/gtest.h"

namespace vb {
namespace {

Cane Line(int64_t id, std::optional<int> parent, Eigen::Vector3d a, Eigen::Vector3d b) {
  return StraightCane(static_cast<int>(id), parent, parent ? CaneKind::kCane : CaneKind::kTrunk, a,
                      b, 0.02);
}

// Trunk 1 up to z = 1 (radius 2 cm) in a head sphere at z = 0.97; cane 2 grows from the trunk
// axis at z = 0.6 (a water shoot), cane 3 from the head's surface 6 cm off the axis at z = 0.95,
// cane 4 from cane 3 0.2 m along it, cane 5 from cane 4.
VineModel Vine() {
  VineModel m;
  m.canes.push_back(Line(1, std::nullopt, {0, 0, 0}, {0, 0, 1}));
  m.canes.push_back(Line(2, 1, {0, 0, 0.6}, {0.3, 0, 0.6}));
  m.canes.push_back(Line(3, 1, {0.06, 0, 0.95}, {0.66, 0, 0.95}));
  m.canes.push_back(Line(4, 3, {0.26, 0, 0.95}, {0.26, 0, 1.4}));
  m.canes.push_back(Line(5, 4, {0.26, 0, 1.2}, {0.4, 0, 1.3}));
  m.head.spheres.push_back({{0, 0, 0.97}, 0.07});
  return m;
}

std::vector<int64_t> Ids(const std::vector<CaneId>& ids) {
  std::vector<int64_t> out;
  for (CaneId id : ids) out.push_back(id.value);
  return out;
}

TEST(FallenWood, ChildrenBeyondTheCutFallWithTheirDescendants) {
  const VineModel vine = Vine();
  const FallingWood fall = WoodFallingFromCut(vine, 2, 0.1);  // cane 3, before cane 4's base
  EXPECT_FALSE(fall.cut_cane_whole);
  EXPECT_FALSE(fall.head);
  EXPECT_EQ(Ids(fall.canes), (std::vector<int64_t>{4, 5}));
  EXPECT_TRUE(WoodFallingFromCut(vine, 2, 0.3).canes.empty());  // beyond cane 4's base
}

TEST(FallenWood, ACutAtTheBaseDropsTheWholeCaneFirst) {
  const FallingWood fall = WoodFallingFromCut(Vine(), 3, 0.0);
  EXPECT_TRUE(fall.cut_cane_whole);
  EXPECT_EQ(Ids(fall.canes), (std::vector<int64_t>{4, 5}));
}

TEST(FallenWood, CanesOfTheHeadHangOnTheTrunkTopAndATrunkCutDropsTheHead) {
  const VineModel vine = Vine();
  // Cane 3's base projects onto the trunk's axis at 0.95, below a cut at 0.97, but lies off the
  // axis: it hangs on the top and falls with the head; cane 2, on the axis at 0.6, stays.
  const FallingWood fall = WoodFallingFromCut(vine, 0, 0.97);
  EXPECT_TRUE(fall.head);
  EXPECT_EQ(Ids(fall.canes), (std::vector<int64_t>{3, 4, 5}));
  const FallingWood low = WoodFallingFromCut(vine, 0, 0.5);
  EXPECT_EQ(Ids(low.canes), (std::vector<int64_t>{2, 3, 4, 5}));
  // A cut at the very top leaves the head.
  EXPECT_FALSE(WoodFallingFromCut(vine, 0, 1.0).head);
}

TEST(FallenWood, AfterCutsTakesTheLowestCutIgnoresUnknownIndicesAndValidates) {
  const VineModel vine = Vine();
  ASSERT_TRUE(vine.Validate().ok()) << vine.Validate();
  std::vector<FallingWood> falls;
  const VineModel after = AfterCuts(vine, {{2, 0.5}, {2, 0.1}, {99, 0.0}}, &falls);
  EXPECT_TRUE(after.Validate().ok()) << after.Validate();
  ASSERT_EQ(falls.size(), 1u);  // one per cut cane, for its lowest cut
  EXPECT_EQ(Ids(falls[0].canes), (std::vector<int64_t>{4, 5}));
  ASSERT_TRUE(after.IndexOf(CaneId{3}));
  EXPECT_NEAR(after.canes[*after.IndexOf(CaneId{3})].polyline.Length(), 0.1, 1e-12);
  EXPECT_FALSE(after.IndexOf(CaneId{4}));
  EXPECT_FALSE(after.IndexOf(CaneId{5}));
  EXPECT_EQ(after.canes.size(), 3u);
  EXPECT_EQ(after.head.spheres.size(), 1u);
  // Obstacles, wires and posts do not fall.
  VineModel with_trellis = vine;
  with_trellis.obstacles.push_back(
      WoodObstacle{Line(9, std::nullopt, {0, 0, 0}, {0, 0, 0.2}).polyline});
  with_trellis.wires.push_back(Wire{WireId{1}, {{-1, 0, 1}, {1, 0, 1}}});
  const VineModel kept = AfterCuts(with_trellis, {{0, 0.97}, {2, 0.0}});
  EXPECT_EQ(kept.obstacles.size(), 1u);
  EXPECT_EQ(kept.wires.size(), 1u);
  const VineModel no_trunk_top = AfterCuts(vine, {{0, 0.97}});
  EXPECT_TRUE(no_trunk_top.head.spheres.empty());
  EXPECT_TRUE(no_trunk_top.Validate().ok()) << no_trunk_top.Validate();
}

}  // namespace
}  // namespace vb
