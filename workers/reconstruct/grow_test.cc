// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/grow.h"

#include <cmath>
#include <functional>
#include <string>
#include <utility>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/cane_test_util.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using testing_util::CurvedCane;

// A straight cane from a to b, every 1 cm.
Polyline3 Straight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Polyline3 line;
  const int n = static_cast<int>(std::ceil((b - a).norm() / 0.01));
  for (int i = 0; i <= n; ++i) {
    line.points.push_back(a + (b - a) * (static_cast<double>(i) / n));
    line.radii.push_back(0.004);
  }
  return line;
}

VineModel ModelOf(const std::vector<Polyline3>& lines) {
  VineModel model;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline = Straight({0.0, 0.8, 0.3}, {0.0, 0.8, 0.6});
  model.canes.push_back(trunk);
  for (size_t i = 0; i < lines.size(); ++i) {
    Cane cane;
    cane.id = CaneId(static_cast<int>(i) + 2);
    cane.parent_id = CaneId(1);
    cane.kind = CaneKind::kCane;
    cane.polyline = lines[i];
    model.canes.push_back(cane);
  }
  return model;
}

// Views drawn from the truth; the thick region is left to the trunk (no cane is that wide).
std::vector<View2D> ViewsOf(const std::vector<Polyline3>& lines, const RigCalibration& rig) {
  SyntheticViewOptions options;
  options.draw_head = false;
  return SyntheticViews(ModelOf(lines), rig, options, 40.0);
}

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

// The first `n` points of a line.
Polyline3 Head(const Polyline3& line, size_t n) {
  Polyline3 out = line;
  out.points.resize(n);
  out.radii.resize(n);
  return out;
}

// From point `n` on.
Polyline3 Tail(const Polyline3& line, size_t n) {
  Polyline3 out;
  out.points.assign(line.points.begin() + n, line.points.end());
  out.radii.assign(line.radii.begin() + n, line.radii.end());
  return out;
}

GrowOptions On() {
  GrowOptions options;
  options.enabled = true;
  return options;
}

// The cane of the tests: 0.4 m long, crossed at its 20th point (x = -0.1) by a steep cane; the
// skeleton of every view breaks the cane there (a junction of four segments), and its 3D piece
// is taken to stop 1 cm before the crossing.
struct Crossing {
  Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  Polyline3 crossing;
  Crossing() {
    const Eigen::Vector3d c = cane.points[20];
    crossing = Straight(c + Eigen::Vector3d(-0.06, 0.0, -0.12), c + Eigen::Vector3d(0.06, 0.0, 0.12));
  }
};

TEST(GrowCaneEnds, GrowsThroughACrossingWithinTwoMillimetres) {
  const RigCalibration rig = sim::MakeRig().value();
  const Crossing scene;
  const std::vector<View2D> views = ViewsOf({scene.cane, scene.crossing}, rig);
  std::vector<Polyline3> canes = {Head(scene.cane, 20), scene.crossing};
  const Eigen::Vector3d old_end = canes[0].points.back();
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &canes, &summary).ok());
  ASSERT_GT(canes[0].points.size(), 20u);
  // The end grew through the crossing, at least 8 cm beyond it.
  EXPECT_GT(canes[0].points.back().x(), scene.cane.points[20].x() + 0.08);
  for (size_t i = 20; i < canes[0].points.size(); ++i)
    EXPECT_LT(DistanceToLine(canes[0].points[i], scene.cane), 0.002) << i;
  // The other end of the cane ran out of the skeleton (the cane's true base) and did not grow.
  EXPECT_LT((canes[0].points.front() - scene.cane.points.front()).norm(), 0.006);
  EXPECT_GE(summary.ends_grown, 1);
  EXPECT_GT(summary.added_length_m, 0.08);
  EXPECT_LT((canes[0].points.back() - old_end).norm(), summary.added_length_m + 1e-9);
  // The crossing cane is whole in the views at both ends: nothing to grow onto.
  for (const Eigen::Vector3d& p : canes[1].points)
    EXPECT_LT(DistanceToLine(p, scene.crossing), 0.004);
}

