// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/connect.h"

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

Polyline3 Line(Eigen::Vector3d a, Eigen::Vector3d b, double radius = 0.004, int n = 10) {
  Polyline3 line;
  for (int i = 0; i <= n; ++i) {
    line.points.push_back(a + (b - a) * (static_cast<double>(i) / n));
    line.radii.push_back(radius);
  }
  return line;
}

HeadModel Head() {
  HeadModel head;
  head.spheres.push_back({{0, 0.8, 1.0}, 0.05});
  return head;
}

TEST(ConnectCanes, GrowsATreeFromTheTrunkAndHead) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  std::vector<Polyline3> canes = {
      Line({0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}),        // A: from the head surface outward
      Line({0.3, 0.8, 1.5}, {0.3, 0.8, 1.075}),       // B: tip end 2 mm from A's middle
      Line({1.0, 0.9, 0.3}, {1.0, 0.9, 0.8}),         // C: far from everything
      Line({0.0, 0.8, 0.3}, {0.0, 0.8, 0.7}, 0.02),   // D: the trunk seen again
      Line({-0.05, 0.8, 1.03}, {-0.1, 0.8, 1.05}),    // E: a short stub on the head
  };
  ConnectSummary summary;
  const auto model = ConnectCanes(canes, trunk, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.attached, 3);
  EXPECT_EQ(summary.unattached, 1);
  EXPECT_EQ(summary.inside_trunk_or_head, 1);
  ASSERT_EQ(model->canes.size(), 4u);
  EXPECT_EQ(model->canes[0].kind, CaneKind::kTrunk);
  EXPECT_EQ(model->head.spheres.size(), 1u);
  // The stub attaches first (it touches the head), then A; B hangs on A, base at its old tip.
  const Cane* a = nullptr;
  const Cane* b = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.kind == CaneKind::kSpur) EXPECT_EQ(cane.parent_id, CaneId(1));
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.6, 0.8, 1.1))) a = &cane;
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.3, 0.8, 1.5))) b = &cane;
  }
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(a->parent_id, CaneId(1));
  EXPECT_EQ(a->kind, CaneKind::kCane);
  EXPECT_EQ(b->parent_id, a->id);
  // B's first point lies on A.
  const Eigen::Vector3d base = b->polyline.points.front();
  EXPECT_LT(PointSegmentDistance(base, {0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}), 1e-9);
}

TEST(ConnectCanes, TheStereoTrunkReplacesTheSilhouetteAxis) {
  const Polyline3 silhouette = Line({0.01, 0.8, 0}, {0.01, 0.8, 0.95}, 0.03);
  const std::vector<Polyline3> canes = {Line({0.0, 0.8, 0.9}, {0.0, 0.8, 0.35}, 0.02)};
  const auto model = ConnectCanes(canes, silhouette, Head(), ConnectOptions());
  ASSERT_TRUE(model.ok());
  ASSERT_EQ(model->canes.size(), 1u);
  const Polyline3& trunk = model->canes[0].polyline;
  EXPECT_NEAR(trunk.points.front().z(), 0.0, 1e-9);   // reaches the ground
  EXPECT_NEAR(trunk.points.back().z(), 0.9, 1e-9);    // oriented upward
  EXPECT_NEAR(trunk.points.back().x(), 0.0, 1e-9);    // the stereo axis
}

TEST(ConnectCanes, WithoutATrunkTheLowestThickCaneStandsIn) {
  const std::vector<Polyline3> canes = {Line({0, 0.8, 0.9}, {0, 0.8, 0.2}, 0.02),
                                        Line({0, 0.8, 0.9}, {0.4, 0.8, 1.0})};
  const auto model = ConnectCanes(canes, std::nullopt, HeadModel(), ConnectOptions());
  ASSERT_TRUE(model.ok());
  ASSERT_EQ(model->canes.size(), 2u);
  EXPECT_EQ(model->canes[0].kind, CaneKind::kTrunk);
  EXPECT_LT(model->canes[0].polyline.points.front().z(), 0.25);
  EXPECT_EQ(model->canes[1].parent_id, CaneId(1));
}

TEST(ConnectCanes, EmptyInputAndBadCanes) {
  const auto empty = ConnectCanes({}, std::nullopt, HeadModel(), ConnectOptions());
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->canes.empty());
  Polyline3 bad = Line({0, 0, 0}, {1, 0, 0});
  bad.points[3].x() = std::nan("");
  const auto result = ConnectCanes({bad}, std::nullopt, HeadModel(), ConnectOptions());
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(result.status().message()).find("canes[0]"), std::string::npos);
  ConnectOptions options;
  options.max_attach_m = -1;
  EXPECT_FALSE(ConnectCanes({}, std::nullopt, HeadModel(), options).ok());
}

}  // namespace
}  // namespace vb::reconstruct
