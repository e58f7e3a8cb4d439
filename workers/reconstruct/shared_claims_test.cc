// SPDX-License-Identifier: Apache-2.0
// The shared-claim relaxation of the one-to-one constraint (SharedClaimOptions, correspondence.h):
// two canes that lie along each other in one view but part in the other two keep both their
// candidates of a pair with that view; a ghost sharing a segment with a right candidate still
// conflicts with it; option validation names the field.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/match_segments_test_util.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// Two canes of radius 4 mm: A straight and upright; B's lower half on the rays of camera 0
// through A's lower half, 12% deeper (one path in view 0, parted by parallax in views 1 and 2),
// its upper half bending away sideways. Drawn as a skeleton draws canes lying along each other:
// in view 0 the shared stretch belongs to A only (SyntheticViewOptions::merge_overlaps).
struct AlongInOneView {
  VineModel model;
  RigCalibration rig;
  std::vector<View2D> views;
};
AlongInOneView DrawAlongInOneView() {
  AlongInOneView out;
  out.rig = Rig(3);
  const Eigen::Vector3d c0 = out.rig.cameras[0].CentreInPlatform();
  const Eigen::Vector3d a0(-0.02, 0.80, 0.80), a1(0.03, 0.82, 1.25);
  out.model.canes.push_back(MakeCane(2, a0, a1, 0.004));
  auto deeper = [&](const Eigen::Vector3d& p) { return c0 + 1.12 * (p - c0); };
  Cane b = MakeCane(3, deeper(a0), deeper(0.5 * (a0 + a1)), 0.004);
  b.polyline.points.push_back(b.polyline.points.back() + Eigen::Vector3d(0.14, 0.0, 0.17));
  b.polyline.radii.push_back(0.004);
  out.model.canes.push_back(b);
  SyntheticViewOptions draw;
  draw.break_at_crossings_px = 2.0;
  draw.merge_overlaps = true;
  out.views = SyntheticViews(out.model, out.rig, draw);
  return out;
}

// Index of the candidate of view pair (0, 2) lying on `cane` over at least 90% of its points
// within 5 mm whose segment in view 0 is `segment_a` (any when -1), the longest; -1 if none.
// (Pair (0, 2): in pair (0, 1), whose epipolar lines run across both canes, the run of A's
// samples that crosses B in view 1 goes on past the parting, a wrong match.)
int FindCandidate(const std::vector<ScoredCandidate>& candidates, const Polyline3& cane,
                  int segment_a) {
  int best = -1;
  size_t best_n = 0;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const ScoredCandidate& c = candidates[i];
    if (c.candidate.view_a != 0 || c.candidate.view_b != 2) continue;
    if (segment_a >= 0 && c.candidate.segment_a != segment_a) continue;
    if (!IsRightMatch(c.fit.points, {&cane}, 0.005, 0.9)) continue;
    if (c.fit.points.size() > best_n) {
      best_n = c.fit.points.size();
      best = static_cast<int>(i);
    }
  }
  return best;
}

bool Conflicts(const std::vector<std::vector<int>>& conflicts, int i, int j) {
  return std::find(conflicts[i].begin(), conflicts[i].end(), j) != conflicts[i].end();
}