TEST(GrowCaneEnds, BacksOffAMisplacedEndWhenAsked) {
  const RigCalibration rig = sim::MakeRig().value();
  const Crossing scene;
  const std::vector<View2D> views = ViewsOf({scene.cane, scene.crossing}, rig);
  // The piece's last point is 6 mm off the cane: the views disagree on the end.
  Polyline3 piece = Head(scene.cane, 20);
  piece.points.back() += Eigen::Vector3d(0.0, 0.0, 0.006);
  {
    std::vector<Polyline3> canes = {piece, scene.crossing};
    GrowSummary summary;
    ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &canes, &summary).ok());
    EXPECT_GE(summary.end_unsupported, 1);
    EXPECT_EQ(canes[0].points.size(), 20u);  // by default such an end is not grown
  }
  GrowOptions options = On();
  options.end_backoff_m = 0.02;
  std::vector<Polyline3> canes = {piece, scene.crossing};
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes).ok());
  // Backed off to the point before, then grown through the crossing; the misplaced point is gone.
  EXPECT_GT(canes[0].points.back().x(), scene.cane.points[20].x() + 0.08);
  for (size_t i = 18; i < canes[0].points.size(); ++i)
    EXPECT_LT(DistanceToLine(canes[0].points[i], scene.cane), 0.002) << i;
}

TEST(GrowCaneEnds, StopsWhereAViewContradicts) {
  const RigCalibration rig = sim::MakeRig().value();
  const Crossing scene;
  // Camera 1 shows nothing of the cane beyond its 25th point: growth must stop there.
  std::vector<View2D> views = ViewsOf({scene.cane, scene.crossing}, rig);
  views[1] = ViewsOf({Head(scene.cane, 26), scene.crossing}, rig)[1];
  std::vector<Polyline3> canes = {Head(scene.cane, 20), scene.crossing};
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &canes, &summary).ok());
  EXPECT_GE(summary.contradicted, 1);
  EXPECT_LT(canes[0].points.back().x(), scene.cane.points[25].x() + 0.01);
  for (size_t i = 20; i < canes[0].points.size(); ++i)
    EXPECT_LT(DistanceToLine(canes[0].points[i], scene.cane), 0.002) << i;
}

TEST(GrowCaneEnds, DoesNotRunAlongAnotherCane) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf({cane}, rig);
  // The control: the first 15 cm alone grows to the end of the cane.
  {
    std::vector<Polyline3> canes = {Head(cane, 16)};
    ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &canes).ok());
    EXPECT_GT(canes[0].points.back().x(), cane.points[16].x() + 0.1);
  }
  // The rest of the cane is in the model already, from 3 cm on: growth stops where it meets it
  // and does not run along it.
  std::vector<Polyline3> canes = {Head(cane, 16), Tail(cane, 18)};
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &canes, &summary).ok());
  EXPECT_GE(summary.alongside, 1);
  EXPECT_LT(canes[0].points.back().x(), cane.points[18].x() + 0.012);
  // Nor does the rest grow back along the first piece.
  EXPECT_GT(canes[1].points.front().x(), cane.points[15].x() - 0.012);
}

// Growth alongside other canes, as by default (session 17).
GrowOptions Alongside() {
  GrowOptions options = On();
  EXPECT_GT(options.alongside_max_m, 0.08);
  EXPECT_GT(options.alongside_prior_px_per_mm, 0.0);
  return options;
}

// Two canes that lie along each other in every view for 6 cm (x in [-0.12, -0.06]) and part
// again on either side: `other` 1 cm behind `own` in depth there, and dropping away from it
// steeply outside. The views draw the shared stretch as one skeleton path, `other`'s (as a
// skeleton merges two canes lying along each other), and the model has `other` whole but `own`
// only up to where the stretch begins.
struct SharedStretch {
  Polyline3 own = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  Polyline3 other;
  SharedStretch() {
    other = own;
    for (Eigen::Vector3d& p : other.points) {
      const double outside = std::max({0.0, -0.12 - p.x(), p.x() + 0.06});
      p += Eigen::Vector3d(0.0, 0.01, -2.0 * outside);
    }
  }
  std::vector<View2D> Views(const RigCalibration& rig) const {
    SyntheticViewOptions options;
    options.draw_head = false;
    options.break_at_crossings_px = 2.0;
    options.merge_overlaps = true;  // `other`, listed first, keeps the shared stretch
    return SyntheticViews(ModelOf({other, own}), rig, options, 40.0);
  }
  // `own` up to 1 cm before the shared stretch.
  Polyline3 OwnPiece() const {
    size_t n = 0;
    while (own.points[n].x() < -0.13) ++n;
    return Head(own, n);
  }
};

