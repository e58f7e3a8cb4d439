// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_bases.h"

#include <cmath>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using ::testing::HasSubstr;

const Eigen::Vector3d kHeadCentre(0.0, 0.8, 0.9);
constexpr double kHeadRadius = 0.05;

// A cane leaving the head's surface along `direction` (x-z plane, across the views' line of
// sight), bending up a little, 0.4 m long, every 1 cm, from its base.
Polyline3 CaneFromHead(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d d = direction.normalized();
  const Eigen::Vector3d base = kHeadCentre + kHeadRadius * d;
  Polyline3 line;
  for (int i = 0; i <= 40; ++i) {
    const double s = 0.01 * i;
    line.points.push_back(base + s * d + Eigen::Vector3d(0.0, 0.0, 0.15 * s * s));
    line.radii.push_back(0.004);
  }
  return line;
}

// The true vine: a trunk up to the head, one head sphere, `canes` from it.
VineModel Vine(const std::vector<Polyline3>& canes) {
  VineModel model;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline.points = {{0.0, 0.8, 0.3}, {0.0, 0.8, 0.86}};
  trunk.polyline.radii = {0.02, 0.02};
  model.canes.push_back(trunk);
  for (size_t i = 0; i < canes.size(); ++i) {
    Cane cane;
    cane.id = CaneId(static_cast<int>(i) + 2);
    cane.parent_id = CaneId(1);
    cane.polyline = canes[i];
    model.canes.push_back(cane);
  }
  model.head.spheres.push_back({kHeadCentre, kHeadRadius});
  return model;
}

// Views drawn from the vine: the head and trunk thick (head discs, the 4 cm trunk), canes not.
std::vector<View2D> ViewsOf(const VineModel& vine, const RigCalibration& rig) {
  return SyntheticViews(vine, rig, SyntheticViewOptions{}, 20.0);
}

// The reconstructed head is looser than the true one (a visual hull): 7 cm instead of 5.
HeadModel LooseHead() {
  HeadModel head;
  head.spheres.push_back({kHeadCentre, 0.07});
  return head;
}

// The cane from `from_m` (arc length) on: what assembly gives when its base is not matched.
Polyline3 From(const Polyline3& line, double from_m) {
  Polyline3 out;
  for (size_t i = 0; i < line.points.size(); ++i) {
    if (0.01 * static_cast<double>(i) < from_m - 1e-9) continue;
    out.points.push_back(line.points[i]);
    out.radii.push_back(line.radii[i]);
  }
  return out;
}

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

HeadBasesOptions On() {
  HeadBasesOptions options;
  options.enabled = true;
  return options;
}

TEST(ExtendBasesToHead, ExtendsACaneToWhereItLeavesTheHead) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CaneFromHead({0.8, 0.0, 0.6});
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  std::vector<Polyline3> canes = {From(cane, 0.06)};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), On(), &canes, &summary).ok());
  EXPECT_EQ(summary.ends_tried, 1);
  EXPECT_EQ(summary.ends_extended, 1);
  EXPECT_EQ(summary.reached_thick, 1);
  // The base now lies where the cane meets the head's silhouette: at its true base, within a
  // step and a half; every added point lies on the true cane (within 5 mm: the extension is
  // straight where the cane bends, and the views place its depth least well).
  EXPECT_LT((canes[0].points.front() - cane.points.front()).norm(), 0.008);
  EXPECT_GT(summary.added_length_m, 0.045);
  for (size_t i = 0; i < canes[0].points.size(); ++i) {
    EXPECT_LT(DistanceToLine(canes[0].points[i], cane), 0.005) << i;
    EXPECT_DOUBLE_EQ(canes[0].radii[i], 0.004);
  }
}