TEST(SharedClaims, CanesAlongEachOtherInOneViewBothKeepTheirCandidates) {
  const AlongInOneView scene = DrawAlongInOneView();
  CorrespondenceOptions options;
  options.shared_claims.enabled = true;
  std::vector<ViewSamples> samples;
  const auto scored =
      ScoreCandidates(scene.views, scene.rig, options, Deadline::Infinite(), &samples);
  ASSERT_TRUE(scored.ok()) << scored.status();
  const Polyline3& a = scene.model.canes[0].polyline;
  const Polyline3& b = scene.model.canes[1].polyline;
  const int on_a = FindCandidate(*scored, a, -1);
  ASSERT_GE(on_a, 0);
  // B's stretch along A in view 0 can only be matched through A's segment there.
  const int on_b = FindCandidate(*scored, b, (*scored)[on_a].candidate.segment_a);
  ASSERT_GE(on_b, 0);
  const SharedClaimPair pair = DescribeSharedClaim(*scored, on_a, on_b, scene.views, samples,
                                                   scene.rig, options.min_conflict_overlap_px);
  EXPECT_EQ(pair.sides, 1);
  EXPECT_GT(pair.separation_m, 0.03);
  EXPECT_GT(pair.min_shared_support, 0.5);
  EXPECT_TRUE(RelaxesConflict(pair, options.shared_claims));

  // The one-to-one constraint alone makes them exclude each other; the relaxation does not.
  const auto strict = CandidateConflicts(*scored, options.min_conflict_overlap_px);
  EXPECT_TRUE(Conflicts(strict, on_a, on_b));
  const auto relaxed = CandidateConflicts(*scored, options, scene.views, samples, scene.rig);
  EXPECT_FALSE(Conflicts(relaxed, on_a, on_b));
  EXPECT_FALSE(Conflicts(relaxed, on_b, on_a));
  options.shared_claims.enabled = false;
  const auto off = CandidateConflicts(*scored, options, scene.views, samples, scene.rig);
  EXPECT_TRUE(Conflicts(off, on_a, on_b));
  options.shared_claims.enabled = true;

  // Both are selected, as pieces of pair (0, 2) on A's segment of view 0; without the
  // relaxation B's is not (its probability is the lower one).
  const int segment_a = (*scored)[on_a].candidate.segment_a;
  // Whether the selected pieces of pair (0, 2) on that segment include one within 6 mm of `cane`.
  auto selected_on = [&](const CorrespondenceOptions& o, const Polyline3& cane) {
    const auto pieces = MatchSegments(scene.views, scene.rig, o, Deadline::Infinite());
    EXPECT_TRUE(pieces.ok()) << pieces.status();
    if (!pieces.ok()) return false;
    for (const Piece3D& piece : *pieces) {
      if (piece.view_a == 0 && piece.view_b == 2 && piece.segment_a == segment_a &&
          MaxDistance(piece, cane) < 0.006) {
        return true;
      }
    }
    return false;
  };
  EXPECT_TRUE(selected_on(options, a));
  EXPECT_TRUE(selected_on(options, b));
  CorrespondenceOptions strict_options = options;
  strict_options.shared_claims.enabled = false;
  EXPECT_TRUE(selected_on(strict_options, a));
  EXPECT_FALSE(selected_on(strict_options, b));
}

TEST(SharedClaims, GhostSharingASegmentStillConflicts) {
  const AlongInOneView scene = DrawAlongInOneView();
  CorrespondenceOptions options;
  options.shared_claims.enabled = true;
  std::vector<ViewSamples> samples;
  auto scored = ScoreCandidates(scene.views, scene.rig, options, Deadline::Infinite(), &samples);
  ASSERT_TRUE(scored.ok()) << scored.status();
  const int on_a = FindCandidate(*scored, scene.model.canes[0].polyline, -1);
  ASSERT_GE(on_a, 0);
  // A ghost: A's claim in view 0 matched to another segment of view 2, so that its curve lies
  // 6 cm deeper along view 0's rays, where view 1 shows nothing.
  ScoredCandidate ghost = (*scored)[on_a];
  ghost.candidate.segment_b = static_cast<int>(scene.views[2].segments.size());
  const Eigen::Vector3d c0 = scene.rig.cameras[0].CentreInPlatform();
  for (Eigen::Vector3d& p : ghost.fit.points) p = c0 + (p - c0) * (1.0 + 0.06 / (p - c0).norm());
  for (Eigen::Vector3d& p : ghost.fit.control_points) {
    p = c0 + (p - c0) * (1.0 + 0.06 / (p - c0).norm());
  }
  scored->push_back(ghost);
  const int g = static_cast<int>(scored->size()) - 1;
  const SharedClaimPair pair = DescribeSharedClaim(*scored, on_a, g, scene.views, samples,
                                                   scene.rig, options.min_conflict_overlap_px);
  EXPECT_EQ(pair.sides, 1);
  EXPECT_GT(pair.separation_m, 0.04);
  EXPECT_LT(pair.min_shared_support, 0.3);
  EXPECT_FALSE(RelaxesConflict(pair, options.shared_claims));
  const auto conflicts = CandidateConflicts(*scored, options, scene.views, samples, scene.rig);
  EXPECT_TRUE(Conflicts(conflicts, on_a, g));
  EXPECT_TRUE(Conflicts(conflicts, g, on_a));

  // One cane twice (the same segments in both views) is never relaxed.
  ScoredCandidate twin = (*scored)[on_a];
  scored->push_back(twin);
  const SharedClaimPair same = DescribeSharedClaim(*scored, on_a, g + 1, scene.views, samples,
                                                   scene.rig, options.min_conflict_overlap_px);
  EXPECT_EQ(same.sides, 2);
  EXPECT_FALSE(RelaxesConflict(same, options.shared_claims));
}

