// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/depth_sweep_check.h"

#include <cmath>
#include <vector>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/cane_test_util.h"
#include "workers/reconstruct/depth_sweep.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using testing_util::ViewsOf;

Polyline3 CurvedCane(double radius_m) {
  Polyline3 line = testing_util::CurvedCane(-0.25, 0.15, 0.9, 0.4, /*bend_out=*/0.1);
  for (double& r : line.radii) r = radius_m;
  return line;
}

std::vector<ViewSamples> SamplesOf(const std::vector<View2D>& views, const RigCalibration& rig) {
  std::vector<ViewSamples> out;
  for (size_t v = 0; v < views.size(); ++v) out.emplace_back(views[v], rig.cameras[v], 4.0);
  return out;
}

// A ghost whose widths disagree: views 0 and 1 show the cane 4 mm in radius, view 2 the same
// axis 12 mm in radius. Every skeleton agrees; the radii the views imply differ threefold.
std::vector<View2D> GhostViews(const RigCalibration& rig) {
  const std::vector<View2D> thin = ViewsOf(CurvedCane(0.004), rig);
  const std::vector<View2D> thick = ViewsOf(CurvedCane(0.012), rig);
  return {thin[0], thin[1], thick[2]};
}

View2D BandView(int rows_from, int rows_to) {
  View2D view;
  view.width = 60;
  view.height = 60;
  view.classes = ClassImage(60, 60);
  for (int y = rows_from; y <= rows_to; ++y)
    for (int x = 0; x < 60; ++x) view.classes.set(x, y, PixelClass::kForeground);
  return view;
}

TEST(ForegroundWidthAcross, MeasuresABandAcrossItsDirection) {
  const View2D view = BandView(20, 26);  // 7 px wide
  // Half-pixel steps, each rounded to its pixel: within half a pixel.
  EXPECT_NEAR(ForegroundWidthAcross(view, {30, 23}, {1, 0}), 7.0, 0.5);
  // Off centre by 1.6 px, and along the other sense of the line: the same band.
  EXPECT_NEAR(ForegroundWidthAcross(view, {30, 24.6}, {-1, 0}), 7.0, 0.5);
  // Starting 2 px outside it, the nearest foreground within 2 px is found.
  EXPECT_NEAR(ForegroundWidthAcross(view, {30, 18}, {1, 0}), 7.0, 0.5);
  // Across a band 3 px wide: the width, not the walk's reach.
  EXPECT_NEAR(ForegroundWidthAcross(BandView(40, 42), {10, 41}, {1, 0}), 3.0, 0.5);
  // Nothing within 2 px, a zero direction, or a view without a class image: 0.
  EXPECT_DOUBLE_EQ(ForegroundWidthAcross(view, {30, 40}, {1, 0}), 0.0);
  EXPECT_DOUBLE_EQ(ForegroundWidthAcross(view, {30, 23}, {0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(ForegroundWidthAcross(View2D{}, {30, 23}, {1, 0}), 0.0);
  // At most max_half_px each way.
  EXPECT_DOUBLE_EQ(ForegroundWidthAcross(BandView(0, 59), {30, 30}, {1, 0}, 5.0), 11.0);
}

TEST(MeasureSweptRun, ATrueCaneAgreesInEveryView) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(0.004);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  const SweptRunFeatures f = MeasureSweptRun(cane, views, rig, SamplesOf(views, rig));
  EXPECT_EQ(f.views, 3);
  EXPECT_LT(f.width_log_spread, 0.3);
  EXPECT_LT(f.width_log_excess, 0.3);
  EXPECT_GT(f.foreground, 0.9);
  EXPECT_GT(f.tangent, 0.9);
  EXPECT_NEAR(f.mean_y_m, 0.8 + 0.1 * 0.4 * 0.4 / 3, 0.005);  // bend_out 0.1 u^2, u in [0, 0.4]
  EXPECT_GT(f.straightness, 0.95);
  EXPECT_LT(f.turning_per_m, 2.0);
}

TEST(MeasureSweptRun, AGhostsImpliedRadiiDisagree) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = GhostViews(rig);
  const SweptRunFeatures f = MeasureSweptRun(CurvedCane(0.004), views, rig, SamplesOf(views, rig));
  EXPECT_EQ(f.views, 3);
  EXPECT_NEAR(f.width_log_spread, std::log(3.0), 0.35);
  EXPECT_GT(f.width_log_excess, 0.6);  // view 2 shows it ~3 times as wide as it projects
}

TEST(MeasureSweptRun, LeavesOutAViewWithoutAClassImage) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = GhostViews(rig);
  views[2].classes = ClassImage();  // the thick view: without it the two thin views agree
  const SweptRunFeatures f = MeasureSweptRun(CurvedCane(0.004), views, rig, SamplesOf(views, rig));
  EXPECT_EQ(f.views, 2);
  EXPECT_LT(f.width_log_spread, 0.3);
  EXPECT_GT(f.foreground, 0.9);
}

TEST(MeasureSweptRun, ARunOffTheWoodLeavesTheForeground) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(0.004);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  Polyline3 off = cane;
  for (Eigen::Vector3d& p : off.points) p.z() += 0.03;
  const SweptRunFeatures f = MeasureSweptRun(off, views, rig, SamplesOf(views, rig));
  EXPECT_LT(f.foreground, 0.1);
  EXPECT_LT(f.tangent, 0.1);
}