// Laid out for the rig before session 24 (sim::NarrowRigOptions), which it keeps.
TEST(GrowCaneEnds, GrowsAlongAnotherCaneOnItsOwnCourseAndPartsFromIt) {
  const RigCalibration rig = sim::MakeRig(sim::NarrowRigOptions()).value();
  const SharedStretch scene;
  const std::vector<View2D> views = scene.Views(rig);
  // The control: without growth alongside other canes (alongside_max_m 0, as before session 17)
  // growth stops alongside the other cane, before the stretch's end.
  {
    std::vector<Polyline3> canes = {scene.OwnPiece(), scene.other};
    GrowSummary summary;
    GrowOptions stop_alongside = On();
    stop_alongside.alongside_max_m = 0.0;
    ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, stop_alongside, &canes, &summary).ok());
    EXPECT_GE(summary.alongside, 1);
    EXPECT_LT(canes[0].points.back().x(), -0.06);
  }
  std::vector<Polyline3> canes = {scene.OwnPiece(), scene.other};
  const size_t old_size = canes[0].points.size();
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, Alongside(), &canes, &summary).ok());
  // The end grew through the shared stretch and on along its own cane beyond it ...
  EXPECT_GT(canes[0].points.back().x(), -0.04);
  EXPECT_EQ(summary.ends_alongside, 1);
  EXPECT_GT(summary.alongside_length_m, 0.04);
  // ... following its own cane, not the other: every grown point is nearer its own.
  for (size_t i = old_size; i < canes[0].points.size(); ++i) {
    EXPECT_LT(DistanceToLine(canes[0].points[i], scene.own), 0.003) << i;
    EXPECT_GT(DistanceToLine(canes[0].points[i], scene.other), 0.006) << i;
  }
  // The other cane, whole in the views, is left as it was.
  EXPECT_EQ(canes[1].points.size(), scene.other.points.size());
}

TEST(GrowCaneEnds, StopsAlongACaneThatContinuesIt) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf({cane}, rig);
  // The rest of the cane is in the model from 3 cm on: growing alongside other canes does not
  // run along it, since it is the end's own continuation (its end at the meeting point).
  std::vector<Polyline3> canes = {Head(cane, 16), Tail(cane, 18)};
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, Alongside(), &canes, &summary).ok());
  EXPECT_GE(summary.alongside, 1);
  EXPECT_EQ(summary.ends_alongside, 0);
  EXPECT_LT(canes[0].points.back().x(), cane.points[18].x() + 0.012);
  EXPECT_GT(canes[1].points.front().x(), cane.points[15].x() - 0.012);
  // With the continuation test off (the other cane's end must coincide with the point) and no
  // least gap, the end runs along it.
  GrowOptions loose = Alongside();
  loose.continuation_m = 0.0;
  loose.alongside_min_gap_m = 0.0;
  std::vector<Polyline3> doubled = {Head(cane, 16), Tail(cane, 18)};
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, loose, &doubled, &summary).ok());
  EXPECT_GT(summary.ends_alongside, 0);
}

// Support in bundles (s18): band_support and band_end_support on, or both off (the old rule).
GrowOptions Bands(bool on = true) {
  GrowOptions options = On();
  options.band_support = on;
  options.band_end_support = on;
  return options;
}

