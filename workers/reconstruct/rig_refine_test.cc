// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/rig_refine.h"

#include <cmath>

#include "gtest/gtest.h"
#include "sim/fiducials.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// Turns a camera by `angle_rad` about `axis` (camera frame), keeping its centre.
CameraCalibration Turned(const CameraCalibration& camera, const Eigen::Vector3d& axis,
                         double angle_rad) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  CameraCalibration out = camera;
  out.rotation_camera_from_platform = r * camera.rotation_camera_from_platform;
  out.translation_camera_from_platform = r * camera.translation_camera_from_platform;
  return out;
}

// Pixel displacement between two calibrations of one camera at a point.
double Displacement(const CameraCalibration& a, const CameraCalibration& b,
                    const Eigen::Vector3d& p) {
  return (*a.Project(p) - *b.Project(p)).norm();
}

struct Stop {
  VineModel truth;
  RigCalibration true_rig;
  std::vector<View2D> views;       // drawn with the true rig
  std::vector<Piece3D> pieces;     // the true canes, as if matched with certainty
};

Stop MakeStop(uint64_t seed) {
  Stop stop;
  stop.truth = sim::GenerateScene(seed, 1).value().vine;
  stop.true_rig = sim::MakeRig().value();
  stop.views = SyntheticViews(stop.truth, stop.true_rig);
  for (const Cane& cane : stop.truth.canes) {
    if (cane.kind != CaneKind::kCane) continue;
    Piece3D piece;
    piece.polyline = cane.polyline;
    piece.probability = 1.0;
    piece.support = 1.0;
    stop.pieces.push_back(piece);
  }
  return stop;
}

TEST(RigRefine, RecoversTurnedCameras) {
  // Four stops: how well the distance field pins a camera depends on the stop (with the default
  // rig since session 24, 0.3-1.25 px from 3 px on 1100-1103; the 0.29 m triangle before it gave
  // 0.24-0.90 px).
  double sum[3] = {};
  const int stops = 4;
  for (uint64_t seed = 1100; seed < 1100 + stops; ++seed) {
    const Stop stop = MakeStop(seed);
    RigCalibration drifted = stop.true_rig;
    const double pixel = 1.0 / drifted.cameras[1].camera_matrix(0, 0);
    drifted.cameras[1] = Turned(drifted.cameras[1], {1, 0.3, 0}, 3.0 * pixel);
    drifted.cameras[2] = Turned(drifted.cameras[2], {0.2, 1, 0.5}, 3.0 * pixel);
    const Eigen::Vector3d probe(0.1, 0.8, 1.0);
    RigRefineOptions reference_cam0;  // cam0 is exact here: hold it
    reference_cam0.reference_camera = 0;
    ASSERT_GT(Displacement(drifted.cameras[1], stop.true_rig.cameras[1], probe), 2.0);

    RigRefineSummary summary;
    const absl::StatusOr<RigCalibration> refined = RefineRig(
        stop.views, drifted, stop.pieces, reference_cam0, Deadline::Infinite(), &summary);
    ASSERT_TRUE(refined.ok()) << refined.status();
    ASSERT_TRUE(summary.applied) << summary.reason;
    EXPECT_GE(summary.points, 60);
    EXPECT_EQ(summary.correction_px[0], 0.0);
    EXPECT_LT(summary.median_after_px, summary.median_before_px);
    // From 3 px to within half of it on every stop, and a third on average: the synthetic
    // skeletons are rasterised at whole pixels, which limits how well the distance field pins a
    // camera.
    for (int v = 1; v <= 2; ++v) {
      const double d = Displacement(refined->cameras[v], stop.true_rig.cameras[v], probe);
      EXPECT_LT(d, 1.5) << "seed " << seed << " camera " << v;
      sum[v] += d;
      EXPECT_NEAR((refined->cameras[v].CentreInPlatform() -
                   stop.true_rig.cameras[v].CentreInPlatform()).norm(), 0.0, 1e-9);
    }
  }
  for (int v = 1; v <= 2; ++v) EXPECT_LT(sum[v] / stops, 1.0) << v;
}

// Least-squares intersection of the rays through `uv` (one pixel per camera of `rig`).
Eigen::Vector3d Triangulate(const RigCalibration& rig, const std::vector<Eigen::Vector2d>& uv) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < uv.size(); ++i) {
    const Eigen::Vector3d d = rig.cameras[i].RayInPlatform(uv[i]);
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * rig.cameras[i].CentreInPlatform();
  }
  return a.ldlt().solve(b);
}

