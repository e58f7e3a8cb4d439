// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/join_images.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "core/vine_model_test_util.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// A point of OneCaneAcrossTheView's cane (x in [-0.1, 0.2]).
Eigen::Vector3d OnTheCane(double x) { return {x, 0.8, 0.9 + 0.1 * (x + 0.1) / 0.3}; }

TEST(JoinImages, AGapAlongTheCaneIsWoodInEveryView) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  const JoinImageEvidence e = MeasureJoinImages(OnTheCane(0.0), OnTheCane(0.06), views, rig);
  EXPECT_GE(e.gap_all_views, 0.99);
  EXPECT_GE(e.gap_best_two, 0.99);
  EXPECT_EQ(e.junction_views, 0.0);  // synthetic views have no junctions
  EXPECT_EQ(e.past_support, 0.0);
}

TEST(JoinImages, AGapOverBackgroundIsNotWood) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  // From a point 8 cm above the cane down onto it, over the backdrop but for its last samples.
  const Eigen::Vector3d point = OnTheCane(0.0);
  const JoinImageEvidence e =
      MeasureJoinImages(point + Eigen::Vector3d(0, 0, 0.08), point, views, rig);
  EXPECT_LT(e.gap_all_views, 0.2);
  EXPECT_LT(e.gap_best_two, 0.2);
  EXPECT_GT(e.gap_best_two, 0.0);  // the end on the cane is wood
}

TEST(JoinImages, TheSecondBestViewCounts) {
  const RigCalibration rig = sim::MakeRig().value();
  ASSERT_GE(rig.cameras.size(), 3u);
  std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  // The cane erased from all views but the first: one view is not enough.
  for (size_t v = 1; v < views.size(); ++v) {
    std::fill(views[v].classes.data.begin(), views[v].classes.data.end(),
              static_cast<uint8_t>(PixelClass::kBackground));
  }
  const JoinImageEvidence one = MeasureJoinImages(OnTheCane(0.0), OnTheCane(0.06), views, rig);
  EXPECT_EQ(one.gap_best_two, 0.0);
  EXPECT_EQ(one.gap_all_views, 0.0);
  // Back in the second view: the two best views show it all, though the others do not.
  views[1] = SyntheticViews(OneCaneAcrossTheView(), rig)[1];
  const JoinImageEvidence two = MeasureJoinImages(OnTheCane(0.0), OnTheCane(0.06), views, rig);
  EXPECT_GE(two.gap_best_two, 0.99);
  if (views.size() > 2) {
    EXPECT_EQ(two.gap_all_views, 0.0);
  }
}

// A junction node with three segments at `uv` (only its position and degree are read).
Node2D Junction(const Eigen::Vector2d& uv) {
  Node2D n;
  n.position = uv;
  n.segments = {0, 1, 2};
  return n;
}

TEST(JoinImages, JunctionsNearTheProjectedJoinPoint) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  const Eigen::Vector3d point = OnTheCane(0.05), base = point + Eigen::Vector3d(0, 0, 0.01);
  int seen = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    const auto uv = rig.cameras[v].Project(point);
    seen += uv && rig.cameras[v].InImage(*uv);
  }
  ASSERT_GE(seen, 2);
  const auto uv0 = rig.cameras[0].Project(point);
  ASSERT_TRUE(uv0 && rig.cameras[0].InImage(*uv0));
  // 4 px off in view 0: one view of `seen`.
  views[0].nodes.push_back(Junction(*uv0 + Eigen::Vector2d(4.0, 0.0)));
  EXPECT_DOUBLE_EQ(MeasureJoinImages(base, point, views, rig).junction_views, 1.0 / seen);
  // An end node (one segment) there does not count; a junction 8 px off does not either.
  Node2D end = Junction(*uv0);
  end.segments = {0};
  views[0].nodes = {end, Junction(*uv0 + Eigen::Vector2d(0.0, 8.0))};
  EXPECT_EQ(MeasureJoinImages(base, point, views, rig).junction_views, 0.0);
  // In every view that sees it: 1.
  for (size_t v = 0; v < views.size(); ++v) {
    if (const auto uv = rig.cameras[v].Project(point)) views[v].nodes.push_back(Junction(*uv));
  }
  EXPECT_DOUBLE_EQ(MeasureJoinImages(base, point, views, rig).junction_views, 1.0);
}

TEST(JoinImages, ANonFiniteLineHasNoEvidence) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  const JoinImageEvidence e = MeasureJoinImages(OnTheCane(0.0), {NAN, 0.8, 1.0}, views, rig);
  EXPECT_EQ(e.gap_all_views, 0.0);
  EXPECT_EQ(e.gap_best_two, 0.0);
  EXPECT_EQ(e.junction_views, 0.0);
  EXPECT_EQ(GapSupportByView(OnTheCane(0.0), {NAN, 0.8, 1.0}, views, rig),
            std::vector<double>(views.size(), 0.0));
}

TEST(JoinImageOptions, RejectsBadValuesNamingTheField) {
  EXPECT_TRUE(JoinImageOptions{}.Validate().ok());
  JoinImageOptions zero;  // the edges of the ranges are valid
  zero.gap.tolerance_px = 0;
  zero.gap.min_views = 0;
  zero.junction_radius_px = 0.0;
  EXPECT_TRUE(zero.Validate().ok()) << zero.Validate();
  const auto rejects = [](const JoinImageOptions& o, const std::string& field) {
    const absl::Status s = o.Validate();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(s.message().find("join_images." + field + " "), std::string::npos) << s;
  };
  for (const double bad : {0.0, -0.005, std::nan(""), HUGE_VAL}) {
    JoinImageOptions o;
    o.gap.step_m = bad;
    rejects(o, "gap.step_m");
  }
  JoinImageOptions o;
  o.gap.tolerance_px = -1;
  rejects(o, "gap.tolerance_px");
  o = {};
  o.gap.min_views = -1;
  rejects(o, "gap.min_views");
  for (const double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    o = {};
    o.junction_radius_px = bad;
    rejects(o, "junction_radius_px");
  }
}

}  // namespace
}  // namespace vb::reconstruct