// Two canes of 6 mm radius side by side, 11 mm apart in height (overlapping by 1 mm, so every
// view shows one band of wood), and the views' skeleton drawn along the bundle's middle, 5.5 mm
// from each cane's axis (as a skeleton thins two fused canes): the classes come from both canes,
// the skeleton and its distance map from the middle line.
struct SideBySide {
  Polyline3 own = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  Polyline3 other, middle;
  SideBySide() {
    for (double& r : own.radii) r = 0.006;
    other = own;
    middle = own;
    for (Eigen::Vector3d& p : other.points) p.z() += 0.011;
    for (Eigen::Vector3d& p : middle.points) p.z() += 0.0055;
  }
  std::vector<View2D> Views(const RigCalibration& rig) const {
    std::vector<View2D> views = ViewsOf({own, other}, rig);
    const std::vector<View2D> skeleton = ViewsOf({middle}, rig);
    for (size_t v = 0; v < views.size(); ++v) {
      views[v].segments = skeleton[v].segments;
      views[v].nodes = skeleton[v].nodes;
      views[v].centreline_distance_px = skeleton[v].centreline_distance_px;
    }
    return views;
  }
};

TEST(GrowCaneEnds, GrowsThroughABundleWhoseSkeletonRunsBetweenTheCanes) {
  const RigCalibration rig = sim::MakeRig().value();
  const SideBySide scene;
  const std::vector<View2D> views = scene.Views(rig);
  // The control: the own cane's axis projects more than support_px off the skeleton, so the old
  // rule finds the tip unsupported; support in bundles for the steps alone does not change that.
  for (const bool steps_only : {false, true}) {
    std::vector<Polyline3> canes = {Head(scene.own, 20)};
    GrowOptions options = Bands(false);
    options.band_support = steps_only;
    GrowSummary summary;
    ASSERT_TRUE(
        GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes, &summary, true).ok());
    EXPECT_EQ(summary.end_unsupported, 1) << steps_only;
    EXPECT_EQ(canes[0].points.size(), 20u) << steps_only;
  }
  std::vector<Polyline3> canes = {Head(scene.own, 20)};
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, Bands(), &canes, &summary, true).ok());
  // The tip grew at least 8 cm on, along its own cane: every grown point within 3 mm of it and
  // further than that from the bundle's middle.
  EXPECT_GT(canes[0].points.back().x(), scene.own.points[19].x() + 0.08);
  EXPECT_EQ(summary.ends_grown, 1);
  for (size_t i = 20; i < canes[0].points.size(); ++i) {
    EXPECT_LT(DistanceToLine(canes[0].points[i], scene.own), 0.003) << i;
    EXPECT_GT(DistanceToLine(canes[0].points[i], scene.middle), 0.003) << i;
  }
}

// Laid out for the rig before session 24 (sim::NarrowRigOptions), which it keeps.
TEST(GrowCaneEnds, KeepsTheOldRuleWhereTheBandIsOneCaneWide) {
  const RigCalibration rig = sim::MakeRig(sim::NarrowRigOptions()).value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf({cane}, rig);
  // The piece's tip lies 3 mm off the axis of its 4 mm cane: inside the cane's wood, but more
  // than support_px off the skeleton, and the band there is one cane wide: not supported.
  Polyline3 piece = Head(cane, 20);
  piece.points.back() += Eigen::Vector3d(0.0, 0.0, 0.003);
  for (const bool bands : {false, true}) {
    std::vector<Polyline3> canes = {piece};
    GrowSummary summary;
    ASSERT_TRUE(
        GrowCaneEnds(views, rig, WorkingVolume{}, Bands(bands), &canes, &summary, true).ok());
    EXPECT_EQ(summary.end_unsupported, 1) << bands;
    EXPECT_EQ(canes[0].points.size(), 20u) << bands;
  }
  // A well-placed tip grows to the cane's end as before, on its own cane (within its 4 mm radius;
  // either rule strays up to 3 mm on the first grown points here).
  for (const bool bands : {false, true}) {
    std::vector<Polyline3> canes = {Head(cane, 16)};
    ASSERT_TRUE(
        GrowCaneEnds(views, rig, WorkingVolume{}, Bands(bands), &canes, nullptr, true).ok());
    EXPECT_GT(canes[0].points.back().x(), cane.points[16].x() + 0.1) << bands;
    for (size_t i = 16; i < canes[0].points.size(); ++i)
      EXPECT_LT(DistanceToLine(canes[0].points[i], cane), 0.004) << bands << " " << i;
  }
}