// RMS 3D error of triangulating true image points of the vine plane with `rig`.
double TriangulationRmsM(const RigCalibration& true_rig, const RigCalibration& rig) {
  double sum = 0.0;
  int n = 0;
  for (double x = -0.6; x <= 0.61; x += 0.3) {
    for (double z = 0.4; z <= 1.81; z += 0.35) {
      const Eigen::Vector3d p(x, 0.8, z);
      std::vector<Eigen::Vector2d> uv;
      for (const CameraCalibration& camera : true_rig.cameras) uv.push_back(*camera.Project(p));
      sum += (Triangulate(rig, uv) - p).squaredNorm();
      ++n;
    }
  }
  return std::sqrt(sum / n);
}

// With every camera drifted (none exact to hold as the reference), the refinement spreads the
// correction over all cameras under the priors; triangulation of the vine plane improves on
// every drift and halves overall.
TEST(RigRefine, HalvesTriangulationErrorOfAPerturbedRig) {
  const Stop stop = MakeStop(1105);
  double sum_before = 0.0, sum_after = 0.0;
  for (uint64_t seed : {1, 2, 3, 4, 5, 6}) {
    const RigCalibration drifted = sim::PerturbCalibration(stop.true_rig, 1.0, seed);
    RigRefineSummary summary;
    const absl::StatusOr<RigCalibration> refined =
        RefineRig(stop.views, drifted, stop.pieces, {}, Deadline::Infinite(), &summary);
    ASSERT_TRUE(refined.ok()) << refined.status();
    ASSERT_TRUE(summary.applied) << summary.reason;
    const double before = TriangulationRmsM(stop.true_rig, drifted);
    const double after = TriangulationRmsM(stop.true_rig, *refined);
    EXPECT_LT(after, before) << "seed " << seed;
    sum_before += before;
    sum_after += after;
  }
  EXPECT_LT(sum_after, 0.5 * sum_before) << sum_before << " m -> " << sum_after << " m";
}

// The 2D stage measures wire and post lines in pixels and expresses them through the calibration
// it is given: for views drawn with the true rig, that is the drifted one.
std::vector<View2D> ViewsMeasuredWith(const Stop& stop, const RigCalibration& drifted) {
  std::vector<View2D> views = stop.views;
  for (size_t v = 0; v < views.size(); ++v) {
    ReexpressLines(stop.true_rig.cameras[v], drifted.cameras[v], &views[v].wires);
    ReexpressLines(stop.true_rig.cameras[v], drifted.cameras[v], &views[v].posts);
  }
  return views;
}

std::vector<TrellisLineMatch> MatchTrellis(const std::vector<View2D>& views,
                                           const RigCalibration& rig) {
  TrellisOptions options;
  options.max_residual_px = RigRefineOptions().trellis_match_residual_px;
  return MatchTrellisLines(views, rig, WorkingVolume(), options).value();
}

// A wire matched to the wrong line in one view (the next wire up) misses its traces by tens of
// pixels once fitted to the canes' rig: it is left out, and the rig comes out as from the canes
// and the other wires.
TEST(RigRefine, LeavesOutAMismatchedWire) {
  const Stop stop = MakeStop(1101);
  const RigCalibration drifted = sim::PerturbCalibration(stop.true_rig, 1.0, 3);
  const std::vector<View2D> views = ViewsMeasuredWith(stop, drifted);
  std::vector<TrellisLineMatch> trellis = MatchTrellis(views, drifted);
  ASSERT_EQ(trellis.size(), 4u);  // the scene's four wires; no post in view
  RigRefineOptions options;
  options.use_trellis = true;
  RigRefineSummary good;
  const auto with_good = RefineRig(views, drifted, stop.pieces, trellis, options,
                                   Deadline::Infinite(), &good);
  ASSERT_TRUE(with_good.ok()) << with_good.status();
  EXPECT_EQ(good.trellis_rejected, 0);
  EXPECT_EQ(good.trellis_lines, 4);
  trellis[0].lines[2] = trellis[1].lines[2];  // wire 0 given wire 1's line in view 2
  RigRefineSummary bad;
  const auto with_bad = RefineRig(views, drifted, stop.pieces, trellis, options,
                                  Deadline::Infinite(), &bad);
  ASSERT_TRUE(with_bad.ok()) << with_bad.status();
  ASSERT_TRUE(bad.applied) << bad.reason;
  EXPECT_EQ(bad.trellis_rejected, 1);
  EXPECT_EQ(bad.trellis_lines, 3);
  EXPECT_LT(TriangulationRmsM(stop.true_rig, *with_bad),
            1.1 * TriangulationRmsM(stop.true_rig, *with_good) + 1e-4);
}

