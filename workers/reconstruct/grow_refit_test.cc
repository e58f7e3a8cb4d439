// SPDX-License-Identifier: Apache-2.0
// The joint refit of a grown stretch (GrowOptions::refit_span_m; grow_refit.cc).
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/cane_test_util.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/grow_internal.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using testing_util::CurvedCane;
using testing_util::ViewsOf;

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

// The unit ray from the rig's centre through p: the direction the views fix least well.
Eigen::Vector3d Ray(const RigCalibration& rig, const Eigen::Vector3d& p) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const CameraCalibration& camera : rig.cameras) centre += camera.CentreInPlatform();
  return (p - centre / static_cast<double>(rig.cameras.size())).normalized();
}

GrowOptions Refit() {
  GrowOptions options;
  options.refit_span_m = 0.03;
  return options;
}

// Points every 5 mm along the cane from arc length s0 to s1.
std::vector<Eigen::Vector3d> Stretch(const Polyline3& cane, double s0, double s1) {
  std::vector<Eigen::Vector3d> out;
  for (double s = s0; s <= s1 + 1e-9; s += 0.005) out.push_back(cane.PointAt(s));
  return out;
}

TEST(GrowRefit, LeavesPointsOnTheirCaneWithinAMillimetre) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  const GrowOptions options = Refit();
  const grow_internal::GrowEvidence evidence(views, rig, options);
  std::vector<Eigen::Vector3d> curve = Stretch(cane, 0.10, 0.16);
  const std::vector<Eigen::Vector3d> before = curve;
  evidence.Refit(&curve, 5);
  ASSERT_EQ(curve.size(), before.size());
  double moved = 0;
  for (size_t i = 0; i < curve.size(); ++i) {
    if (i < 5) {
      EXPECT_EQ(curve[i], before[i]) << i;  // the anchors stay
      continue;
    }
    // The skeletons are drawn on whole pixels: a pixel is ~1.6 mm across at this range.
    EXPECT_LT((curve[i] - before[i]).norm(), 0.001) << i;
    EXPECT_LT(DistanceToLine(curve[i], cane), 0.001) << i;
    moved += (curve[i] - before[i]).norm() / static_cast<double>(curve.size() - 5);
  }
  EXPECT_LT(moved, 0.0005);
}

TEST(GrowRefit, PullsAStretchOffInDepthBackOntoItsCane) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  const GrowOptions options = Refit();
  const grow_internal::GrowEvidence evidence(views, rig, options);
  std::vector<Eigen::Vector3d> curve = Stretch(cane, 0.10, 0.16);
  // The free points 3 mm off along the ray, the way two views' depth drifts.
  for (size_t i = 5; i < curve.size(); ++i) curve[i] += 0.003 * Ray(rig, curve[i]);
  for (size_t i = 5; i < curve.size(); ++i)
    ASSERT_GT(DistanceToLine(curve[i], cane), 0.0025) << i;
  evidence.Refit(&curve, 5);
  for (size_t i = 5; i < curve.size(); ++i)
    EXPECT_LT(DistanceToLine(curve[i], cane), 0.001) << i;
}

// The cane's first 15 cm as assembly might give it: its last 3 cm bend off in depth, 3 mm at
// the end.
Polyline3 EndOffInDepth(const Polyline3& cane, const RigCalibration& rig) {
  Polyline3 piece = cane;
  piece.points.resize(16);
  piece.radii.resize(16);
  for (int k = 1; k <= 3; ++k) piece.points[12 + k] += 0.001 * k * Ray(rig, piece.points[12 + k]);
  return piece;
}

// The grown points of the cane's tip (GrowEnd::steps), in order.
std::vector<Eigen::Vector3d> TipSteps(const RigCalibration& rig, const std::vector<View2D>& views,
                                      const Polyline3& piece, const GrowOptions& options) {
  std::vector<Polyline3> canes = {piece};
  GrowSummary summary;
  EXPECT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes, &summary).ok());
  for (const GrowEnd& end : summary.ends)
    if (end.side == 0) return end.steps;
  return {};
}