TEST(ExtendBasesToHead, ExtendsTheLastPointWhenItIsTheBase) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CaneFromHead({-0.9, 0.0, 0.45});
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  Polyline3 reversed = From(cane, 0.05);
  std::reverse(reversed.points.begin(), reversed.points.end());
  std::vector<Polyline3> canes = {reversed};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), On(), &canes, &summary).ok());
  EXPECT_EQ(summary.ends_extended, 1);
  EXPECT_LT((canes[0].points.back() - cane.points.front()).norm(), 0.008);
  EXPECT_NEAR((canes[0].points.front() - cane.points.back()).norm(), 0.0, 1e-12);
}

// A cane leaving the head's surface along `direction` (x-z plane) on a circle of radius
// `radius_m` bending up, `length_m` long, every 1 cm, from its base.
Polyline3 CircularCaneFromHead(const Eigen::Vector3d& direction, double radius_m,
                               double length_m) {
  const Eigen::Vector3d d = direction.normalized();
  const Eigen::Vector3d up(-d.z(), 0.0, d.x());  // d turned 90 degrees in the x-z plane
  const Eigen::Vector3d base = kHeadCentre + kHeadRadius * d;
  Polyline3 line;
  for (int i = 0; 0.01 * i <= length_m + 1e-9; ++i) {
    const double a = 0.01 * i / radius_m;
    line.points.push_back(base + radius_m * std::sin(a) * d + radius_m * (1.0 - std::cos(a)) * up);
    line.radii.push_back(0.004);
  }
  return line;
}

TEST(ExtendBasesToHead, RecordsTheEndsBendAndCourse) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CircularCaneFromHead({0.8, 0.0, 0.6}, 0.15, 0.25);
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  std::vector<Polyline3> canes = {From(cane, 0.08)};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), On(), &canes, &summary).ok());
  ASSERT_EQ(summary.extensions.size(), 1u);
  const HeadBaseExtension& x = summary.extensions[0];
  // Two chords of 3 cm, a chord apart on a circle of 15 cm: 0.03 / 0.15 rad = 11.46 degrees.
  EXPECT_NEAR(x.bend_deg, 0.2 * 180.0 / 3.14159265358979, 0.3);
  EXPECT_LT((x.end - cane.points[8]).norm(), 1e-9);
  EXPECT_EQ(x.inside_m.size(), x.points.size());
  EXPECT_EQ(x.skeleton_px.size(), x.points.size());
  // The end is 8 cm out on the cane, 1 cm outside the 7 cm loose head.
  EXPECT_NEAR(x.end_distance_m, (cane.points[8] - kHeadCentre).norm() - 0.07, 1e-9);
}

TEST(ExtendBasesToHead, FollowsACurvedCaneWithTheEndsCurvature) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CircularCaneFromHead({0.8, 0.0, 0.6}, 0.15, 0.25);
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  // No correction toward the skeleton: the course is the prediction alone.
  HeadBasesOptions options = On();
  options.max_offset_m = 0.0;
  options.curve_gain = 1.0;
  std::vector<Polyline3> curved = {From(cane, 0.08)};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &curved, &summary).ok());
  ASSERT_EQ(summary.ends_extended, 1);
  // The circle continued: the base within a step of the true one, every point on the cane.
  EXPECT_LT((curved[0].points.front() - cane.points.front()).norm(), 0.006);
  for (size_t i = 0; i < curved[0].points.size(); ++i)
    EXPECT_LT(DistanceToLine(curved[0].points[i], cane), 0.002) << i;
  // The straight course (s19) leaves the cane: it misses the base by more than a centimetre or
  // leaves the wood and is dropped.
  options.curve_gain = 0.0;
  std::vector<Polyline3> straight = {From(cane, 0.08)};
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &straight, &summary).ok());
  if (summary.ends_extended == 1) {
    EXPECT_GT((straight[0].points.front() - cane.points.front()).norm(), 0.01);
  } else {
    EXPECT_EQ(straight[0].points.size(), From(cane, 0.08).points.size());
  }
}

