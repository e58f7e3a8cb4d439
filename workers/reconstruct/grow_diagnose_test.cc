// SPDX-License-Identifier: Apache-2.0
// Diagnosis tool, not a test: what the two-view growth of cane ends (grow.h) adds on rendered
// stops (VB_SEED, VB_STOPS, VB_INPUT as ReportStopsFromEnv; images by default). Run with
// --gtest_also_run_disabled_tests --gtest_filter='Grow.DISABLED_Report'. Tuning seeds only
// (1100-1999).

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/cane_assembly.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

double DistanceToCanes(const Eigen::Vector3d& p, const std::vector<Cane>& canes) {
  double best = 1e9;
  for (const Cane& c : canes) {
    const std::vector<Eigen::Vector3d>& q = c.polyline.points;
    for (size_t i = 0; i + 1 < q.size(); ++i) {
      double t = 0;
      best = std::min(best, PointSegmentDistance(p, q[i], q[i + 1], &t));
    }
  }
  return best;
}

double MeanSe(const std::vector<double>& v, double* se) {
  double mean = 0;
  for (double x : v) mean += x;
  mean /= std::max<size_t>(1, v.size());
  double var = 0;
  for (double x : v) var += (x - mean) * (x - mean);
  *se = v.size() > 1 ? std::sqrt(var / (v.size() - 1) / v.size()) : 0.0;
  return mean;
}

GrowOptions OptionsFromEnv() {
  GrowOptions o;
  const auto get = [](const char* name, double* field) {
    if (const char* text = std::getenv(name)) *field = std::atof(text);
  };
  get("VB_GROW_SUPPORT_PX", &o.support_px);
  get("VB_GROW_LEN", &o.max_length_m);
  get("VB_GROW_EPI", &o.min_epipolar_angle_deg);
  get("VB_GROW_TURN", &o.max_turn_deg);
  get("VB_GROW_OTHER", &o.other_cane_m);
  get("VB_GROW_PRIOR", &o.prior_px_per_mm);
  get("VB_GROW_OFFSET", &o.max_offset_m);
  get("VB_GROW_MIN_LEN", &o.min_length_m);
  get("VB_GROW_MIN_CANE", &o.min_cane_length_m);
  if (const char* v = std::getenv("VB_GROW_VIEWS")) o.min_support_views = std::atoi(v);
  if (const char* v = std::getenv("VB_GROW_END")) o.require_end_support = std::atoi(v) != 0;
  return o;
}

