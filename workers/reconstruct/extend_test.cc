// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/extend.h"

#include <cmath>

#include "core/geometry.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// A smooth cane in the vine plane region (y ~ 0.8 m) from x0 to x1 along the row, rising and
// bending a little out of the plane, every 1 cm.
Cane CurvedCane(double x0, double x1) {
  Cane cane;
  cane.id = CaneId(2);
  cane.parent_id = CaneId(1);
  cane.kind = CaneKind::kCane;
  for (double x = x0; x <= x1 + 1e-9; x += 0.01) {
    const double u = x - x0;
    cane.polyline.points.emplace_back(x, 0.8 + 0.03 * u * u, 1.05 + 0.12 * u - 0.05 * u * u);
    cane.polyline.radii.push_back(0.005);
  }
  return cane;
}

VineModel VineWith(const Cane& cane) {
  VineModel model;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline.points = {{0.0, 0.8, 0.5}, {0.0, 0.8, 1.0}};
  trunk.polyline.radii = {0.015, 0.015};
  model.canes.push_back(trunk);
  model.canes.push_back(cane);
  return model;
}

int ImagesSeeing(const RigCalibration& rig, const Eigen::Vector3d& p) {
  int n = 0;
  for (const CameraCalibration& camera : rig.cameras) {
    const auto uv = camera.Project(p);
    n += uv && camera.InImage(*uv);
  }
  return n;
}

// The index of the cane's last point that two or more cameras see (0 if none).
size_t LastSeenByTwo(const RigCalibration& rig, const Cane& cane) {
  size_t last = 0;
  for (size_t i = 0; i < cane.polyline.points.size(); ++i)
    if (ImagesSeeing(rig, cane.polyline.points[i]) >= 2) last = i;
  return last;
}

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

// The first `n` points of the cane.
Cane Truncated(const Cane& cane, size_t n) {
  Cane out = cane;
  out.polyline.points.resize(n);
  out.polyline.radii.resize(n);
  return out;
}

ExtendOptions On() {
  ExtendOptions options;
  options.enabled = true;
  return options;
}

TEST(ExtendCanes, ExtendsATipSeenByOneCameraWithinTolerance) {
  const RigCalibration rig = sim::MakeRig().value();
  const Cane cane = CurvedCane(0.4, 1.5);
  // The cane leaves the two-view strip along the row: cut the model where it does.
  const size_t last_two = LastSeenByTwo(rig, cane);
  ASSERT_GT(last_two, 20u);
  ASSERT_LT(last_two + 10, cane.polyline.points.size());
  for (size_t i = last_two + 1; i < last_two + 8; ++i)
    ASSERT_EQ(ImagesSeeing(rig, cane.polyline.points[i]), 1) << i;
  const VineModel truth = VineWith(cane);
  const std::vector<View2D> views = SyntheticViews(truth, rig);
  VineModel model = VineWith(Truncated(cane, last_two + 1));
  const Eigen::Vector3d old_tip = model.canes[1].polyline.points.back();
  const double old_length = model.canes[1].polyline.Length();
  WorkingVolume volume;
  volume.box.max().x() = 1.6;  // the cane runs beyond the default volume's 1.1 m
  ExtendOptions options = On();
  options.max_tip_row_distance_m = 2.0;  // the tip lies ~1 m along the row from the trunk
  ExtendSummary summary;
  ASSERT_TRUE(ExtendCanes(views, rig, volume, options, &model, &summary).ok());
  EXPECT_EQ(summary.tips_extended, 1);
  const Polyline3& extended = model.canes[1].polyline;
  ASSERT_GT(extended.points.size(), last_two + 1);
  // Every added point lies within the metrics' 10 mm of the true cane, and the extension reaches
  // into the part only one camera sees.
  for (size_t i = last_two + 1; i < extended.points.size(); ++i)
    EXPECT_LT(DistanceToLine(extended.points[i], cane.polyline), 0.010) << i;
  EXPECT_GT((extended.points.back() - old_tip).norm(), 0.02);
  EXPECT_EQ(ImagesSeeing(rig, extended.points.back()), 1);
  EXPECT_NEAR(summary.added_length_m, extended.Length() - old_length, 1e-9);
  // The trunk is not extended.
  EXPECT_EQ(model.canes[0].polyline.points.size(), 2u);

  // A looser depth cap follows the cane further; its depth drifts with distance from the tip
  // (what the cap is for), but stays within tolerance over the first 4 cm.
  ExtendOptions loose = options;
  loose.max_depth_sd_m = 0.05;
  loose.second_difference_sd_m = 0.0003;
  VineModel far = VineWith(Truncated(cane, last_two + 1));
  ASSERT_TRUE(ExtendCanes(views, rig, volume, loose, &far).ok());
  const Polyline3& further = far.canes[1].polyline;
  EXPECT_GT((further.points.back() - old_tip).norm(), 0.08);
  for (size_t i = last_two + 1; i < further.points.size(); ++i) {
    if ((further.points[i] - old_tip).norm() > 0.04) break;
    EXPECT_LT(DistanceToLine(further.points[i], cane.polyline), 0.010) << i;
  }
}

