// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/depth_sweep.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/cane_test_util.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using testing_util::ViewsOf;

// testing_util::CurvedCane bent out of the plane more (0.1 u^2) than the grow tests bend it.
Polyline3 CurvedCane(double x0, double x1, double z0, double slope) {
  return testing_util::CurvedCane(x0, x1, z0, slope, /*bend_out=*/0.1);
}

DepthSweepOptions On() {
  DepthSweepOptions options;
  options.enabled = true;
  return options;
}

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

TEST(SweepUnexplainedPaths, FindsAnUnexplainedCaneWithinFourMillimetres) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 truth = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  const std::vector<View2D> views = ViewsOf({truth}, rig);
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes, &summary).ok());
  ASSERT_GE(canes.size(), 1u);
  EXPECT_EQ(summary.added_canes, static_cast<int>(canes.size()));
  double length = 0.0, sum = 0.0;
  int points = 0;
  for (const Polyline3& cane : canes) {
    ASSERT_TRUE(cane.Validate("cane").ok());
    length += cane.Length();
    // Depth is only as good as the skeletons' ~0.5 px: where the cane runs at a shallow angle to
    // the epipolar lines a millimetre of depth moves its projection by a tenth of a pixel.
    for (const Eigen::Vector3d& p : cane.points) {
      const double d = DistanceToLine(p, truth);
      EXPECT_LT(d, 0.004);
      sum += d;
      ++points;
    }
    // Radius from the 2D width: the true 4 mm within 1.5 mm.
    EXPECT_NEAR(cane.radii.front(), 0.004, 0.0015);
  }
  EXPECT_LT(sum / points, 0.0015);
  EXPECT_NEAR(summary.added_length_m, length, 1e-9);
  // Most of the cane is found (its ends within the stretch's first and last samples).
  EXPECT_GT(length, 0.8 * truth.Length());
  // The first view's sweep explains the cane in the others: they add nothing more.
  EXPECT_EQ(canes.size(), 1u);
  EXPECT_GT(summary.stretches[0], 0);
  EXPECT_EQ(summary.stretches[1], 0);
  EXPECT_EQ(summary.stretches[2], 0);
}

TEST(SweepUnexplainedPaths, AddsNothingWhereACaneExplainsTheSkeleton) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 truth = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  const std::vector<View2D> views = ViewsOf({truth}, rig);
  std::vector<Polyline3> canes = {truth};
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes, &summary).ok());
  EXPECT_EQ(canes.size(), 1u);
  EXPECT_EQ(summary.added_canes, 0);
  for (size_t v = 0; v < views.size(); ++v) EXPECT_EQ(summary.stretches[v], 0) << v;
}

TEST(SweepUnexplainedPaths, FindsOnlyTheUnexplainedOneOfTwoCanes) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 known = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  const Polyline3 unknown = CurvedCane(-0.2, 0.2, 1.3, -0.3);
  const std::vector<View2D> views = ViewsOf({known, unknown}, rig);
  std::vector<Polyline3> canes = {known};
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes).ok());
  ASSERT_GE(canes.size(), 2u);
  EXPECT_EQ(canes[0].points, known.points);  // the canes given are left as they are
  for (size_t i = 1; i < canes.size(); ++i)
    for (const Eigen::Vector3d& p : canes[i].points) EXPECT_LT(DistanceToLine(p, unknown), 0.003);
}

// A ghost configuration: views 0 and 1 show one cane, view 2 the same cane 3 cm higher. Every
// pair of views is consistent with some 3D curve, no curve with all three.
TEST(SweepUnexplainedPaths, AddsNothingWhereTheThreeViewsDisagree) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 truth = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  Polyline3 shifted = truth;
  for (Eigen::Vector3d& p : shifted.points) p.z() += 0.03;
  const std::vector<View2D> a = ViewsOf({truth}, rig), b = ViewsOf({shifted}, rig);
  const std::vector<View2D> views = {a[0], a[1], b[2]};
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes, &summary).ok());
  EXPECT_GT(summary.samples, 0);
  EXPECT_TRUE(canes.empty());
  // Even where two views would be enough, the third sees the samples and contradicts them.
  DepthSweepOptions two = On();
  two.min_views = 2;
  std::vector<Polyline3> canes_two;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, two, Deadline::Infinite(),
                                    &canes_two).ok());
  EXPECT_TRUE(canes_two.empty());
}