TEST(GrowCaneEnds, GrowsOnlyTheTipWhenAsked) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf({cane}, rig);
  const Polyline3 middle = Tail(Head(cane, 30), 10);  // points 10-29 of the cane
  std::vector<Polyline3> both = {middle}, tip = {middle};
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &both).ok());
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, On(), &tip, nullptr, true).ok());
  // Both ends grow by default; with tips_only the base stays where it was.
  EXPECT_LT(both[0].points.front().x(), middle.points.front().x() - 0.03);
  EXPECT_EQ(tip[0].points.front(), middle.points.front());
  EXPECT_GT(tip[0].points.back().x(), middle.points.back().x() + 0.03);
}

TEST(GrowCaneEnds, LeavesTheCanesWhenDisabled) {
  const RigCalibration rig = sim::MakeRig().value();
  const Crossing scene;
  const std::vector<View2D> views = ViewsOf({scene.cane, scene.crossing}, rig);
  std::vector<Polyline3> canes = {Head(scene.cane, 20), scene.crossing};
  GrowOptions options;
  EXPECT_TRUE(options.enabled);  // on by default since session 16
  options.enabled = false;
  GrowSummary summary;
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes, &summary).ok());
  EXPECT_EQ(canes[0].points.size(), 20u);
  EXPECT_EQ(summary.ends_tried, 0);
}

TEST(GrowCaneEnds, RejectsBadInputNamingTheField) {
  const RigCalibration rig = sim::MakeRig().value();
  const Crossing scene;
  const std::vector<View2D> views = ViewsOf({scene.cane}, rig);
  std::vector<Polyline3> canes = {Head(scene.cane, 20)};
  GrowOptions options = On();
  options.support_px = -1;
  absl::Status status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), testing::HasSubstr("support_px"));
  options = On();
  options.min_support_views = 1;
  status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
  EXPECT_THAT(status.message(), testing::HasSubstr("min_support_views"));
  options = On();
  options.max_turn_deg = 120;
  status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
  EXPECT_THAT(status.message(), testing::HasSubstr("max_turn_deg"));
  options = On();
  options.offset_grid_m = 1e-7;
  status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
  EXPECT_THAT(status.message(), testing::HasSubstr("offset_grid_m"));
  options = On();
  options.max_length_m = 100.0;
  status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
  EXPECT_THAT(status.message(), testing::HasSubstr("max_length_m"));
  for (const auto& [field, change] :
       std::vector<std::pair<std::string, std::function<void(GrowOptions*)>>>{
           {"alongside_max_m", [](GrowOptions* o) { o->alongside_max_m = -0.1; }},
           {"alongside_max_m", [](GrowOptions* o) { o->alongside_max_m = 1.0; }},
           {"alongside_min_gap_m", [](GrowOptions* o) { o->alongside_min_gap_m = 0.02; }},
           {"continuation_m", [](GrowOptions* o) { o->continuation_m = NAN; }},
           {"alongside_prior_px_per_mm",
            [](GrowOptions* o) { o->alongside_prior_px_per_mm = -1; }},
           {"end_backoff_m", [](GrowOptions* o) { o->end_backoff_m = INFINITY; }},
           {"band_margin_px", [](GrowOptions* o) { o->band_margin_px = -1; }},
           {"band_tolerance_px", [](GrowOptions* o) { o->band_tolerance_px = NAN; }},
           {"band_prior_px_per_mm", [](GrowOptions* o) { o->band_prior_px_per_mm = -2; }}}) {
    options = Alongside();
    change(&options);
    status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(status.message(), testing::HasSubstr(field));
  }
  status = GrowCaneEnds({views[0]}, rig, WorkingVolume{}, On(), &canes);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), testing::HasSubstr("views"));
  // A view whose size is not its camera's (the probes index pixels by the camera's size).
  std::vector<View2D> small = views;
  small[1].width -= 8;
  status = GrowCaneEnds(small, rig, WorkingVolume{}, On(), &canes);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), testing::HasSubstr("views[1]"));
}

}  // namespace
}  // namespace vb::reconstruct