// On rigs drifted in every camera and every parameter, with every cane piece certain, the trellis
// does not help (docs/reconstruction.md, 3b); the refinement must still halve the error.
TEST(RigRefine, WithTheTrellisStillHalvesTriangulationErrorOfAPerturbedRig) {
  const Stop stop = MakeStop(1105);
  double sum_before = 0.0, sum_after = 0.0;
  for (uint64_t seed : {1, 2, 3, 4, 5, 6}) {
    const RigCalibration drifted = sim::PerturbCalibration(stop.true_rig, 1.0, seed);
    const std::vector<View2D> views = ViewsMeasuredWith(stop, drifted);
    RigRefineOptions options;
    options.use_trellis = true;
    RigRefineSummary summary;
    const absl::StatusOr<RigCalibration> refined = RefineRig(
        views, drifted, stop.pieces, MatchTrellis(views, drifted), options, Deadline::Infinite(),
        &summary);
    ASSERT_TRUE(refined.ok()) << refined.status();
    ASSERT_TRUE(summary.applied) << summary.reason;
    EXPECT_GE(summary.trellis_lines, 3) << "seed " << seed;
    sum_before += TriangulationRmsM(stop.true_rig, drifted);
    sum_after += TriangulationRmsM(stop.true_rig, *refined);
  }
  EXPECT_LT(sum_after, 0.6 * sum_before) << sum_before << " m -> " << sum_after << " m";
}

TEST(RigRefine, RejectsTrellisLinesTheViewsDoNotHave) {
  const Stop stop = MakeStop(1104);
  TrellisLineMatch match;
  match.a = {-0.8, 0.8, 1.0};
  match.b = {0.8, 0.8, 1.0};
  match.lines = {0, 0, 99};
  const auto status =
      RefineRig(stop.views, stop.true_rig, stop.pieces, {match}, {}, Deadline::Infinite());
  EXPECT_EQ(status.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.status().message().find("trellis[0].lines[2]"), std::string::npos)
      << status.status();
  match.lines = {0, 0};
  EXPECT_EQ(RefineRig(stop.views, stop.true_rig, stop.pieces, {match}, {}, Deadline::Infinite())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(RigRefine, LeavesAnExactRigAlone) {
  const Stop stop = MakeStop(1102);
  RigRefineSummary summary;
  const absl::StatusOr<RigCalibration> refined =
      RefineRig(stop.views, stop.true_rig, stop.pieces, {}, Deadline::Infinite(), &summary);
  ASSERT_TRUE(refined.ok()) << refined.status();
  for (size_t v = 0; v < refined->cameras.size(); ++v) EXPECT_LT(summary.correction_px[v], 0.3);
}

TEST(RigRefine, TooFewConfidentPointsKeepsTheRig) {
  Stop stop = MakeStop(1103);
  for (Piece3D& piece : stop.pieces) piece.probability = 0.5;  // nothing confident
  RigCalibration drifted = stop.true_rig;
  drifted.cameras[1] = Turned(drifted.cameras[1], {1, 0, 0}, 0.003);
  RigRefineSummary summary;
  const absl::StatusOr<RigCalibration> refined =
      RefineRig(stop.views, drifted, stop.pieces, {}, Deadline::Infinite(), &summary);
  ASSERT_TRUE(refined.ok());
  EXPECT_FALSE(summary.applied);
  EXPECT_NE(summary.reason.find("confident points"), std::string::npos) << summary.reason;
  EXPECT_EQ(refined->cameras[1].rotation_camera_from_platform,
            drifted.cameras[1].rotation_camera_from_platform);
}

TEST(RigRefine, RejectsMismatchedViews) {
  const Stop stop = MakeStop(1104);
  std::vector<View2D> views = stop.views;
  views.pop_back();
  EXPECT_EQ(RefineRig(views, stop.true_rig, stop.pieces, {}, Deadline::Infinite()).status().code(),
            absl::StatusCode::kInvalidArgument);
  RigRefineOptions bad;
  bad.reference_camera = 7;
  const auto status = RefineRig(stop.views, stop.true_rig, stop.pieces, bad, Deadline::Infinite());
  EXPECT_EQ(status.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.status().message().find("reference_camera"), std::string::npos);
}

}  // namespace
}  // namespace vb::reconstruct