// Views 0 and 1 show a cane, view 2 sees the same place with no skeleton near it: even where
// two supporting views are enough (min_views 2), a view that sees the samples and holds them far
// from its skeleton rejects them.
TEST(SweepUnexplainedPaths, RejectsSamplesThatASeeingViewContradicts) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 truth = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  std::vector<View2D> views = ViewsOf({truth}, rig);
  DepthSweepOptions two = On();
  two.min_views = 2;
  std::vector<Polyline3> control;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, two, Deadline::Infinite(),
                                    &control).ok());
  ASSERT_FALSE(control.empty());  // with all three views the cane is found
  views[2].segments.clear();
  views[2].nodes.clear();
  std::fill(views[2].centreline_distance_px.begin(), views[2].centreline_distance_px.end(),
            kCentrelineDistanceCapPx);
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, two, Deadline::Infinite(),
                                    &canes, &summary).ok());
  EXPECT_GT(summary.samples, 0);
  EXPECT_EQ(summary.accepted_samples, 0);
  EXPECT_TRUE(canes.empty());
}

// A straight cane along a wire: its skeleton lies on the wire's line in every view, where a
// wrongly segmented wire would lie too, and is left; without the wire lines it is found.
TEST(SweepUnexplainedPaths, LeavesSkeletonAlongAWireLine) {
  const RigCalibration rig = sim::MakeRig().value();
  Polyline3 cane;
  for (double x = -0.2; x <= 0.2 + 1e-9; x += 0.01) {
    cane.points.emplace_back(x, 0.85, 1.0);
    cane.radii.push_back(0.003);
  }
  VineModel model;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline = cane;
  model.canes.push_back(trunk);
  Wire wire;
  wire.id = WireId(1);
  wire.points = {Eigen::Vector3d(-0.5, 0.85, 1.0), Eigen::Vector3d(0.5, 0.85, 1.0)};
  model.wires.push_back(wire);
  SyntheticViewOptions drawn;
  drawn.draw_head = false;
  std::vector<View2D> views = SyntheticViews(model, rig, drawn, 40.0);
  for (const View2D& view : views) ASSERT_FALSE(view.wires.empty());
  std::vector<Polyline3> canes;
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes).ok());
  EXPECT_TRUE(canes.empty());
  for (View2D& view : views) view.wires.clear();
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(),
                                    &canes).ok());
  ASSERT_FALSE(canes.empty());
  for (const Eigen::Vector3d& p : canes[0].points) EXPECT_LT(DistanceToLine(p, cane), 0.004);
}

TEST(SweepUnexplainedPaths, LeavesTheCanesWhenDisabled) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 truth = CurvedCane(-0.25, 0.15, 0.9, 0.4);
  const std::vector<View2D> views = ViewsOf({truth}, rig);
  std::vector<Polyline3> canes;
  DepthSweepSummary summary;
  DepthSweepOptions options;
  options.enabled = false;  // on by default
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, options, Deadline::Infinite(),
                                    &canes, &summary).ok());
  EXPECT_TRUE(canes.empty());
  EXPECT_EQ(summary.samples, 0);
  // The same views with the defaults: the cane is found, so the test above can fail.
  ASSERT_TRUE(SweepUnexplainedPaths(views, rig, WorkingVolume{}, DepthSweepOptions{},
                                    Deadline::Infinite(), &canes, &summary).ok());
  EXPECT_EQ(canes.size(), 1u);
}

TEST(SweepUnexplainedPaths, RejectsAViewCountThatDisagreesWithTheRig) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = ViewsOf({CurvedCane(-0.25, 0.15, 0.9, 0.4)}, rig);
  views.pop_back();
  std::vector<Polyline3> canes;
  const absl::Status status =
      SweepUnexplainedPaths(views, rig, WorkingVolume{}, On(), Deadline::Infinite(), &canes);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("views"), std::string::npos);
}

TEST(DepthSweepOptions, ValidateRejectsBadFieldsByName) {
  EXPECT_TRUE(DepthSweepOptions{}.Validate().ok());
  const auto expect_rejected = [](DepthSweepOptions options, const char* field) {
    const absl::Status status = options.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  };
  DepthSweepOptions o;
  o.sample_px = 0;
  expect_rejected(o, "sweep.sample_px");
  o = {};
  o.depth_step_px = NAN;
  expect_rejected(o, "sweep.depth_step_px");
  o = {};
  o.accept_px = -1;
  expect_rejected(o, "sweep.accept_px");
  o = {};
  o.min_views = 1;
  expect_rejected(o, "sweep.min_views");
  o = {};
  o.max_step = 0;
  expect_rejected(o, "sweep.max_step");
  o = {};
  o.max_depths = 1;
  expect_rejected(o, "sweep.max_depths");
  o = {};
  o.max_radius_m = 0;
  expect_rejected(o, "sweep.max_radius_m");
  o = {};
  o.min_length_m = -0.1;
  expect_rejected(o, "sweep.min_length_m");
  o = {};
  o.line_margin_px = -1;
  expect_rejected(o, "sweep.line_margin_px");
  o = {};
  o.thick_margin_px = -1;
  expect_rejected(o, "sweep.thick_margin_px");
}

}  // namespace
}  // namespace vb::reconstruct