TEST(MeasureSweptRun, TurningCountsABend) {
  const RigCalibration rig = sim::MakeRig().value();
  Polyline3 bent;
  // Two straight 10 cm legs at a right angle: pi/2 over 0.2 m.
  for (double s = 0.0; s <= 0.1 + 1e-9; s += 0.01) bent.points.emplace_back(s, 0.8, 1.0);
  for (double s = 0.01; s <= 0.1 + 1e-9; s += 0.01) bent.points.emplace_back(0.1, 0.8, 1.0 + s);
  bent.radii.assign(bent.points.size(), 0.004);
  const std::vector<View2D> views = ViewsOf(bent, rig);
  const SweptRunFeatures f = MeasureSweptRun(bent, views, rig, SamplesOf(views, rig));
  EXPECT_NEAR(f.turning_per_m, M_PI / 2 / 0.2, 0.5);
  EXPECT_NEAR(f.straightness, std::sqrt(2.0) * 0.1 / 0.2, 0.01);
}

DepthSweepOptions Checked(bool check) {
  DepthSweepOptions options;
  options.enabled = true;
  options.check = check;
  return options;
}

TEST(SweepCheck, DropsAGhostWhoseWidthsDisagree) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = GhostViews(rig);
  std::vector<Polyline3> unchecked;
  DepthSweepSummary off;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, Checked(false),
                                    Deadline::Infinite(), &unchecked, &off).ok());
  ASSERT_FALSE(unchecked.empty());  // the skeletons agree: without the check it is added
  ASSERT_EQ(off.added.size(), unchecked.size());
  EXPECT_FALSE(off.added[0].checked);
  EXPECT_EQ(off.rejected_canes, 0);
  std::vector<Polyline3> checked;
  DepthSweepSummary on;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, Checked(true),
                                    Deadline::Infinite(), &checked, &on).ok());
  EXPECT_TRUE(checked.empty());
  EXPECT_TRUE(on.added.empty());
  EXPECT_GE(on.rejected_canes, 1);
  EXPECT_GT(on.rejected_length_m, 0.1);
}

TEST(SweepCheck, KeepsATrueCane) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(0.004);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, Checked(true),
                                    Deadline::Infinite(), &canes, &summary).ok());
  ASSERT_EQ(canes.size(), 1u);
  EXPECT_GT(canes[0].Length(), 0.8 * cane.Length());
  EXPECT_TRUE(summary.added[0].checked);
  EXPECT_EQ(summary.rejected_canes, 0);
}

TEST(PassesCheck, EachLimitDropsWhatExceedsIt) {
  DepthSweepOptions options;  // spread 0.5, excess off, foreground off here
  options.check_min_foreground = 0.0;
  SweptRunFeatures f;
  f.width_log_spread = 0.49;
  f.width_log_excess = 5.0;
  f.foreground = 0.0;
  EXPECT_TRUE(PassesCheck(f, options));
  EXPECT_FALSE(PassesCheck(f, DepthSweepOptions{}));  // the default foreground limit, 0.5
  f.width_log_spread = 0.51;
  EXPECT_FALSE(PassesCheck(f, options));
  f.width_log_spread = 0.0;
  DepthSweepOptions excess = options;
  excess.check_max_width_log_excess = 0.4;
  EXPECT_FALSE(PassesCheck(f, excess));
  f.width_log_excess = 0.3;
  EXPECT_TRUE(PassesCheck(f, excess));
  DepthSweepOptions foreground = options;
  foreground.check_min_foreground = 0.5;
  EXPECT_FALSE(PassesCheck(f, foreground));
  f.foreground = 0.6;
  EXPECT_TRUE(PassesCheck(f, foreground));
}

// The excess limit alone (spread off) drops the same ghost: view 2 shows it three times as wide
// as its radius projects.
TEST(SweepCheck, TheExcessLimitAloneDropsTheGhost) {
  const RigCalibration rig = sim::MakeRig().value();
  DepthSweepOptions options = Checked(true);
  options.check_max_width_log_spread = 10.0;
  options.check_max_width_log_excess = 0.5;
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(GhostViews(rig), rig, WorkingVolume{}, options,
                                    Deadline::Infinite(), &canes, &summary).ok());
  EXPECT_TRUE(canes.empty());
  EXPECT_GE(summary.rejected_canes, 1);
}

TEST(DepthSweepOptions, ValidateRejectsBadCheckFieldsByName) {
  const auto expect_rejected = [](DepthSweepOptions options, const char* field) {
    const absl::Status status = options.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  };
  DepthSweepOptions o;
  o.check_max_width_log_spread = -0.1;
  expect_rejected(o, "sweep.check_max_width_log_spread");
  o = {};
  o.check_max_width_log_excess = INFINITY;
  expect_rejected(o, "sweep.check_max_width_log_excess");
  o = {};
  o.check_min_foreground = NAN;
  expect_rejected(o, "sweep.check_min_foreground");
  o = {};
  o.check_min_foreground = 1.5;
  expect_rejected(o, "sweep.check_min_foreground");
}

}  // namespace
}  // namespace vb::reconstruct