TEST(ExtendBasesToHead, ConvergingCanesStopAtTheirOwnBases) {
  const RigCalibration rig = sim::MakeRig().value();
  // Two canes leaving the head 1.4 cm apart (16 degrees), their courses converging toward its
  // centre.
  const Polyline3 a = CaneFromHead({0.8, 0.0, 0.6});
  const Polyline3 b = CaneFromHead({0.6, 0.0, 0.8});
  const std::vector<View2D> views = ViewsOf(Vine({a, b}), rig);
  std::vector<Polyline3> canes = {From(a, 0.05), From(b, 0.05)};
  HeadBasesOptions options = On();
  options.curve_gain = 1.0;
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &canes, &summary).ok());
  EXPECT_EQ(summary.ends_extended, 2);
  EXPECT_LT((canes[0].points.front() - a.points.front()).norm(), 0.008);
  EXPECT_LT((canes[1].points.front() - b.points.front()).norm(), 0.008);
  // Neither runs onto or past the other: each point is nearer its own cane than the other's.
  for (const Eigen::Vector3d& p : canes[0].points)
    EXPECT_LT(DistanceToLine(p, a), DistanceToLine(p, b));
  for (const Eigen::Vector3d& p : canes[1].points)
    EXPECT_LT(DistanceToLine(p, b), DistanceToLine(p, a));
}

TEST(ExtendBasesToHead, DropsACourseOffTheViewsSkeletonsWithMaxSkeletonPx) {
  const RigCalibration rig = sim::MakeRig().value();
  const Eigen::Vector3d d = Eigen::Vector3d(0.8, 0.0, 0.6).normalized();
  const Polyline3 cane = CircularCaneFromHead(d, 100.0, 0.3);  // straight
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  HeadBasesOptions options = On();
  options.max_offset_m = 0.0;  // no correction: the course stays where the end puts it
  options.max_skeleton_px = 1.0;
  // On the cane: its points lie on the views' skeletons, and it is kept.
  std::vector<Polyline3> on = {From(cane, 0.06)};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &on, &summary).ok());
  EXPECT_EQ(summary.ends_extended, 1);
  EXPECT_EQ(summary.off_skeleton, 0);
  ASSERT_EQ(summary.extensions.size(), 1u);
  for (double px : summary.extensions[0].skeleton_px) EXPECT_LT(px, 1.0);
  // 3 mm beside it, across the views' line of sight (still on the cane's silhouette): dropped.
  Polyline3 beside = From(cane, 0.06);
  for (Eigen::Vector3d& p : beside.points) p += 0.003 * Eigen::Vector3d(-d.z(), 0.0, d.x());
  std::vector<Polyline3> off = {beside};
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &off, &summary).ok());
  EXPECT_EQ(summary.ends_tried, 1);
  EXPECT_EQ(summary.ends_extended, 0);
  EXPECT_EQ(summary.off_skeleton, 1);
  EXPECT_EQ(off[0].points, beside.points);
  // Without the test it is kept.
  options.max_skeleton_px = 0.0;
  off = {beside};
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &off, &summary).ok());
  EXPECT_EQ(summary.ends_extended, 1);
  EXPECT_EQ(summary.off_skeleton, 0);
}

// Laid out for the rig before session 24 (sim::NarrowRigOptions), which it keeps.
TEST(ExtendBasesToHead, RunsMaxInsideIntoTheHeadWhenTheThickTestIsOff) {
  const RigCalibration rig = sim::MakeRig(sim::NarrowRigOptions()).value();
  const Polyline3 cane = CaneFromHead({0.8, 0.0, 0.6});
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  std::vector<Polyline3> canes = {From(cane, 0.06)};
  HeadBasesOptions options = On();
  options.min_thick_views = 0;
  options.max_inside_m = 0.015;
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), options, &canes, &summary).ok());
  EXPECT_EQ(summary.reached_inside, 1);
  EXPECT_EQ(summary.reached_thick, 0);
  // The cane enters the 7 cm sphere 2 cm from its base and runs 1.5 cm (to the step) inside it.
  EXPECT_NEAR((canes[0].points.front() - kHeadCentre).norm(), 0.055, 0.004);
}