TEST(ExtendCanes, RejectsAnExtensionAnotherViewContradicts) {
  const RigCalibration rig = sim::MakeRig().value();
  // A cane in the middle of the view, cut at 0.25 m: every camera sees where it would continue.
  const Cane cane = CurvedCane(0.05, 0.6);
  const VineModel truth = VineWith(cane);
  const VineModel cut = VineWith(Truncated(cane, 21));
  ASSERT_EQ(ImagesSeeing(rig, cane.polyline.points[30]), 3);

  // All views show the continuation: it is followed (the control).
  {
    VineModel model = cut;
    ExtendSummary summary;
    ASSERT_TRUE(
        ExtendCanes(SyntheticViews(truth, rig), rig, WorkingVolume{}, On(), &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, 1);
    EXPECT_GT(model.canes[1].polyline.points.size(), 21u);
  }
  // Only camera 0 shows wood beyond the tip; the others show background where the extension
  // would project: rejected.
  {
    std::vector<View2D> views = SyntheticViews(cut, rig);
    views[0] = SyntheticViews(truth, rig)[0];
    VineModel model = cut;
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, WorkingVolume{}, On(), &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, 0);
    EXPECT_GE(summary.contradicted, 1);
    EXPECT_EQ(model.canes[1].polyline.points.size(), 21u);
  }
}

// The model's trunk moved along the row by dx (its canes stay).
VineModel WithTrunkAt(VineModel model, double dx) {
  for (Eigen::Vector3d& p : model.canes[0].polyline.points) p.x() += dx;
  return model;
}

TEST(ExtendCanes, SkipsATipFarAlongTheRowFromTheTrunk) {
  const RigCalibration rig = sim::MakeRig().value();
  const Cane cane = CurvedCane(0.4, 1.5);
  const size_t last_two = LastSeenByTwo(rig, cane);
  const Cane cut = Truncated(cane, last_two + 1);
  const double tip_x = cut.polyline.points.back().x();
  ASSERT_GT(tip_x, 0.95);  // beyond 0.9 m from the trunk at x = 0
  const std::vector<View2D> views = SyntheticViews(VineWith(cane), rig);
  WorkingVolume volume;
  volume.box.max().x() = 1.6;
  ExtendOptions row_rule = On();
  EXPECT_EQ(row_rule.max_tip_row_distance_m, 0.0);  // off by default since s26
  row_rule.max_tip_row_distance_m = 0.9;
  // Trunk at x = 0: the tip is farther than max_tip_row_distance_m along the row: skipped.
  {
    VineModel model = VineWith(cut);
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, volume, row_rule, &model, &summary).ok());
    EXPECT_EQ(summary.tips_tried, 1);
    EXPECT_EQ(summary.tips_extended, 0);
    EXPECT_EQ(model.canes[1].polyline.points.size(), last_two + 1);
  }
  // The distance is from the trunk, not from x = 0: with the trunk 0.3 m nearer the tip, it is
  // extended (the trunk's own drawing is not in these views, which does not matter here).
  {
    VineModel model = WithTrunkAt(VineWith(cut), tip_x - 0.6);
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, volume, row_rule, &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, 1);
    EXPECT_GT(model.canes[1].polyline.points.size(), last_two + 1);
  }
  // With the defaults (the rule off) the far tip is extended.
  {
    VineModel model = VineWith(cut);
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, volume, On(), &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, 1);
  }
}

// A straight cane from `from` along `direction` (normalised here), `length` long, every 1 cm.
Cane StraightCane(const Eigen::Vector3d& from, const Eigen::Vector3d& direction, double length) {
  Cane cane;
  cane.id = CaneId(2);
  cane.parent_id = CaneId(1);
  cane.kind = CaneKind::kCane;
  for (double s = 0; s <= length + 1e-9; s += 0.01) {
    cane.polyline.points.push_back(from + s * direction.normalized());
    cane.polyline.radii.push_back(0.005);
  }
  return cane;
}

TEST(ExtendCanes, SkipsATipPointingAcrossTheRow) {
  const RigCalibration rig = sim::MakeRig().value();
  // Two straight canes in the middle of the views, seen whole by every camera; the model holds
  // their first 20 cm. One lies in the vine plane, one turns 40 degrees toward the cameras
  // (tangent y component 0.64 > 0.3).
  for (const auto& [direction, extended] :
       {std::pair{Eigen::Vector3d(1, 0, 0.3), true},
        std::pair{Eigen::Vector3d(std::cos(0.70), -std::sin(0.70), 0).normalized(), false}}) {
    const Cane cane = StraightCane({0.05, 0.85, 1.0}, direction, 0.4);
    ASSERT_EQ(ImagesSeeing(rig, cane.polyline.points.back()), 3);
    const std::vector<View2D> views = SyntheticViews(VineWith(cane), rig);
    VineModel model = VineWith(Truncated(cane, 21));
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, WorkingVolume{}, On(), &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, extended ? 1 : 0) << direction.transpose();
    // Without the rule the turned cane is extended too (the control).
    ExtendOptions any = On();
    any.max_tip_out_of_plane = 1.0;
    model = VineWith(Truncated(cane, 21));
    ASSERT_TRUE(ExtendCanes(views, rig, WorkingVolume{}, any, &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, 1) << direction.transpose();
  }
}