// Laid out for the rig before session 24 (sim::NarrowRigOptions), which it keeps.
TEST(GrowRefit, GrowsFromAnEndOffInDepthBackOntoItsCane) {
  const RigCalibration rig = sim::MakeRig(sim::NarrowRigOptions()).value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  const Polyline3 piece = EndOffInDepth(cane, rig);
  ASSERT_GT(DistanceToLine(piece.points.back(), cane), 0.0028);
  GrowOptions off;
  off.refit_span_m = 0.0;
  const std::vector<Eigen::Vector3d> drifting = TipSteps(rig, views, piece, off);
  const std::vector<Eigen::Vector3d> refitted = TipSteps(rig, views, piece, Refit());
  ASSERT_GE(drifting.size(), 20u);
  ASSERT_GE(refitted.size(), 20u);
  // With the refit the growth keeps the end's course for the first steps (it trusts the end) and
  // is back on its cane within 4 cm, and stays there; without, each point's depth is left to
  // the skeletons' whole pixels on its own and wanders by 1-3 mm.
  double worst_off = 0, worst_refit = 0, mean_off = 0, mean_refit = 0;
  for (size_t i = 8; i < 20; ++i) {
    worst_off = std::max(worst_off, DistanceToLine(drifting[i], cane));
    worst_refit = std::max(worst_refit, DistanceToLine(refitted[i], cane));
    mean_off += DistanceToLine(drifting[i], cane) / 12;
    mean_refit += DistanceToLine(refitted[i], cane) / 12;
  }
  EXPECT_GT(worst_off, 0.0012);
  EXPECT_GT(mean_off, 0.0006);
  EXPECT_LT(worst_refit, 0.001);
  EXPECT_LT(mean_refit, 0.0004);
}

TEST(GrowRefit, MovesTheEndItselfWhenAsked) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  const Polyline3 piece = EndOffInDepth(cane, rig);
  GrowOptions options = Refit();
  std::vector<Polyline3> kept = {piece};
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, options, &kept).ok());
  options.refit_end_m = 0.015;
  std::vector<Polyline3> moved = {piece};
  ASSERT_TRUE(GrowCaneEnds(views, rig, WorkingVolume{}, options, &moved).ok());
  ASSERT_GT(kept[0].points.size(), 20u);
  ASSERT_GT(moved[0].points.size(), 20u);
  // Without refit_end_m the end stays; with it, its last two points (within 1.5 cm) move toward
  // the cane (2 and 3 mm off before), the points before them stay.
  for (size_t i = 0; i < 16; ++i) EXPECT_EQ(kept[0].points[i], piece.points[i]) << i;
  for (size_t i = 0; i < 14; ++i) EXPECT_EQ(moved[0].points[i], piece.points[i]) << i;
  for (size_t i = 14; i < 16; ++i) {
    EXPECT_LT(DistanceToLine(moved[0].points[i], cane),
              DistanceToLine(piece.points[i], cane) - 0.0004) << i;
  }
}

TEST(GrowRefit, RejectsBadOptionsNamingTheField) {
  const RigCalibration rig = sim::MakeRig().value();
  const Polyline3 cane = CurvedCane(-0.3, 0.1, 0.95, 0.3);
  const std::vector<View2D> views = ViewsOf(cane, rig);
  for (const auto& [field, change] :
       std::vector<std::pair<std::string, std::function<void(GrowOptions*)>>>{
           {"refit_span_m", [](GrowOptions* o) { o->refit_span_m = -0.01; }},
           {"refit_span_m", [](GrowOptions* o) { o->refit_span_m = 1.0; }},
           {"refit_end_m", [](GrowOptions* o) { o->refit_end_m = NAN; }},
           {"refit_search_px", [](GrowOptions* o) { o->refit_search_px = 80.0; }},
           {"refit_smooth_px_per_mm", [](GrowOptions* o) { o->refit_smooth_px_per_mm = -1; }}}) {
    GrowOptions options = Refit();
    change(&options);
    std::vector<Polyline3> canes = {cane};
    const absl::Status status = GrowCaneEnds(views, rig, WorkingVolume{}, options, &canes);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(status.message(), testing::HasSubstr(field));
  }
}

}  // namespace
}  // namespace vb::reconstruct
