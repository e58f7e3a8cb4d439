// SPDX-License-Identifier: Apache-2.0
// Diagnosis tools, not tests (docs/diagnosis.md): correspondence alone on one stop
// (MatchSegments.DISABLED_Diagnose) and the raw pieces' bench metrics against the final model's
// (MatchSegments.DISABLED_PipelineLoss). Run with --gtest_also_run_disabled_tests and the test's
// name as the filter. Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/gibbs.h"
#include "workers/reconstruct/match_segments_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

TEST(MatchSegments, DISABLED_Diagnose) {
  const char* env = std::getenv("VB_SEED");
  const uint64_t seed = env ? std::atoi(env) : 1500;
  // VB_INPUT: synthetic (default), labels or images (MakeRenderedStop).
  const char* input_env = std::getenv("VB_INPUT");
  const std::string input = input_env ? input_env : "synthetic";
  const SimulatedStop stop =
      input == "synthetic" ? MakeSimulatedStop(seed) : MakeRenderedStop(seed, input == "images");
  std::vector<const Polyline3*> truth;
  for (const Cane& cane : stop.drawn.canes) truth.push_back(&cane.polyline);
  const auto scored = ScoreCandidates(stop.views, stop.rig, {}, Deadline::Infinite()).value();
  auto as_pieces = [&](auto pred) {
    std::vector<Piece3D> out;
    for (const ScoredCandidate& c : scored) {
      if (!pred(c)) continue;
      Piece3D p;
      p.polyline.points = c.fit.control_points;
      p.polyline.radii = c.fit.radii;
      out.push_back(p);
    }
    return out;
  };
  auto report = [&](const char* name, const std::vector<Piece3D>& pieces) {
    const Metrics m = Evaluate(pieces, stop.scene.vine, stop.drawn, stop.true_rig);
    std::printf("%-12s %4zu pieces coverage %.3f precision %.3f\n", name, pieces.size(), m.coverage, m.precision);
  };
  report("all", as_pieces([](const ScoredCandidate&) { return true; }));
  report("right", as_pieces([&](const ScoredCandidate& c) { return IsRightMatch(c.fit.points, truth); }));
  report("p>0.5", as_pieces([](const ScoredCandidate& c) { return c.probability > 0.5; }));
  report("p>0.2", as_pieces([](const ScoredCandidate& c) { return c.probability > 0.2; }));
  report("selected", MatchSegments(stop.views, stop.rig, {}, Deadline::Infinite()).value());
  {
    std::vector<double> probs;
    std::vector<bool> right;
    for (const ScoredCandidate& c : scored) { probs.push_back(c.probability); right.push_back(IsRightMatch(c.fit.points, truth)); }
    const auto conflicts = CandidateConflicts(scored, 8.0);
    const auto marg = GibbsMarginals(probs, conflicts, {});
    int shown = 0;
    for (size_t i = 0; i < scored.size() && shown < 12; ++i) {
      if (!right[i] || probs[i] < 0.5 || marg[i] >= 0.5) continue;
      ++shown;
      const auto& c = scored[i].candidate;
      std::printf("right %zu (v%d s%d v%d t%d [%.0f,%.0f] [%.0f,%.0f]) p %.2f m %.2f; conflicts:", i, c.view_a, c.segment_a, c.view_b, c.segment_b, c.begin_a_px, c.end_a_px, c.begin_b_px, c.end_b_px, probs[i], marg[i]);
      for (int j : conflicts[i]) {
        const auto& d = scored[j].candidate;
        std::printf(" [%d %s p%.2f m%.2f s%d t%d a[%.0f,%.0f] b[%.0f,%.0f]]", j, right[j] ? "R" : "w", probs[j], marg[j], d.segment_a, d.segment_b, d.begin_a_px, d.end_a_px, d.begin_b_px, d.end_b_px);
      }
      std::printf("\n");
    }
  }
  // Per view pair: right candidates.
  for (int a = 0; a < 3; ++a) for (int b = a + 1; b < 3; ++b) {
    int n = 0, r = 0;
    for (const ScoredCandidate& c : scored) {
      if (c.candidate.view_a != a || c.candidate.view_b != b) continue;
      ++n;
      r += IsRightMatch(c.fit.points, truth);
    }
    std::printf("pair %d%d: %d candidates, %d right\n", a, b, n, r);
  }
}

// Where the whole pipeline's cane recall and precision are lost on rendered stops (VB_INPUT
// labels or images; VB_SEED first seed, VB_STOPS count): the bench metrics of the raw pieces
// of MatchSegments (each as a cane) against those of ReconstructFromViews.
TEST(MatchSegments, DISABLED_PipelineLoss) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1100, 8);
  ReconstructOptions options;
  OverrideFromEnv("VB_ALPHA", &options.correspondence.alpha);
  double sums[4] = {0, 0, 0, 0};
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images);
    ASSERT_FALSE(stop.views.empty());
    const auto pieces =
        MatchSegments(stop.views, stop.rig, options.correspondence, Deadline::Infinite());
    ASSERT_TRUE(pieces.ok()) << pieces.status();
    std::vector<Polyline3> lines;
    for (const Piece3D& piece : *pieces) lines.push_back(piece.polyline);
    const auto raw_m = EvaluateReconstruction(Flat(lines), stop.scene.vine);
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const auto full_m = EvaluateReconstruction(result->model, stop.scene.vine);
    ASSERT_TRUE(raw_m.ok()) << raw_m.status();
    ASSERT_TRUE(full_m.ok()) << full_m.status();
    std::printf("seed %llu: pieces %zu recall %.3f precision %.3f | model recall %.3f precision "
                "%.3f\n", static_cast<unsigned long long>(first + k), pieces->size(),
                raw_m->cane_recall, raw_m->cane_precision, full_m->cane_recall,
                full_m->cane_precision);
    sums[0] += raw_m->cane_recall / count;
    sums[1] += raw_m->cane_precision / count;
    sums[2] += full_m->cane_recall / count;
    sums[3] += full_m->cane_precision / count;
  }
  std::printf("mean: pieces recall %.3f precision %.3f | model recall %.3f precision %.3f\n",
              sums[0], sums[1], sums[2], sums[3]);
}

}  // namespace
}  // namespace vb::reconstruct