TEST(ExtendBasesToHead, DropsAnExtensionTheViewsDoNotShowAsWood) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CaneFromHead({0.8, 0.0, 0.6});
  // The views show the cane only from 4 cm out: between it and the head lies background.
  const std::vector<View2D> views = ViewsOf(Vine({From(cane, 0.04)}), rig);
  const Polyline3 input = From(cane, 0.07);
  std::vector<Polyline3> canes = {input};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), On(), &canes, &summary).ok());
  EXPECT_EQ(summary.ends_tried, 1);
  EXPECT_EQ(summary.ends_extended, 0);
  EXPECT_EQ(summary.no_wood, 1);
  EXPECT_EQ(canes[0].points, input.points);
}

TEST(ExtendBasesToHead, LeavesEndsThatDoNotPointAtTheHead) {
  const RigCalibration rig = sim::MakeRig().value();
  // Upright beside the head, its lower end 8 cm from the head's surface, pointing down past it.
  Polyline3 upright;
  for (int i = 0; i <= 30; ++i) {
    upright.points.emplace_back(0.12, 0.8, 0.95 + 0.01 * i);
    upright.radii.push_back(0.004);
  }
  const Polyline3 cane = CaneFromHead({0.8, 0.0, 0.6});
  const std::vector<View2D> views = ViewsOf(Vine({cane, upright}), rig);
  std::vector<Polyline3> canes = {upright};
  HeadBasesSummary summary;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), On(), &canes, &summary).ok());
  EXPECT_EQ(summary.ends_tried, 0);
  EXPECT_EQ(canes[0].points, upright.points);
}

TEST(ExtendBasesToHead, DoesNothingWhenOff) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CaneFromHead({0.8, 0.0, 0.6});
  const std::vector<View2D> views = ViewsOf(Vine({cane}), rig);
  const Polyline3 input = From(cane, 0.06);
  std::vector<Polyline3> canes = {input};
  HeadBasesSummary summary;
  HeadBasesOptions off;
  off.enabled = false;
  ASSERT_TRUE(ExtendBasesToHead(views, rig, LooseHead(), off, &canes, &summary).ok());
  EXPECT_EQ(summary.ends_tried, 0);
  EXPECT_EQ(canes[0].points, input.points);
}

TEST(ExtendBasesToHead, RejectsInvalidOptions) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<Polyline3> canes;
  const std::vector<View2D> views = ViewsOf(Vine({}), rig);
  auto check = [&](HeadBasesOptions options, const std::string& field) {
    const absl::Status s = ExtendBasesToHead(views, rig, LooseHead(), options, &canes);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(std::string(s.message()), HasSubstr("head_bases." + field));
  };
  HeadBasesOptions o = On();
  o.min_cos = 1.5;
  check(o, "min_cos");
  o = On();
  o.min_thick_views = -1;
  check(o, "min_thick_views");
  o = On();
  o.max_turn_deg = 90.0;
  check(o, "max_turn_deg");
  o = On();
  o.step_m = 0.0;
  check(o, "step_m");
  o = On();
  o.max_inside_m = std::nan("");
  check(o, "max_inside_m");
  o = On();
  o.max_offset_m = 0.05;
  check(o, "max_offset_m");
  o = On();
  o.curve_gain = -0.1;
  check(o, "curve_gain");
  o = On();
  o.curve_gain = std::nan("");
  check(o, "curve_gain");
  o = On();
  o.max_skeleton_px = -1.0;
  check(o, "max_skeleton_px");
}

TEST(ExtendBasesToHead, RejectsViewsThatDoNotMatchTheRig) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = ViewsOf(Vine({}), rig);
  views.pop_back();
  std::vector<Polyline3> canes;
  const absl::Status s = ExtendBasesToHead(views, rig, LooseHead(), On(), &canes);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), HasSubstr("views"));
}

}  // namespace
}  // namespace vb::reconstruct
