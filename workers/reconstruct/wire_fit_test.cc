// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/wire_fit.h"

#include <cmath>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"
#include "workers/reconstruct/trellis2d.h"
#include "workers/reconstruct/trellis3d.h"

namespace vb::reconstruct {
namespace {

// Height of a wire fixed at z0 on posts at x = post_x and post_x +- 6 m, sagging `sag` midway
// (as sim/trellis.h hangs them).
double SagZ(double x, double z0, double sag, double post_x) {
  const double u = (x - post_x) / 6.0;
  const double frac = u - std::floor(u);
  return z0 - sag * 4.0 * frac * (1.0 - frac);
}

// Two wires sagging 35 mm between posts, one post at x = 0.1 m in view (the wires kink there).
VineModel SaggingTrellis() {
  VineModel model;
  for (int i = 0; i < 2; ++i) {
    Wire wire;
    wire.id = WireId(i + 1);
    const double z0 = 0.95 + 0.3 * i;
    for (double x = -2.0; x <= 2.0 + 1e-9; x += 0.05)
      wire.points.emplace_back(x, 0.8 + 0.01 * i, SagZ(x, z0, 0.035, 0.1));
    model.wires.push_back(wire);
  }
  return model;
}

// The synthetic views with their wire lines extracted from the drawn classes, as the 2D stage
// does it (so that each line carries its observed centre trace).
std::vector<View2D> ViewsWithTraces(const VineModel& model, const RigCalibration& rig) {
  std::vector<View2D> views = SyntheticViews(model, rig);
  for (size_t v = 0; v < views.size(); ++v)
    views[v].wires = ExtractWires(views[v].classes, rig.cameras[v], Structure2DOptions{});
  return views;
}

double DistanceToPolyline(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& points) {
  double best = 1e9;
  for (size_t i = 0; i + 1 < points.size(); ++i)
    best = std::min(best, PointSegmentDistance(p, points[i], points[i + 1]));
  return best;
}

// Largest distance over |x| <= 0.8 m from each true wire to its reconstruction (sorted by z).
std::vector<double> WorstErrors(const Trellis& trellis, const VineModel& truth) {
  std::vector<double> worst;
  for (size_t w = 0; w < truth.wires.size() && w < trellis.wires.size(); ++w) {
    double e = 0.0;
    for (const Eigen::Vector3d& p : truth.wires[w].points)
      if (std::abs(p.x()) <= 0.8) e = std::max(e, DistanceToPolyline(p, trellis.wires[w].points));
    worst.push_back(e);
  }
  return worst;
}

TEST(FitWirePolyline, SaggingWireWithAPostInViewIsFollowedWithinTolerance) {
  const RigCalibration rig = sim::MakeRig().value();
  const VineModel truth = SaggingTrellis();
  const std::vector<View2D> views = ViewsWithTraces(truth, rig);
  TrellisOptions options;
  const auto sagging = ReconstructTrellis(views, rig, WorkingVolume(), options);
  ASSERT_TRUE(sagging.ok()) << sagging.status();
  ASSERT_EQ(sagging->wires.size(), 2u);
  for (double e : WorstErrors(*sagging, truth)) EXPECT_LT(e, 0.005);
  for (const Wire& wire : sagging->wires) EXPECT_GT(wire.points.size(), 2u);
  // The straight wire of the same lines cannot follow the kink: the test depends on the sag.
  options.fit_sag = false;
  const auto straight = ReconstructTrellis(views, rig, WorkingVolume(), options);
  ASSERT_TRUE(straight.ok()) << straight.status();
  ASSERT_EQ(straight->wires.size(), 2u);
  EXPECT_GT(WorstErrors(*straight, truth)[0], 0.008);
}

TEST(FitWirePolyline, StraightWireStaysStraight) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel truth;
  Wire wire;
  wire.id = WireId(1);
  wire.points = {{-2.0, 0.8, 1.0}, {2.0, 0.82, 1.02}};
  truth.wires.push_back(wire);
  const auto trellis = ReconstructTrellis(ViewsWithTraces(truth, rig), rig, WorkingVolume());
  ASSERT_TRUE(trellis.ok()) << trellis.status();
  ASSERT_EQ(trellis->wires.size(), 1u);
  // Over the whole volume, the extrapolated ends included.
  for (const Eigen::Vector3d& p : trellis->wires[0].points)
    EXPECT_LT(PointSegmentDistance(p, wire.points[0], wire.points[1]), 0.004) << p.transpose();
}

TEST(FitWirePolyline, TooFewObservationsGiveNoFit) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views(rig.cameras.size());
  EXPECT_TRUE(FitWirePolyline(views, rig, {-1.0, 0.8, 1.0}, {1.0, 0.8, 1.0}, WireFitOptions{})
                  .empty());
}

TEST(WireFitOptions, RejectsNonPositiveFieldsByName) {
  WireFitOptions options;
  EXPECT_TRUE(options.Validate().ok());
  options.gate_px = 0;
  EXPECT_NE(options.Validate().message().find("gate_px"), std::string::npos);
  options = WireFitOptions{};
  options.passes = 0;
  EXPECT_NE(options.Validate().message().find("passes"), std::string::npos);
  TrellisOptions trellis;
  trellis.wire_fit.knot_spacing_m = -1;
  EXPECT_NE(trellis.Validate().message().find("knot_spacing_m"), std::string::npos);
}

}  // namespace
}  // namespace vb::reconstruct
