// SPDX-License-Identifier: Apache-2.0
// MatchSegments on one or two straight canes: reconstruction, crossings, empty views, bad input
// and deadlines; and MatchWithRigRefinement's choice of classifier per pass. The epipolar
// geometry cases are in correspondence_epipolar_test.cc, whole simulated vines in
// correspondence_sim_test.cc.
#include "workers/reconstruct/correspondence.h"

#include <atomic>
#include <cmath>
#include <string>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/match_segments_test_util.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// A cane oblique in the image (well conditioned for the horizontal pair) and receding in depth,
// in the views of `cameras` cameras.
OneCaneViews ObliqueCane(int cameras) {
  return DrawOneCane({-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, cameras);
}

TEST(MatchSegments, StraightCaneInTwoViewsReconstructsWithin2mm) {
  const auto [model, rig, views] = ObliqueCane(2);
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
    if (cameras == 2) {
      EXPECT_EQ(pieces->size(), 2u);
    }
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
  const auto [model, rig, views] = ObliqueCane(3);
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
  // A quadratic match model that does not fit its features or holds a non-finite weight.
  CorrespondenceOptions bad_model;
  bad_model.classifier.multi_view_quadratic.weights.pop_back();
  auto rejected = MatchSegments(views, rig, bad_model, inf);
  EXPECT_EQ(code(rejected), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(rejected.status().message()).find("classifier: quadratic model: weights"),
            std::string::npos)
      << rejected.status();
  bad_model = {};
  bad_model.classifier.multi_view_quadratic.weights[7] = NAN;
  rejected = MatchSegments(views, rig, bad_model, inf);
  EXPECT_NE(std::string(rejected.status().message()).find("weights[7]"), std::string::npos)
      << rejected.status();
  // Strand halves: a sibling out of range, steps not one per point, a non-finite width.
  StrandHalf half;
  half.path = views[1].segments[0];
  half.to_sibling_px.assign(half.path.points.size(), Eigen::Vector2d(0.0, 4.0));
  half.sibling = 0;
  bad = views;
  bad[1].strand_halves = {half};
  EXPECT_TRUE(MatchSegments(bad, rig, options, inf).ok());  // a well-formed half is searched
  for (int k = 0; k < 3; ++k) {
    bad = views;
    bad[1].strand_halves = {half};
    if (k == 0) bad[1].strand_halves[0].sibling = 1;
    if (k == 1) bad[1].strand_halves[0].to_sibling_px.pop_back();
    if (k == 2) bad[1].strand_halves[0].path.widths_px[2] = NAN;
    const auto r = MatchSegments(bad, rig, options, inf);
    EXPECT_EQ(code(r), absl::StatusCode::kInvalidArgument) << k;
    EXPECT_NE(std::string(r.status().message()).find("views[1].strand_halves[0]"),
              std::string::npos)
        << r.status();
  }
  // Bad options.
  CorrespondenceOptions bad_options;
  bad_options.alpha = 0.0;
  EXPECT_EQ(code(MatchSegments(views, rig, bad_options, inf)), absl::StatusCode::kInvalidArgument);
  bad_options = {};
  bad_options.sample_step_px = NAN;
  EXPECT_EQ(code(MatchSegments(views, rig, bad_options, inf)), absl::StatusCode::kInvalidArgument);
  bad_options = {};
  bad_options.max_ill_conditioned_gap_samples = -1;
  const auto gap = MatchSegments(views, rig, bad_options, inf);
  EXPECT_EQ(code(gap), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(gap.status().message()).find("max_ill_conditioned_gap_samples"),
            std::string::npos)
      << gap.status();
  bad_options = {};
  bad_options.min_epipolar_sin_refined = 1.0;
  const auto sin_refined = MatchSegments(views, rig, bad_options, inf);
  EXPECT_EQ(code(sin_refined), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(sin_refined.status().message()).find("min_epipolar_sin_refined"),
            std::string::npos)
      << sin_refined.status();
  const char* const fields[] = {"other_views.gate_px", "other_views.min_cos",
                                "other_views.max_residual_growth_px", "other_views.rounds",
                                "other_views.min_associations"};
  for (int k = 0; k < 5; ++k) {
    bad_options = {};
    if (k == 0) bad_options.other_views.gate_px = 0.0;
    if (k == 1) bad_options.other_views.min_cos = 1.5;
    if (k == 2) bad_options.other_views.max_residual_growth_px = NAN;
    if (k == 3) bad_options.other_views.rounds = -1;
    if (k == 4) bad_options.other_views.min_associations = 0;
    const auto other = MatchSegments(views, rig, bad_options, inf);
    EXPECT_EQ(code(other), absl::StatusCode::kInvalidArgument) << k;
    EXPECT_NE(std::string(other.status().message()).find(fields[k]), std::string::npos)
        << other.status();
  }
}

TEST(MatchSegments, ExpiredDeadlineFails) {
  const auto [model, rig, views] = ObliqueCane(3);
  const auto pieces = MatchSegments(views, rig, {}, Deadline::In(0.0));
  EXPECT_EQ(pieces.status().code(), absl::StatusCode::kDeadlineExceeded);
  std::atomic<bool> cancelled{true};
  EXPECT_EQ(MatchSegments(views, rig, {}, Deadline::In(10.0, &cancelled)).status().code(),
            absl::StatusCode::kCancelled);
}

// The first pass (the rig as calibrated) is scored by ReconstructOptions::first_pass_classifier,
// the second by correspondence.classifier; with rig refinement off only the first pass runs.
TEST(MatchWithRigRefinement, FirstPassUsesTheFirstPassClassifier) {
  const auto [model, rig, views] = ObliqueCane(3);
  ReconstructOptions options;
  options.rig_refine.enabled = false;
  const auto kept = MatchWithRigRefinement(views, rig, options, Deadline::Infinite());
  ASSERT_TRUE(kept.ok()) << kept.status();
  EXPECT_FALSE(kept->pieces.empty());
  options.first_pass_classifier.multi_view[0] = -100.0;  // rejects every candidate
  options.first_pass_classifier.two_view[0] = -100.0;
  const auto none = MatchWithRigRefinement(views, rig, options, Deadline::Infinite());
  ASSERT_TRUE(none.ok()) << none.status();
  EXPECT_TRUE(none->pieces.empty());
  // The second pass's classifier plays no part here.
  options = {};
  options.rig_refine.enabled = false;
  options.correspondence.classifier.multi_view[0] = -100.0;
  options.correspondence.classifier.multi_view_quadratic.weights[0] = -100.0;
  options.correspondence.classifier.two_view[0] = -100.0;
  const auto first = MatchWithRigRefinement(views, rig, options, Deadline::Infinite());
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->pieces.size(), kept->pieces.size());
}

TEST(MatchWithRigRefinement, NonFiniteFirstPassClassifierRejects) {
  const auto [model, rig, views] = ObliqueCane(3);
  ReconstructOptions options;
  options.first_pass_classifier.two_view[3] = NAN;
  const auto r = MatchWithRigRefinement(views, rig, options, Deadline::Infinite());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(r.status().message()).find("first_pass_classifier"), std::string::npos)
      << r.status();
}

}  // namespace
}  // namespace vb::reconstruct
