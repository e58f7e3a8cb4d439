// SPDX-License-Identifier: Apache-2.0
#include "core/model_metrics.h"

#include <cmath>
#include <string>

#include "gtest/gtest.h"
#include "core/vine_model_test_util.h"

namespace vb {
namespace {

VineModel Truth() {
  VineModel m;
  m.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0, 0.8, 0}, {0, 0.8, 1.0}));
  m.canes.push_back(StraightCane(2, 1, CaneKind::kCane, {0, 0.8, 1.0}, {0.5, 0.8, 1.0}));
  m.canes.push_back(StraightCane(3, 1, CaneKind::kCane, {0, 0.8, 1.0}, {-0.5, 0.8, 1.2}));
  m.head.spheres.push_back({{0, 0.8, 1.0}, 0.05});
  Wire w;
  w.id = WireId(1);
  w.points = {{-2.0, 0.8, 0.95}, {2.0, 0.8, 0.95}};
  m.wires.push_back(w);
  return m;
}

TEST(EvaluateReconstruction, PerfectModelScoresOne) {
  const auto m = EvaluateReconstruction(Truth(), Truth());
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->cane_recall, 1.0);
  EXPECT_DOUBLE_EQ(m->cane_precision, 1.0);
  EXPECT_DOUBLE_EQ(m->connectivity, 1.0);
  EXPECT_DOUBLE_EQ(m->connectivity_strict, 1.0);
  EXPECT_DOUBLE_EQ(m->wire_recall, 1.0);
  EXPECT_NEAR(m->head_enclosed_fraction, 1.0, 1e-9);
  EXPECT_NEAR(m->head_volume_ratio, 1.0, 1e-9);
  EXPECT_NEAR(m->truth_cane_length_m, 1.0 + 0.5 + std::hypot(0.5, 0.2), 1e-9);
}

TEST(EvaluateReconstruction, CountsMissingShiftedAndDisconnectedLength) {
  VineModel model = Truth();
  model.canes.erase(model.canes.begin() + 2);  // cane 3 missing: recall loses its length
  // A false cane, and cane 2 hung on it instead of on the trunk: recalled but not connected.
  model.canes.push_back(StraightCane(9, 1, CaneKind::kCane, {0, 0.9, 0.5}, {0.3, 0.9, 0.5}));
  model.canes[1].parent_id = CaneId(9);
  const auto m = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m.ok()) << m.status();
  const double total = 1.5 + std::hypot(0.5, 0.2);
  EXPECT_NEAR(m->cane_recall, 1.5 / total, 0.01);
  EXPECT_NEAR(m->connectivity, 1.0 / total, 0.01);
  EXPECT_NEAR(m->connectivity_strict, 1.0 / total, 0.01);
  EXPECT_NEAR(m->cane_precision, 1.5 / 1.8, 0.01);
  // Wires and head missing entirely.
  model.wires.clear();
  model.head.spheres.clear();
  const auto m2 = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m2.ok());
  EXPECT_EQ(m2->wire_recall, 0.0);
  EXPECT_EQ(m2->head_enclosed_fraction, 0.0);
}

// A side cane (4) grows from the middle of cane 2. Hung on the trunk in the model, it counts as
// connected (the trunk is the root) but not strictly (its true parent is cane 2, not the trunk);
// hung on cane 3 it is neither.
TEST(EvaluateReconstruction, StrictConnectivityAsksWhereTheRouteMeetsTheTrunk) {
  VineModel truth = Truth();
  truth.canes.push_back(StraightCane(4, 2, CaneKind::kCane, {0.25, 0.8, 1.0}, {0.25, 0.8, 1.3}));
  const double total = 1.8 + std::hypot(0.5, 0.2);
  auto m = EvaluateReconstruction(truth, truth);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->connectivity, 1.0);
  EXPECT_DOUBLE_EQ(m->connectivity_strict, 1.0);
  VineModel on_trunk = truth;
  on_trunk.canes[3].parent_id = CaneId(1);
  m = EvaluateReconstruction(on_trunk, truth);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->cane_recall, 1.0);
  EXPECT_DOUBLE_EQ(m->connectivity, 1.0);
  // Its first centimetre lies within 10 mm of cane 2, which is strictly connected.
  EXPECT_NEAR(m->connectivity_strict, (total - 0.29) / total, 0.005);
  VineModel on_cane3 = truth;
  on_cane3.canes[3].parent_id = CaneId(3);
  m = EvaluateReconstruction(on_cane3, truth);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_NEAR(m->connectivity, (total - 0.29) / total, 0.005);
  EXPECT_NEAR(m->connectivity_strict, (total - 0.29) / total, 0.005);
}