namespace vb::reconstruct {
namespace {

// Wires drawn from a model end far outside the image (beyond the lens's fold); re-expressing them
// for the same camera must give the same line, and for a longer focal length the line seen
// through the same pixels.
// The platform's fiducials as the detector would report them for images taken by `true_rig`:
// at their true projections, plus a deterministic error of up to `noise_px` in each coordinate.
std::vector<View2D> WithFiducials(std::vector<View2D> views, const RigCalibration& true_rig,
                                  const RigCalibration& calibrated, double noise_px) {
  int k = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    for (size_t f = 0; f < true_rig.fiducials.size(); ++f) {
      const Eigen::Vector3d& p = true_rig.fiducials[f].position_in_platform;
      const auto uv = true_rig.cameras[v].Project(p);
      const auto expected = calibrated.cameras[v].Project(p);
      if (!uv || !true_rig.cameras[v].InImage(*uv) || !expected) continue;
      ++k;
      const Eigen::Vector2d error(noise_px * std::sin(1.7 * k), noise_px * std::cos(2.3 * k));
      views[v].fiducials.push_back({static_cast<int>(f), *uv + error, *expected});
    }
  }
  return views;
}

RigCalibration WithPlatformFiducials(RigCalibration rig) {
  rig.fiducials = sim::PlatformFiducials().value();
  return rig;
}

// No cane at all: the fiducials alone pull every camera of a drifted rig back to the truth (to
// a small fraction of the drift, with 0.2 px of detection error).
TEST(RigRefine, FiducialsAlonePullADriftedRigBack) {
  const Stop stop = MakeStop(1101);
  const RigCalibration true_rig = WithPlatformFiducials(stop.true_rig);
  for (uint64_t seed : {1, 2, 3}) {
    const RigCalibration drifted = sim::PerturbCalibration(true_rig, 1.0, seed);
    const std::vector<View2D> views = WithFiducials(stop.views, true_rig, drifted, 0.2);
    RigRefineSummary summary;
    const absl::StatusOr<RigCalibration> refined =
        RefineRig(views, drifted, /*pieces=*/{}, {}, Deadline::Infinite(), &summary);
    ASSERT_TRUE(refined.ok()) << refined.status();
    ASSERT_TRUE(summary.applied) << summary.reason;
    EXPECT_EQ(summary.points, 0);
    EXPECT_EQ(summary.fiducials_rejected, 0);
    EXPECT_LT(summary.fiducial_rms_after_px, 0.5 * summary.fiducial_rms_before_px);
    for (size_t c = 0; c < true_rig.cameras.size(); ++c) {
      const double before = sim::ReprojectionRmsPx(true_rig.cameras[c], drifted.cameras[c]);
      const double after = sim::ReprojectionRmsPx(true_rig.cameras[c], refined->cameras[c]);
      EXPECT_LT(after, 0.25 * before) << "seed " << seed << " camera " << c << ": " << before
                                      << " px -> " << after << " px";
    }
  }
}

// With too few fiducials and no canes, nothing is refined.
TEST(RigRefine, TooFewFiducialsAndNoCanesKeepsTheRig) {
  const Stop stop = MakeStop(1101);
  const RigCalibration true_rig = WithPlatformFiducials(stop.true_rig);
  const RigCalibration drifted = sim::PerturbCalibration(true_rig, 1.0, 1);
  std::vector<View2D> views = WithFiducials(stop.views, true_rig, drifted, 0.0);
  for (View2D& view : views) view.fiducials.resize(3);
  RigRefineSummary summary;
  const auto refined = RefineRig(views, drifted, {}, {}, Deadline::Infinite(), &summary);
  ASSERT_TRUE(refined.ok()) << refined.status();
  EXPECT_FALSE(summary.applied);
  EXPECT_NE(summary.reason.find("fiducials"), std::string::npos) << summary.reason;
}

// The canes leave the depth distortion of the whole rig loose; with the fiducials too,
// triangulation of the vine plane comes out better than from the canes alone on every drift.
TEST(RigRefine, FiducialsImproveOnTheCanesAlone) {
  const Stop stop = MakeStop(1105);
  const RigCalibration true_rig = WithPlatformFiducials(stop.true_rig);
  double sum_canes = 0.0, sum_both = 0.0, sum_before = 0.0;
  for (uint64_t seed : {1, 2, 3, 4, 5, 6}) {
    const RigCalibration drifted = sim::PerturbCalibration(true_rig, 1.0, seed);
    RigRefineOptions canes_only;
    canes_only.use_fiducials = false;
    const std::vector<View2D> views = WithFiducials(stop.views, true_rig, drifted, 0.2);
    const auto canes = RefineRig(views, drifted, stop.pieces, canes_only, Deadline::Infinite());
    RigRefineSummary summary;
    const auto both = RefineRig(views, drifted, stop.pieces, {}, Deadline::Infinite(), &summary);
    ASSERT_TRUE(canes.ok() && both.ok());
    ASSERT_TRUE(summary.applied) << summary.reason;
    EXPECT_GT(summary.fiducial_observations, 30);
    const double after_canes = TriangulationRmsM(true_rig, *canes);
    const double after_both = TriangulationRmsM(true_rig, *both);
    EXPECT_LT(after_both, after_canes) << "seed " << seed;
    sum_before += TriangulationRmsM(true_rig, drifted);
    sum_canes += after_canes;
    sum_both += after_both;
  }
  EXPECT_LT(sum_both, 0.5 * sum_canes)
      << "before " << sum_before << " m, canes " << sum_canes << " m, with fiducials " << sum_both;
}

// A detection of something else 12 px from a fiducial is rejected and named in the log; the rig
// still comes back.
TEST(RigRefine, RejectsAFiducialDetectionFarFromItsFiducial) {
  const Stop stop = MakeStop(1101);
  const RigCalibration true_rig = WithPlatformFiducials(stop.true_rig);
  const RigCalibration drifted = sim::PerturbCalibration(true_rig, 1.0, 2);
  std::vector<View2D> views = WithFiducials(stop.views, true_rig, drifted, 0.1);
  ASSERT_GE(views[1].fiducials.size(), 5u);
  views[1].fiducials[2].uv_px += Eigen::Vector2d(9.0, -8.0);
  const std::string name = true_rig.fiducials[views[1].fiducials[2].fiducial].name;
  RigRefineSummary summary;
  const auto refined = RefineRig(views, drifted, stop.pieces, {}, Deadline::Infinite(), &summary);
  ASSERT_TRUE(refined.ok()) << refined.status();
  ASSERT_TRUE(summary.applied) << summary.reason;
  EXPECT_EQ(summary.fiducials_rejected, 1);
  ASSERT_EQ(summary.fiducial_log.size(), 1u);
  EXPECT_NE(summary.fiducial_log[0].find("cam1 " + name), std::string::npos)
      << summary.fiducial_log[0];
  for (size_t c = 0; c < true_rig.cameras.size(); ++c) {
    EXPECT_LT(sim::ReprojectionRmsPx(true_rig.cameras[c], refined->cameras[c]),
              0.5 * sim::ReprojectionRmsPx(true_rig.cameras[c], drifted.cameras[c]))
        << "camera " << c;
  }
}

TEST(RigRefine, RejectsAFiducialIndexTheRigDoesNotHave) {
  const Stop stop = MakeStop(1101);
  std::vector<View2D> views = stop.views;
  views[0].fiducials.push_back({3, Eigen::Vector2d(100, 100), Eigen::Vector2d(100, 100)});
  const auto refined = RefineRig(views, stop.true_rig, stop.pieces, {}, Deadline::Infinite());
  ASSERT_FALSE(refined.ok());
  EXPECT_EQ(refined.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(refined.status().message().find("views[0].fiducials[0]"), std::string::npos);
}

TEST(ReexpressLines, KeepsLinesThatEndOutsideTheImage) {
  const Stop stop = MakeStop(1106);
  const CameraCalibration& camera = stop.true_rig.cameras[0];
  std::vector<Line2D> wires = stop.views[0].wires;
  ASSERT_FALSE(wires.empty());
  std::vector<Line2D> same = wires;
  ReexpressLines(camera, camera, &same);
  CameraCalibration longer = camera;
  longer.camera_matrix(0, 0) *= 1.002;
  longer.camera_matrix(1, 1) *= 1.002;
  std::vector<Line2D> scaled = wires;
  ReexpressLines(camera, longer, &scaled);
  // A quarter pixel in normalised units: the lens maps a line through a new focal length to a
  // slightly curved one, which the refit straightens.
  const double quarter_px = 0.25 / camera.camera_matrix(0, 0);
  for (size_t i = 0; i < wires.size(); ++i) {
    ASSERT_GT((same[i].end - same[i].begin).norm(), 0.1) << "wire " << i << " lost its support";
    for (double f : {0.1, 0.5, 0.9}) {
      const Eigen::Vector2d p = same[i].begin + f * (same[i].end - same[i].begin);
      EXPECT_NEAR(wires[i].line.dot(p.homogeneous()), 0.0, 1e-9) << "wire " << i;
      const Eigen::Vector2d uv = camera.NormalisedToPixel(p);
      EXPECT_NEAR(scaled[i].line.dot(longer.PixelToNormalised(uv).homogeneous()), 0.0, quarter_px)
          << "wire " << i;
    }
  }
}

}  // namespace
}  // namespace vb::reconstruct
