// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/correspondence.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

Cane MakeCane(int id, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  Cane cane;
  cane.id = CaneId(id);
  cane.kind = id == 1 ? CaneKind::kTrunk : CaneKind::kCane;
  if (id != 1) cane.parent_id = CaneId(1);
  cane.polyline.points = {a, b};
  cane.polyline.radii = {radius, radius};
  return cane;
}

RigCalibration Rig(int cameras) {
  sim::RigOptions options;
  options.camera_count = cameras;
  return sim::MakeRig(options).value();
}

// Points of a piece, sampled along its polyline every 2 mm.
std::vector<Eigen::Vector3d> PiecePoints(const Piece3D& piece) { return piece.polyline.Sample(0.002); }

double MaxDistance(const Piece3D& piece, const Polyline3& truth) {
  double worst = 0.0;
  for (const Eigen::Vector3d& p : PiecePoints(piece)) worst = std::max(worst, DistanceToPolyline(p, truth));
  return worst;
}

// Fraction of `truth` (sampled every 5 mm) within `tolerance_m` of some piece.
double Coverage(const Polyline3& truth, const std::vector<Piece3D>& pieces, double tolerance_m) {
  const std::vector<Eigen::Vector3d> samples = truth.Sample(0.005);
  int covered = 0;
  for (const Eigen::Vector3d& s : samples) {
    for (const Piece3D& piece : pieces) {
      if (DistanceToPolyline(s, piece.polyline) <= tolerance_m) {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / samples.size();
}

TEST(MatchSegments, StraightCaneInTwoViewsReconstructsWithin2mm) {
  VineModel model;
  // Oblique in the image (well conditioned for the horizontal pair) and receding in depth.
  model.canes.push_back(MakeCane(1, {-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, 0.004));
  const RigCalibration rig = Rig(2);
  const std::vector<View2D> views = SyntheticViews(model, rig);
  const auto pieces = MatchSegments(views, rig, {}, Deadline::Infinite());
  ASSERT_TRUE(pieces.ok()) << pieces.status();
  ASSERT_EQ(pieces->size(), 1u);
  const Piece3D& piece = pieces->front();
  EXPECT_LT(MaxDistance(piece, model.canes[0].polyline), 0.002);
  EXPECT_GT(Coverage(model.canes[0].polyline, *pieces, 0.002), 0.9);
  EXPECT_GT(piece.probability, 0.5);
  EXPECT_EQ(piece.view_a, 0);
  EXPECT_EQ(piece.view_b, 1);
  EXPECT_GT(piece.support, 0.95);
  for (double r : piece.polyline.radii) EXPECT_NEAR(r, 0.004, 0.001);
}

TEST(MatchSegments, CrossingCanesAreNotMerged) {
  VineModel model;
  model.canes.push_back(MakeCane(1, {-0.2, 0.8, 0.85}, {0.2, 0.78, 1.2}, 0.005));
  model.canes.push_back(MakeCane(2, {-0.2, 0.84, 1.2}, {0.2, 0.8, 0.85}, 0.004));
  for (int cameras : {2, 3}) {
    SCOPED_TRACE(cameras);
    const RigCalibration rig = Rig(cameras);
    const std::vector<View2D> views = SyntheticViews(model, rig);
    const auto pieces = MatchSegments(views, rig, {}, Deadline::Infinite());
    ASSERT_TRUE(pieces.ok()) << pieces.status();
    if (cameras == 2) EXPECT_EQ(pieces->size(), 2u);
    for (const Piece3D& piece : *pieces) {
      const double d0 = MaxDistance(piece, model.canes[0].polyline);
      const double d1 = MaxDistance(piece, model.canes[1].polyline);
      EXPECT_LT(std::min(d0, d1), 0.003) << "piece of views " << piece.view_a << ","
                                         << piece.view_b;
    }
    for (const Cane& cane : model.canes) EXPECT_GT(Coverage(cane.polyline, *pieces, 0.003), 0.9);
  }
}

TEST(MatchSegments, EmptyViewsGiveNoPieces) {
  const RigCalibration rig = Rig(3);
  const std::vector<View2D> drawn = SyntheticViews(VineModel{}, rig);
  auto pieces = MatchSegments(drawn, rig, {}, Deadline::Infinite());
  ASSERT_TRUE(pieces.ok()) << pieces.status();
  EXPECT_TRUE(pieces->empty());
  pieces = MatchSegments(std::vector<View2D>(3), rig, {}, Deadline::Infinite());
  ASSERT_TRUE(pieces.ok()) << pieces.status();
  EXPECT_TRUE(pieces->empty());
}

TEST(MatchSegments, BadInputRejects) {
  VineModel model;
  model.canes.push_back(MakeCane(1, {-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, 0.004));
  const RigCalibration rig = Rig(3);
  const std::vector<View2D> views = SyntheticViews(model, rig);
  const auto code = [](const absl::StatusOr<std::vector<Piece3D>>& r) { return r.status().code(); };
  const CorrespondenceOptions options;
  const auto inf = Deadline::Infinite();
  // View/camera count mismatch, and fewer than two views.
  EXPECT_EQ(code(MatchSegments({views[0], views[1]}, rig, options, inf)),
            absl::StatusCode::kInvalidArgument);
  RigCalibration one;
  one.cameras = {rig.cameras[0]};
  EXPECT_EQ(code(MatchSegments({views[0]}, one, options, inf)), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(code(MatchSegments({}, RigCalibration{}, options, inf)),
            absl::StatusCode::kInvalidArgument);
  // Coincident camera centres.
  RigCalibration coincident = rig;
  coincident.cameras[1].translation_camera_from_platform =
      -coincident.cameras[1].rotation_camera_from_platform * rig.cameras[0].CentreInPlatform();
  const auto r = MatchSegments(views, coincident, options, inf);
  EXPECT_EQ(code(r), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(r.status().message()).find("apart"), std::string::npos) << r.status();
  // Non-finite calibration.
  RigCalibration nan = rig;
  nan.cameras[2].camera_matrix(0, 0) = NAN;
  EXPECT_EQ(code(MatchSegments(views, nan, options, inf)), absl::StatusCode::kInvalidArgument);
  nan = rig;
  nan.cameras[0].distortion[0] = INFINITY;
  EXPECT_EQ(code(MatchSegments(views, nan, options, inf)), absl::StatusCode::kInvalidArgument);
  // Non-finite 2D data, widths not one per point, wrong view size.
  std::vector<View2D> bad = views;
  bad[1].segments[0].points[3].x() = NAN;
  EXPECT_EQ(code(MatchSegments(bad, rig, options, inf)), absl::StatusCode::kInvalidArgument);
  bad = views;
  bad[1].segments[0].widths_px.pop_back();
  EXPECT_EQ(code(MatchSegments(bad, rig, options, inf)), absl::StatusCode::kInvalidArgument);
  bad = views;
  bad[2].width = 640;
  EXPECT_EQ(code(MatchSegments(bad, rig, options, inf)), absl::StatusCode::kInvalidArgument);
  // Bad options.
  CorrespondenceOptions bad_options;
  bad_options.alpha = 0.0;
  EXPECT_EQ(code(MatchSegments(views, rig, bad_options, inf)), absl::StatusCode::kInvalidArgument);
  bad_options = {};
  bad_options.sample_step_px = NAN;
  EXPECT_EQ(code(MatchSegments(views, rig, bad_options, inf)), absl::StatusCode::kInvalidArgument);
}

TEST(MatchSegments, ExpiredDeadlineFails) {
  VineModel model;
  model.canes.push_back(MakeCane(1, {-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, 0.004));
  const RigCalibration rig = Rig(3);
  const std::vector<View2D> views = SyntheticViews(model, rig);
  const auto pieces = MatchSegments(views, rig, {}, Deadline::In(0.0));
  EXPECT_EQ(pieces.status().code(), absl::StatusCode::kDeadlineExceeded);
  std::atomic<bool> cancelled{true};
  EXPECT_EQ(MatchSegments(views, rig, {}, Deadline::In(10.0, &cancelled)).status().code(),
            absl::StatusCode::kCancelled);
}

// Part of each true cane seen by at least two cameras, as polylines (split where it is not).
std::vector<Polyline3> SeenByTwo(const Polyline3& cane, const RigCalibration& rig) {
  std::vector<Polyline3> parts;
  Polyline3 current;
  for (const Eigen::Vector3d& p : cane.Sample(0.005)) {
    int seen = 0;
    for (const CameraCalibration& camera : rig.cameras) {
      const auto uv = camera.Project(p);
      seen += uv && camera.InImage(*uv) ? 1 : 0;
    }
    if (seen >= 2) {
      current.points.push_back(p);
      current.radii.push_back(0.001);
    } else if (!current.points.empty()) {
      if (current.points.size() >= 2) parts.push_back(current);
      current = {};
    }
  }
  if (current.points.size() >= 2) parts.push_back(current);
  return parts;
}

TEST(MatchSegments, SyntheticVineIsCoveredAndPrecise) {
  const uint64_t seed = 1234;  // training range [1000, 1999]; >= 9000 is the benchmark's
  const sim::Scene scene = sim::GenerateScene(seed, 0).value();
  const RigCalibration truth_rig = Rig(3);
  const RigCalibration rig = sim::PerturbCalibration(truth_rig, 1.0, seed);
  const std::vector<View2D> views = SyntheticViews(scene.vine, truth_rig);
  const auto start = std::chrono::steady_clock::now();
  const auto pieces = MatchSegments(views, rig, {}, Deadline::Infinite());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(pieces.ok()) << pieces.status();

  double truth_length = 0.0, covered_length = 0.0;
  for (const Cane& cane : scene.vine.canes) {
    for (const Polyline3& part : SeenByTwo(cane.polyline, truth_rig)) {
      truth_length += part.Length();
      covered_length += part.Length() * Coverage(part, *pieces, 0.01);
    }
  }
  double piece_length = 0.0, precise_length = 0.0;
  for (const Piece3D& piece : *pieces) {
    const std::vector<Eigen::Vector3d> points = PiecePoints(piece);
    int near = 0;
    for (const Eigen::Vector3d& p : points) {
      for (const Cane& cane : scene.vine.canes) {
        if (DistanceToPolyline(p, cane.polyline) <= 0.01) {
          ++near;
          break;
        }
      }
    }
    piece_length += piece.polyline.Length();
    precise_length += piece.polyline.Length() * near / std::max<size_t>(1, points.size());
  }
  size_t segments = 0;
  for (const View2D& v : views) segments += v.segments.size();
  const double coverage = covered_length / truth_length;
  const double precision = precise_length / std::max(piece_length, 1e-9);
  std::printf("[ synthetic vine seed %llu ] %zu canes, %zu segments in 3 views, %zu pieces; "
              "coverage %.3f of %.2f m, precision %.3f of %.2f m; MatchSegments %.0f ms\n",
              static_cast<unsigned long long>(seed), scene.vine.canes.size(), segments,
              pieces->size(), coverage, truth_length, precision, piece_length, 1e3 * seconds);
  EXPECT_GE(coverage, 0.8);
  EXPECT_GE(precision, 0.9);
}

}  // namespace
}  // namespace vb::reconstruct