TEST(EvaluateReconstruction, HalfTheHeadIsHalfEnclosed) {
  VineModel model = Truth();
  // A huge sphere whose surface passes through the true head's centre plane x = 0.
  model.head.spheres = {{{1.0, 0.8, 1.0}, 1.0}};
  const auto m = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m->head_enclosed_fraction, 0.5, 0.03);
}

TEST(EvaluateReconstruction, ToleranceIsTenMillimetres) {
  VineModel model = Truth();
  for (Cane& c : model.canes)
    for (Eigen::Vector3d& p : c.polyline.points) p.y() += 0.009;
  auto m = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m.ok());
  EXPECT_GT(m->cane_recall, 0.99);
  for (Cane& c : model.canes)
    for (Eigen::Vector3d& p : c.polyline.points) p.y() += 0.002;
  m = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m.ok());
  EXPECT_LT(m->cane_recall, 0.01);
}

// The true head is a 5 cm sphere at the top of the trunk, where canes 2 and 3 start: the last
// 10 cm of the trunk and the first 10 cm of each cane lie within 5 cm of its surface.
TEST(EvaluateReconstruction, RecallNearTheHeadScoresTheLengthNearItsSurface) {
  auto m = EvaluateReconstruction(Truth(), Truth());
  ASSERT_TRUE(m.ok());
  const double total = 1.5 + std::hypot(0.5, 0.2);
  EXPECT_DOUBLE_EQ(m->cane_recall_near_head, 1.0);
  EXPECT_NEAR(m->near_head_length_fraction, 0.3 / total, 0.01);
  // Cane 2 starts 10 cm out: the near-head length loses 8 cm of it (its first centimetre lies
  // within the 10 mm match distance of the trunk's top and cane 3's base, its last of the new
  // base); recall loses the same 8 cm.
  VineModel model = Truth();
  model.canes[1] = StraightCane(2, 1, CaneKind::kCane, {0.1, 0.8, 1.0}, {0.5, 0.8, 1.0});
  m = EvaluateReconstruction(model, Truth());
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m->cane_recall_near_head, 0.22 / 0.30, 0.01);
  EXPECT_NEAR(m->cane_recall, (total - 0.08) / total, 0.002);
  EXPECT_NEAR(m->near_head_length_fraction, 0.3 / total, 0.01);  // a property of the truth
  // A truth without a head has no length near it.
  VineModel headless = Truth();
  headless.head.spheres.clear();
  m = EvaluateReconstruction(model, headless);
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->cane_recall_near_head, 1.0);
  EXPECT_DOUBLE_EQ(m->near_head_length_fraction, 0.0);
  MetricsOptions bad;
  bad.near_head_m = -0.05;
  const auto rejected = EvaluateReconstruction(model, Truth(), bad);
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(std::string(rejected.status().message()).find("near_head_m"), std::string::npos)
      << rejected.status();
}

TEST(EvaluateReconstruction, RejectsInvalidModel) {
  VineModel model = Truth();
  model.canes[1].polyline.points[0].x() = std::nan("");
  const auto m = EvaluateReconstruction(model, Truth());
  ASSERT_FALSE(m.ok());
  EXPECT_NE(std::string(m.status().message()).find("model:"), std::string::npos);
}

TEST(SphereUnionVolume, OneSphereAndTwoOverlappingSpheres) {
  const double r = 0.05;
  const double sphere = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(SphereUnionVolume({{Eigen::Vector3d(0, 0, 1), r}}, 0.001), sphere, 0.01 * sphere);
  // Two spheres whose centres are r apart: 2V minus the lens, V_lens = pi (4r + d)(2r - d)^2 / 12.
  const double lens = M_PI * (4 * r + r) * r * r / 12.0;
  EXPECT_NEAR(SphereUnionVolume({{Eigen::Vector3d(0, 0, 1), r}, {Eigen::Vector3d(r, 0, 1), r}},
                                0.001),
              2 * sphere - lens, 0.01 * sphere);
  EXPECT_EQ(SphereUnionVolume({}, 0.001), 0.0);
}

}  // namespace
}  // namespace vb