// Two candidates of view pair (0, 1) sharing segment 0 of view 0 over [0, 100] px (and not
// their segments of view 1): i's four points there lie 10, 20, 30 and 50 mm from j's curve, j's
// two lie 0.5 m from i's. The separation is the median: (20 + 30) / 2 = 25 mm (the median
// of an even count is the mean of the middle two, core/statistics.h). No view outside the pair:
// no support.
TEST(SharedClaims, SeparationIsTheMedianDistanceOverTheSharedStretch) {
  auto candidate = [](int segment_b, const std::vector<Eigen::Vector3d>& points,
                      const std::vector<double>& arcs, double line_y) {
    ScoredCandidate c;
    c.candidate.view_a = 0;
    c.candidate.view_b = 1;
    c.candidate.segment_a = 0;
    c.candidate.segment_b = segment_b;
    c.candidate.begin_a_px = c.candidate.begin_b_px = 0.0;
    c.candidate.end_a_px = c.candidate.end_b_px = 100.0;
    for (double arc : arcs) {
      EpipolarHit hit;
      hit.arc_a_px = arc;
      hit.arc_b_px = arc;
      c.candidate.hits.push_back(hit);
    }
    c.fit.points = points;
    c.fit.control_points = {{0.0, line_y, 0.0}, {1.0, line_y, 0.0}};
    c.probability = 0.5;
    return c;
  };
  const std::vector<ScoredCandidate> candidates = {
      candidate(0, {{0.1, 0.01, 0}, {0.2, 0.02, 0}, {0.3, 0.03, 0}, {0.4, 0.05, 0}},
                {10, 20, 30, 40}, 0.5),
      candidate(1, {{0.1, 0, 0}, {0.5, 0, 0}}, {10, 50}, 0.0)};
  const std::vector<View2D> views(2);
  const SharedClaimPair pair =
      DescribeSharedClaim(candidates, 0, 1, views, {}, RigCalibration{}, 20.0);
  EXPECT_EQ(pair.sides, 1);
  EXPECT_NEAR(pair.separation_m, 0.025, 1e-12);
  EXPECT_DOUBLE_EQ(pair.max_share, 1.0);
  EXPECT_EQ(pair.min_shared_support, 0.0);
}

TEST(SharedClaims, BadOptionsRejectNamingTheField) {
  CorrespondenceOptions options;
  ASSERT_TRUE(options.Validate().ok());
  options.shared_claims.min_separation_m = -0.01;
  EXPECT_NE(options.Validate().message().find("shared_claims.min_separation_m"),
            std::string::npos);
  options = {};
  options.shared_claims.min_other_view_support = NAN;
  EXPECT_NE(options.Validate().message().find("shared_claims.min_other_view_support"),
            std::string::npos);
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  // The fit's bundle reading (polyline_fit.h) is checked with the other options.
  CorrespondenceOptions bundle;
  bundle.fit.bundle_width_ratio = 0.5;
  EXPECT_NE(bundle.Validate().message().find("fit.bundle_width_ratio"), std::string::npos);
  bundle.fit.bundle_width_ratio = 2.0;
  EXPECT_TRUE(bundle.Validate().ok());
  // MatchSegments reports it too.
  const AlongInOneView scene = DrawAlongInOneView();
  const auto pieces = MatchSegments(scene.views, scene.rig, options, Deadline::Infinite());
  EXPECT_EQ(pieces.status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vb::reconstruct
