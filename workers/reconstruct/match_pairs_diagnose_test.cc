// SPDX-License-Identifier: Apache-2.0
// Diagnosis tools, not tests, beside match_loss_diagnose_test.cc (same stops and knobs): why right
// candidates score below the selection threshold (DISABLED_LowScores), and the "no raw candidate"
// row by view pair (DISABLED_RawCandidatePairs). Run with
//   VB_INPUT=labels|images VB_SEED=1300 VB_STOPS=10 [VB_FIDUCIALS=0] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='MatchLoss.DISABLED_LowScores'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

// Why right candidates score below the selection threshold: every fitted candidate of the
// pipeline's second pass (refined rig), labelled as the classifier's training labels them
// (IsRightMatch against the drawn canes); for right ones below and above 1 / (1 + alpha), the
// mean of each feature and its mean contribution w_i * f_i to the logit. Run as the report above
// (VB_SEED, VB_STOPS, VB_INPUT, VB_FIDUCIALS) with --gtest_filter='MatchLoss.DISABLED_LowScores'.
TEST(MatchLoss, DISABLED_LowScores) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 4);
  const ReconstructOptions options;
  const double threshold = 1.0 / (1.0 + options.correspondence.alpha);
  // [0]: right, below threshold; [1]: right, above; [2]: wrong, above.
  double n[3] = {}, length[3] = {};
  MatchFeatures sum[3]{}, contribution[3]{};
  for (int k = 0; k < count; ++k) {
    const auto run = RenderAndMatch(first + k, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const auto scored = ScoreCandidates(run->stop.views, run->matched.rig, options.correspondence,
                                        Deadline::Infinite());
    ASSERT_TRUE(scored.ok());
    std::vector<const Polyline3*> truth;
    for (const Cane& cane : run->stop.drawn.canes) truth.push_back(&cane.polyline);
    for (const ScoredCandidate& s : *scored) {
      const bool right = IsRightMatch(s.fit.points, truth);
      const bool above = s.probability > threshold;
      if (!right && !above) continue;
      const int group = right ? (above ? 1 : 0) : 2;
      const MatchFeatures& w =
          s.multi_view ? options.correspondence.classifier.multi_view
                       : options.correspondence.classifier.two_view;
      n[group] += 1;
      length[group] += s.fit.length_m;
      for (int i = 0; i < kMatchFeatureCount; ++i) {
        sum[group][i] += s.features[i];
        contribution[group][i] += w[i] * s.features[i];
      }
    }
  }
  std::printf("candidates: right below threshold %.0f (%.1f m), right above %.0f (%.1f m), "
              "wrong above %.0f (%.1f m)\n", n[0], length[0], n[1], length[1], n[2], length[2]);
  std::printf("feature  mean(right<)  mean(right>)  mean(wrong>)   w.f(right<)  w.f(right>)  "
              "w.f(wrong>)\n");
  for (int i = 0; i < kMatchFeatureCount; ++i) {
    std::printf("%7d %13.3f %13.3f %13.3f %13.3f %12.3f %12.3f\n", i, sum[0][i] / n[0],
                sum[1][i] / n[1], sum[2][i] / n[2], contribution[0][i] / n[0],
                contribution[1][i] / n[1], contribution[2][i] / n[2]);
  }
}