TEST(ExtendCanes, SkipsATipOffTheSkeleton) {
  const RigCalibration rig = sim::MakeRig().value();
  const Cane cane = CurvedCane(0.05, 0.6);
  const std::vector<View2D> views = SyntheticViews(VineWith(cane), rig);
  // The model's cane 2 mm above the true one: ~2-3 px off the skeleton in every view, within
  // snap_px of it at the tip. The rule at 0.8 px (off by default since s22).
  ExtendOptions rule = On();
  rule.max_support_px = 0.8;
  for (const auto& [lift_m, extended] : {std::pair{0.0, true}, std::pair{0.002, false}}) {
    VineModel model = VineWith(Truncated(cane, 21));
    for (Eigen::Vector3d& p : model.canes[1].polyline.points) p.z() += lift_m;
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(views, rig, WorkingVolume{}, rule, &model, &summary).ok());
    EXPECT_EQ(summary.tips_extended, extended ? 1 : 0) << lift_m;
    EXPECT_EQ(summary.tips_skipped, extended ? 0 : 1) << lift_m;
  }
  // Without the rule (the default since s22) the lifted cane is extended (the control).
  VineModel model = VineWith(Truncated(cane, 21));
  for (Eigen::Vector3d& p : model.canes[1].polyline.points) p.z() += 0.002;
  ExtendSummary summary;
  ASSERT_TRUE(ExtendCanes(views, rig, WorkingVolume{}, On(), &model, &summary).ok());
  EXPECT_EQ(summary.tips_extended, 1);
}

TEST(TipSupportOf, MeanSkeletonDistanceOfTheLastStretchInTheWorstView) {
  const RigCalibration rig = sim::MakeRig().value();
  const Cane cane = CurvedCane(0.05, 0.6);
  std::vector<View2D> views = SyntheticViews(VineWith(cane), rig);
  const Polyline3 tip = Truncated(cane, 21).polyline;
  const TipSupport on = TipSupportOf(tip, views, rig, 0.03);
  EXPECT_EQ(on.views, 3);
  EXPECT_LT(on.worst_mean_px, 0.8);
  // 2 mm above the true cane: ~2-3 px off the skeleton in some view.
  Polyline3 lifted = tip;
  for (Eigen::Vector3d& p : lifted.points) p.z() += 0.002;
  const TipSupport off = TipSupportOf(lifted, views, rig, 0.03);
  EXPECT_EQ(off.views, 3);
  EXPECT_GT(off.worst_mean_px, 0.8);
  // A view without its distance map does not count; one that sees none of the stretch neither.
  views[1].centreline_distance_px.clear();
  EXPECT_EQ(TipSupportOf(lifted, views, rig, 0.03).views, 2);
  RigCalibration away = rig;
  away.cameras[2].translation_camera_from_platform.z() -= 10.0;  // the stretch is behind it
  EXPECT_EQ(TipSupportOf(lifted, views, away, 0.03).views, 1);
}

TEST(ExtendCanes, LeavesTheModelWhenDisabled) {
  const RigCalibration rig = sim::MakeRig().value();
  const Cane cane = CurvedCane(0.05, 0.6);
  const VineModel truth = VineWith(cane);
  VineModel model = VineWith(Truncated(cane, 21));
  ExtendOptions off;
  off.enabled = false;
  ExtendSummary summary;
  ASSERT_TRUE(
      ExtendCanes(SyntheticViews(truth, rig), rig, WorkingVolume{}, off, &model, &summary).ok());
  EXPECT_EQ(model.canes[1].polyline.points.size(), 21u);
  EXPECT_EQ(summary.tips_tried, 0);
}

TEST(ExtendCanes, RejectsBadOptionsNamingTheField) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel model = VineWith(CurvedCane(0.05, 0.3));
  const std::vector<View2D> views = SyntheticViews(model, rig);
  ExtendOptions options = On();
  options.max_depth_sd_m = -1;
  absl::Status status = ExtendCanes(views, rig, WorkingVolume{}, options, &model);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), testing::HasSubstr("max_depth_sd_m"));
  options = On();
  options.anchor_points = 1;
  status = ExtendCanes(views, rig, WorkingVolume{}, options, &model);
  EXPECT_THAT(status.message(), testing::HasSubstr("anchor_points"));
  options = On();
  options.max_tip_out_of_plane = -0.1;
  status = ExtendCanes(views, rig, WorkingVolume{}, options, &model);
  EXPECT_THAT(status.message(), testing::HasSubstr("max_tip_out_of_plane"));
  options = On();
  options.max_support_px = std::nan("");
  status = ExtendCanes(views, rig, WorkingVolume{}, options, &model);
  EXPECT_THAT(status.message(), testing::HasSubstr("max_support_px"));
  status = ExtendCanes({views[0]}, rig, WorkingVolume{}, On(), &model);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), testing::HasSubstr("views"));
}

}  // namespace
}  // namespace vb::reconstruct
