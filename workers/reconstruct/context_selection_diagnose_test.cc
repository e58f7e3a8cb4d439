// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: what the context-aware selection (context_selection.h) adds on
// rendered stops. Each stop is matched as the pipeline matches it (RenderAndMatch, context off);
// the second pass is then run again with the refined rig and the context selection on
// (MatchSegments; the first pass's pieces above P 0.8, which refine the rig, do not change).
// The pieces the second run has and the first has not are the added ones. Printed per stop and
// summed: pieces and length added; the share of the added length within 10 mm of a cane of the
// vine, and of any drawn cane (vine and neighbours); the same shares for the pieces of the
// normal selection; and the vine's true length within 10 mm of a piece without and with them.
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 [VB_CONTEXT_ALPHA=9] [VB_CONTEXT_GAP_M=0.015]
//   [VB_CONTEXT_MIN_COS=0.9] [VB_CONTEXT_NEW=0.25] [VB_ALPHA=4.5] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='ContextSelection.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

// Points along a polyline every ~5 mm, each with the length it stands for.
struct Sampled {
  std::vector<Eigen::Vector3d> points;
  double step_m = 0.0;
};
Sampled Sample(const std::vector<Eigen::Vector3d>& line) {
  Sampled s;
  s.step_m = 0.005;
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Eigen::Vector3d d = line[k + 1] - line[k];
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / s.step_m)));
    for (int i = 0; i < n; ++i) s.points.push_back(line[k] + d * ((i + 0.5) / n));
  }
  return s;
}
double Length(const std::vector<Eigen::Vector3d>& line) {
  double l = 0.0;
  for (size_t k = 0; k + 1 < line.size(); ++k) l += (line[k + 1] - line[k]).norm();
  return l;
}

struct Shares {
  int pieces = 0;
  double length = 0.0, near_vine = 0.0, near_drawn = 0.0;
  void Add(const Piece3D& piece, const std::vector<Cane>& vine, const std::vector<Cane>& drawn) {
    ++pieces;
    const double length_m = Length(piece.polyline.points);
    length += length_m;
    const Sampled s = Sample(piece.polyline.points);
    if (s.points.empty()) return;
    const double w = length_m / s.points.size();
    for (const Eigen::Vector3d& p : s.points) {
      near_vine += NearAnyCane(p, vine) ? w : 0.0;
      near_drawn += NearAnyCane(p, drawn) ? w : 0.0;
    }
  }
  void Print(const char* name) const {
    std::printf("  %-22s pieces %5d  length %7.2f m  near vine %.3f  near any drawn %.3f\n", name,
                pieces, length, length > 0 ? near_vine / length : 0.0,
                length > 0 ? near_drawn / length : 0.0);
  }
};

// The vine's true length within 10 mm of a piece of `pieces`.
double Covered(const std::vector<Cane>& vine, const std::vector<Piece3D>& pieces, double* total) {
  std::vector<Polyline3> lines;
  for (const Piece3D& p : pieces) lines.push_back(p.polyline);
  double covered = 0.0;
  for (const Cane& cane : vine) {
    const Sampled s = Sample(cane.polyline.points);
    const double w = s.points.empty() ? 0.0 : Length(cane.polyline.points) / s.points.size();
    for (const Eigen::Vector3d& p : s.points) {
      *total += w;
      covered += DistanceToLines(p, lines) <= 0.01 ? w : 0.0;
    }
  }
  return covered;
}

TEST(ContextSelection, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  ReconstructOptions options;
  OverrideFromEnv("VB_ALPHA", &options.correspondence.alpha);
  CorrespondenceOptions on = options.correspondence;
  on.context.enabled = true;
  OverrideFromEnv("VB_CONTEXT_ALPHA", &on.context.alpha);
  OverrideFromEnv("VB_CONTEXT_GAP_M", &on.context.max_gap_m);
  OverrideFromEnv("VB_CONTEXT_MIN_COS", &on.context.min_cos);
  OverrideFromEnv("VB_CONTEXT_NEW", &on.context.min_new_fraction);
  std::printf("alpha %.2f, context alpha %.2f, gap %.3f m, min cos %.2f, new %.2f\n",
              on.alpha, on.context.alpha, on.context.max_gap_m, on.context.min_cos,
              on.context.min_new_fraction);
  Shares kept_total, added_total;
  double true_total = 0.0, covered_off = 0.0, covered_on = 0.0;
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const auto run = RenderAndMatch(seed, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const std::vector<Piece3D>& off = run->matched.pieces;
    const auto with = MatchSegments(run->stop.views, run->matched.rig, on, Deadline::Infinite());
    ASSERT_TRUE(with.ok()) << with.status();
    const std::vector<Cane>& vine = run->stop.scene.vine.canes;
    const std::vector<Cane>& drawn = run->stop.drawn.canes;
    std::set<std::vector<double>> off_keys;
    auto key = [](const Piece3D& p) {
      std::vector<double> v = {double(p.view_a), double(p.segment_a), double(p.view_b),
                               double(p.segment_b)};
      for (const Eigen::Vector3d& x : p.polyline.points) v.insert(v.end(), {x.x(), x.y(), x.z()});
      return v;
    };
    Shares kept, added;
    for (const Piece3D& p : off) {
      off_keys.insert(key(p));
      kept.Add(p, vine, drawn);
    }
    for (const Piece3D& p : *with) {
      if (!off_keys.count(key(p))) added.Add(p, vine, drawn);
    }
    double total = 0.0, unused = 0.0;
    const double c_off = Covered(vine, off, &total);
    const double c_on = Covered(vine, *with, &unused);
    std::printf("seed %llu: kept %d, added %d (%.2f m, near vine %.2f, any %.2f); vine covered "
                "%.3f -> %.3f\n",
                static_cast<unsigned long long>(seed), kept.pieces, added.pieces, added.length,
                added.length > 0 ? added.near_vine / added.length : 0.0,
                added.length > 0 ? added.near_drawn / added.length : 0.0,
                total > 0 ? c_off / total : 0.0, total > 0 ? c_on / total : 0.0);
    kept_total.pieces += kept.pieces;
    kept_total.length += kept.length;
    kept_total.near_vine += kept.near_vine;
    kept_total.near_drawn += kept.near_drawn;
    added_total.pieces += added.pieces;
    added_total.length += added.length;
    added_total.near_vine += added.near_vine;
    added_total.near_drawn += added.near_drawn;
    true_total += total;
    covered_off += c_off;
    covered_on += c_on;
  }
  std::printf("%d stops from %llu:\n", count, static_cast<unsigned long long>(first));
  kept_total.Print("normal selection");
  added_total.Print("added in context");
  std::printf("  vine length within 10 mm of a piece: %.4f -> %.4f (of %.2f m)\n",
              true_total > 0 ? covered_off / true_total : 0.0,
              true_total > 0 ? covered_on / true_total : 0.0, true_total);
}

}  // namespace
}  // namespace vb::reconstruct
