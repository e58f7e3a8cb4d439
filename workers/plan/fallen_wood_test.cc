// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/fallen_wood.h"

#include "core/vine_model_test_util.h"
#include "gtest/gtest.h"

namespace vb::plan {
namespace {

Cane Line(int64_t id, std::optional<int> parent, Eigen::Vector3d a, Eigen::Vector3d b) {
  return StraightCane(static_cast<int>(id), parent, parent ? CaneKind::kCane : CaneKind::kTrunk, a,
                      b);
}

// Trunk 1 up to z = 1; cane 2 along +x from the top; cane 3 grows from cane 2 at x = 0.3, cane 4
// at x = 0.1; cane 5 grows from cane 3.
VineModel Vine() {
  VineModel m;
  m.canes.push_back(Line(1, std::nullopt, {0, 0, 0}, {0, 0, 1}));
  m.canes.push_back(Line(2, 1, {0, 0, 1}, {0.6, 0, 1}));
  m.canes.push_back(Line(3, 2, {0.3, 0, 1}, {0.3, 0, 1.4}));
  m.canes.push_back(Line(4, 2, {0.1, 0, 1}, {0.1, 0, 1.3}));
  m.canes.push_back(Line(5, 3, {0.3, 0, 1.2}, {0.5, 0, 1.3}));
  return m;
}

Cut At(int64_t cane, Eigen::Vector3d p) {
  Cut c;
  c.id = CutId{1};
  c.cane_id = CaneId{cane};
  c.point = p;
  return c;
}

TEST(FallenWood, WoodBeyondACutFallsAndTheRestStays) {
  const std::vector<Cut> cuts = {At(2, {0.2, 0, 1})};
  const VineModel after = WithoutFallenWood(Vine(), cuts);
  EXPECT_TRUE(after.Validate().ok()) << after.Validate();
  ASSERT_TRUE(after.IndexOf(CaneId{2}));
  EXPECT_NEAR(after.canes[*after.IndexOf(CaneId{2})].polyline.Length(), 0.2, 1e-12);
  EXPECT_TRUE(after.IndexOf(CaneId{4}));   // grows below the cut
  EXPECT_FALSE(after.IndexOf(CaneId{3}));  // beyond the cut
  EXPECT_FALSE(after.IndexOf(CaneId{5}));  // with its parent
  EXPECT_TRUE(after.IndexOf(CaneId{1}));
}

TEST(FallenWood, ACutAtTheBaseRemovesTheWholeCane) {
  const std::vector<Cut> cuts = {At(3, {0.3, 0, 1.0})};
  const VineModel after = WithoutFallenWood(Vine(), cuts);
  EXPECT_FALSE(after.IndexOf(CaneId{3}));
  EXPECT_FALSE(after.IndexOf(CaneId{5}));
  EXPECT_TRUE(after.IndexOf(CaneId{2}));
  EXPECT_TRUE(after.Validate().ok());
}

TEST(FallenWood, TheLowestOfSeveralCutsDecidesAndUnknownCanesAreIgnored) {
  std::vector<Cut> cuts = {At(2, {0.5, 0, 1}), At(2, {0.35, 0, 1}), At(99, {0, 0, 0})};
  const VineModel after = WithoutFallenWood(Vine(), cuts);
  EXPECT_NEAR(after.canes[*after.IndexOf(CaneId{2})].polyline.Length(), 0.35, 1e-12);
  EXPECT_TRUE(after.IndexOf(CaneId{3}));  // grows at 0.3, below the lowest cut
  EXPECT_EQ(after.canes.size(), 5u);
}

}  // namespace
}  // namespace vb::plan