// Per stop: the assembled canes (as the pipeline gives them to step 4d), grown with the options
// from the environment: the added length and its share within 10 mm of drawn wood (this vine's
// or a neighbour's: connect sorts them; the metrics' tolerance), split by whether the end it grows from is itself within 10 mm; then the
// whole pipeline with and without the stage: recall, precision and connectivity, their paired
// change (mean +- standard error over stops), and the stage's time.
TEST(Grow, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10, true);
  const GrowOptions grow = OptionsFromEnv();
  ASSERT_TRUE(grow.Validate().ok());
  ReconstructOptions off;
  off.grow.enabled = false;
  ReconstructOptions on;
  on.grow = grow;
  on.grow.enabled = true;
  double wrong_near_head = 0, wrong_10_20 = 0;
  double added = 0, right = 0, added_from_wrong_end = 0, right_from_wrong_end = 0, time = 0;
  int ends = 0, grown_ends = 0;
  GrowSummary totals;
  std::vector<double> d_recall, d_precision, d_connectivity;
  double recall0 = 0, precision0 = 0, connectivity0 = 0;
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const VineModel& truth = stop.scene.vine;
    // Growth is right where it follows wood, this vine's or a neighbour's (connect sorts them).
    const VineModel& drawn = stop.drawn;
    const auto matched = MatchWithRigRefinement(stop.views, stop.rig, off, Deadline::Infinite());
    ASSERT_TRUE(matched.ok()) << matched.status();
    auto canes = AssembleCanes(matched->pieces, off.assembly, Deadline::Infinite());
    ASSERT_TRUE(canes.ok());
    std::erase_if(*canes, [&](const Polyline3& c) { return off.volume.MostlyOutside(c); });
    std::vector<Polyline3> grown = *canes;
    GrowSummary summary;
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(GrowCaneEnds(stop.views, matched->rig, off.volume, on.grow, &grown, &summary).ok());
    time += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ends += summary.ends_tried;
    grown_ends += summary.ends_grown;
    totals.contradicted += summary.contradicted;
    totals.unsupported += summary.unsupported;
    totals.end_unsupported += summary.end_unsupported;
    totals.alongside += summary.alongside;
    totals.thick += summary.thick;
    totals.turned += summary.turned;
    totals.outside += summary.outside;
    totals.capped += summary.capped;
    const double added_before = added, right_before = right;
    for (size_t c = 0; c < grown.size(); ++c) {
      const Polyline3& before = (*canes)[c];
      const Polyline3& after = grown[c];
      // The original points are kept as a contiguous run; what lies outside it was added.
      size_t offset = 0;
      while (offset < after.points.size() && after.points[offset] != before.points.front())
        ++offset;
      ASSERT_LT(offset, after.points.size());
      for (int side = 0; side < 2; ++side) {
        const size_t lo = side == 0 ? 0 : offset + before.points.size() - 1;
        const size_t hi = side == 0 ? offset : after.points.size() - 1;
        if (hi <= lo) continue;
        const Eigen::Vector3d& end = side == 0 ? before.points.front() : before.points.back();
        const bool end_right = DistanceToCanes(end, drawn.canes) <= 0.010;
        for (size_t i = lo; i < hi; ++i) {
          const double step = (after.points[i + 1] - after.points[i]).norm();
          const Eigen::Vector3d mid = 0.5 * (after.points[i + 1] + after.points[i]);
          const bool ok = DistanceToCanes(mid, drawn.canes) <= 0.010;
          added += step;
          right += ok * step;
          if (!ok) {
            double head = 1e9;
            for (const Sphere& sp : drawn.head.spheres)
              head = std::min(head, (mid - sp.center).norm() - sp.radius);
            const double d = DistanceToCanes(mid, drawn.canes);
            wrong_near_head += (head < 0.03) * step;
            wrong_10_20 += (d < 0.02) * step;
          }
          if (!end_right) {
            added_from_wrong_end += step;
            right_from_wrong_end += ok * step;
          }
        }
      }
    }
    if (std::getenv("VB_GROW_QUICK") != nullptr) {
      std::printf("stop %llu: added %.3f m (right %.2f)\n", static_cast<unsigned long long>(first + k),
                  added - added_before,
                  (right - right_before) / std::max(added - added_before, 1e-9));
      d_recall.push_back(0);
      d_precision.push_back(0);
      d_connectivity.push_back(0);
      continue;
    }
    const auto a = ReconstructFromViews(stop.views, stop.rig, off, Deadline::Infinite());
    const auto b = ReconstructFromViews(stop.views, stop.rig, on, Deadline::Infinite());
    ASSERT_TRUE(a.ok() && b.ok());
    const auto ma = EvaluateReconstruction(a->model, truth);
    const auto mb = EvaluateReconstruction(b->model, truth);
    ASSERT_TRUE(ma.ok() && mb.ok());
    recall0 += ma->cane_recall;
    precision0 += ma->cane_precision;
    connectivity0 += ma->connectivity;
    d_recall.push_back(mb->cane_recall - ma->cane_recall);
    d_precision.push_back(mb->cane_precision - ma->cane_precision);
    d_connectivity.push_back(mb->connectivity - ma->connectivity);
    std::printf("stop %llu: added %.3f m (right %.2f), recall %+.4f precision %+.4f "
                "connectivity %+.4f\n",
                static_cast<unsigned long long>(first + k), added - added_before,
                (right - right_before) / std::max(added - added_before, 1e-9), d_recall.back(), d_precision.back(), d_connectivity.back());
  }
  double se_r = 0, se_p = 0, se_c = 0;
  const double dr = MeanSe(d_recall, &se_r), dp = MeanSe(d_precision, &se_p),
               dc = MeanSe(d_connectivity, &se_c);
  std::printf("stops %llu-%llu (%s): ends %d grown %d; end unsupported %d; stopped: unsupported %d contradicted %d "
              "alongside %d thick %d turned %d outside %d capped %d\n",
              static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), images ? "images" : "views",
              ends, grown_ends, totals.end_unsupported, totals.unsupported, totals.contradicted, totals.alongside,
              totals.thick, totals.turned, totals.outside, totals.capped);
  std::printf("added %.3f m per stop, right %.3f; from ends already > 10 mm off: %.3f m per stop, "
              "right %.3f; stage %.4f s per stop\n",
              added / count, right / std::max(added, 1e-9), added_from_wrong_end / count,
              right_from_wrong_end / std::max(added_from_wrong_end, 1e-9), time / count);
  std::printf("wrong within 3 cm of the head %.3f m per stop, 10-20 mm from wood %.3f m per stop\n",
              wrong_near_head / count, wrong_10_20 / count);
  std::printf("without: recall %.4f precision %.4f connectivity %.4f\n", recall0 / count,
              precision0 / count, connectivity0 / count);
  std::printf("with - without: recall %+.4f +- %.4f, precision %+.4f +- %.4f, connectivity "
              "%+.4f +- %.4f\n",
              dr, se_r, dp, se_p, dc, se_c);
}

}  // namespace
}  // namespace vb::reconstruct