// The "no raw candidate" row by view pair (DISABLED_RawCandidates classes why a run is missing;
// this classes which pairs could have given one): for each true sample with skeleton in two or
// more views and no raw candidate within 10 mm, over the pairs whose skeleton segments lie on it,
//   how many views have skeleton on it (a third view that sees it, or not);
//   the best-conditioned such pair (largest |sin| of the cane's angle to that pair's epipolar
//   line in view a, true geometry), its cameras and that |sin|;
//   the nearest hit of that pair's two segments (every run, min_hits 1): distance, and how much
//   of it is depth along view a's ray (|offset . ray| / |offset|);
//   the sample within 12 px of an end of its segment in some view (a junction, a gap), and the
//   same share over all samples with skeleton in two or more views;
//   a selected piece (MatchWithRigRefinement, refined) within 10 mm or 10-20 mm anyway.
// Run as the report above with --gtest_filter='MatchLoss.DISABLED_RawCandidatePairs'.
TEST(MatchLoss, DISABLED_RawCandidatePairs) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 4);
  const ReconstructOptions options;
  double total = 0, lost = 0;
  double by_views[4] = {};
  std::map<std::string, double> by_pair_sin, by_nearest, by_depth_share;
  double near_end = 0, near_end_all = 0, skel2_all = 0;
  double piece_near[3] = {};
  // Samples with skeleton in 3 views: the worst-conditioned pair (the one that does not share a
  // view a crossing or junction may have bent), its |sin| and its nearest hit.
  std::map<std::string, double> worst_pair;  // a selected piece within 10 mm, 10-20 mm, neither
  auto sin_bucket = [](double s) {
    return s < 0.2 ? "<0.2" : s < 0.4 ? "0.2-0.4" : s < 0.7 ? "0.4-0.7" : ">=0.7";
  };
  for (int k = 0; k < count; ++k) {
    const auto run = RenderAndMatch(first + k, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const SimulatedStop& stop = run->stop;
    const int n = static_cast<int>(stop.views.size());
    const std::vector<View2D>& views = run->views();
    const RigCalibration& rig = run->matched.rig;
    // As the second pass searches each pair (a view outside it shows anything in a 3-camera rig).
    const CandidateOptions co = CandidateOptionsFor(options.correspondence, n > 2);
    using PairKey = std::tuple<int, int, int, int>;
    std::map<PairKey, std::vector<Eigen::Vector3d>> runs;
    PointGrid grid, piece10;
    for (const Piece3D& piece : run->matched.pieces) {
      piece10.AddLine(piece.polyline.points, 1.0);
    }
    const std::vector<ViewSamples> samples =
        SampleViews(views, rig, options.correspondence.sample_step_px);
    CandidateOptions all_runs = co;
    all_runs.min_hits = 1;
    for (const MatchCandidate& c : RawCandidates(samples, rig, all_runs)) {
      const std::vector<Eigen::Vector3d> pts = HitPoints(c);
      if (static_cast<int>(c.hits.size()) >= co.min_hits) grid.AddLine(pts, 1.0);
      auto& list = runs[{c.view_a, c.segment_a, c.view_b, c.segment_b}];
      list.insert(list.end(), pts.begin(), pts.end());
    }
    const SegmentMaps maps(views);
    for (const Cane& cane : stop.scene.vine.canes) {
      if (cane.kind == CaneKind::kSpur) continue;
      const std::vector<Eigen::Vector3d> pts = cane.polyline.Sample(0.005);
      for (size_t i = 0; i < pts.size(); ++i) {
        const Eigen::Vector3d& p = pts[i];
        const Eigen::Vector3d t = TangentAt(pts, i);
        const SampleInViews at = LocateSample(p, stop.true_rig, views, maps);
        const std::vector<int>& seg = at.segment;
        const std::vector<Eigen::Vector2d>& px = at.px;
        const int skel = at.skeleton;
        total += 1;
        bool end_near = false;
        for (int v = 0; v < n && skel >= 2; ++v) {
          if (seg[v] < 0) continue;
          const auto& sp = views[v].segments[seg[v]].points;
          end_near = end_near || (sp.front() - px[v]).norm() < 12.0 ||
                     (sp.back() - px[v]).norm() < 12.0;
        }
        if (skel >= 2) skel2_all += 1, near_end_all += end_near;
        if (skel < 2 || grid.MaxNear(p) >= 0) continue;
        lost += 1;
        near_end += end_near;
        piece_near[piece10.MaxNear(p) >= 0 ? 0 : piece10.MaxNear(p, 0.02) >= 0 ? 1 : 2] += 1;
        by_views[std::min(skel, 3)] += 1;
        int best_a = -1, best_b = -1, worst_a = -1, worst_b = -1;
        double best_sin = -1, worst_sin = 2;
        for (int a = 0; a < n; ++a)
          for (int b = a + 1; b < n; ++b) {
            if (seg[a] < 0 || seg[b] < 0) continue;
            const std::optional<double> s = EpipolarSin(stop.true_rig, a, b, p, t, px[a]);
            if (!s) continue;
            const double sin = *s;
            if (sin > best_sin) best_sin = sin, best_a = a, best_b = b;
            if (sin < worst_sin) worst_sin = sin, worst_a = a, worst_b = b;
          }
        if (best_a < 0) continue;
        if (skel >= 3 && worst_a >= 0) {
          double nearest_worst = INFINITY;
          const auto w = runs.find({worst_a, seg[worst_a], worst_b, seg[worst_b]});
          if (w != runs.end())
            for (const Eigen::Vector3d& q : w->second)
              nearest_worst = std::min(nearest_worst, (q - p).norm());
          worst_pair[absl::StrCat("|sin| ", sin_bucket(worst_sin), ", nearest hit ",
                                  nearest_worst <= 0.01   ? "<=10 mm"
                                  : nearest_worst <= 0.02 ? "10-20 mm"
                                  : std::isfinite(nearest_worst) ? ">20 mm"
                                                                 : "none")] += 1;
        }
        by_pair_sin[absl::StrCat("pair ", best_a, "-", best_b, " |sin| ", sin_bucket(best_sin),
                                 skel >= 3 ? ", 3 views" : ", 2 views")] += 1;
        double nearest = INFINITY;
        Eigen::Vector3d offset = Eigen::Vector3d::Zero();
        const auto it = runs.find({best_a, seg[best_a], best_b, seg[best_b]});
        if (it != runs.end())
          for (const Eigen::Vector3d& q : it->second)
            if ((q - p).norm() < nearest) nearest = (q - p).norm(), offset = q - p;
        const char* bucket = nearest <= 0.01   ? "<=10 mm (short runs only)"
                             : nearest <= 0.02 ? "10-20 mm"
                             : nearest <= 0.05 ? "20-50 mm"
                             : std::isfinite(nearest) ? ">50 mm"
                                                      : "no hit";
        by_nearest[absl::StrCat(bucket, ", |sin| ", sin_bucket(best_sin))] += 1;
        if (nearest > 0.01 && nearest <= 0.05) {
          const Eigen::Vector3d ray =
              (p - stop.true_rig.cameras[best_a].CentreInPlatform()).normalized();
          const double share = std::abs(offset.dot(ray)) / offset.norm();
          by_depth_share[share >= 0.9 ? "depth >= 0.9 of the offset"
                                      : share >= 0.5 ? "depth 0.5-0.9" : "depth < 0.5"] += 1;
        }
      }
    }
    std::printf("seed %llu: lost at raw %.3f\n", static_cast<unsigned long long>(first + k),
                lost / total);
  }
  std::printf("no raw candidate (skeleton in >= 2 views): %.3f of true length, %d stops\n",
              lost / total, count);
  std::printf("  skeleton in 2 views %.3f, in 3 %.3f; within 12 px of a segment end %.3f\n",
              by_views[2] / total, by_views[3] / total, near_end / total);
  std::printf("  of all samples with skeleton in >= 2 views (%.3f), within 12 px of a segment end "
              "%.3f\n", skel2_all / total, near_end_all / total);
  std::printf("  a selected piece (refined) within 10 mm anyway %.4f, 10-20 mm %.4f, neither %.4f\n",
              piece_near[0] / total, piece_near[1] / total, piece_near[2] / total);
  std::printf("  best-conditioned pair (cameras, |sin| to its epipolar line in view a):\n");
  for (const auto& [key, v] : by_pair_sin) std::printf("    %-40s %.4f\n", key.c_str(), v / total);
  std::printf("  skeleton in 3 views: the worst-conditioned pair, its |sin| and nearest hit:\n");
  for (const auto& [key, v] : worst_pair) std::printf("    %-40s %.4f\n", key.c_str(), v / total);
  std::printf("  that pair's nearest hit (any run):\n");
  for (const auto& [key, v] : by_nearest) std::printf("    %-40s %.4f\n", key.c_str(), v / total);
  std::printf("  of nearest 10-50 mm, the share of the offset along view a's ray:\n");
  for (const auto& [key, v] : by_depth_share)
    std::printf("    %-40s %.4f\n", key.c_str(), v / total);
}

}  // namespace
}  // namespace vb::reconstruct
