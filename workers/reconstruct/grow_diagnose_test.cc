// SPDX-License-Identifier: Apache-2.0
// Diagnosis tool, not a test: what the two-view growth of cane ends (grow.h) adds on rendered
// stops (VB_SEED, VB_STOPS, VB_INPUT as ReportStopsFromEnv; images by default). Run with
// --gtest_also_run_disabled_tests --gtest_filter='Grow.DISABLED_Report'. Tuning seeds only
// (1100-1999). VB_GROW_WHY=1 adds why unsupported ends failed (WhyUnsupported), VB_GROW_BAND=1
// turns on support in bundles (GrowOptions::band_support), VB_GROW_DRIFT=1 adds how far the grown
// points lie off their true cane (DriftTally, grow_drift_diagnose.h), VB_GROW_REFIT=M refits the
// grown stretch (GrowOptions::refit_span_m; VB_GROW_REFIT_END, _SMOOTH, _PX, _ANCHOR).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/cane_assembly.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/grow_drift_diagnose.h"
#include "workers/reconstruct/grow_internal.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

double MeanSe(const std::vector<double>& v, double* se) {
  double mean = 0;
  for (double x : v) mean += x;
  mean /= std::max<size_t>(1, v.size());
  double var = 0;
  for (double x : v) var += (x - mean) * (x - mean);
  *se = v.size() > 1 ? std::sqrt(var / (v.size() - 1) / v.size()) : 0.0;
  return mean;
}

// The ends whose growth stopped alongside another cane, against the truth: whether the end and
// the other cane lie on the vine's canes, on the same true cane (the other cane continues this
// one) or another, how far apart those two true canes are, and the end's own true cane's length
// beyond the stop (up to 15 cm) that no grown cane recalls: what growth alongside could win.
// The same length for every end on its vine's canes, by why its growth stopped.
struct AlongsideTally {
  int ends = 0, end_off = 0, other_off = 0, same = 0, different = 0;
  double lost_same = 0, lost_different = 0;   // m beyond the stop, not recalled
  int gap[4] = {};                            // different: true canes < 10, 10-20, 20-40, 40+ mm
  double lost_by_gap[4] = {};
  // Every end on its vine's canes, by why growth stopped (GrowStop order): ends, and the own
  // true cane's length beyond the stop that no grown cane recalls.
  int by_stop[8] = {};
  double lost_by_stop[8] = {};

  void Print(int count) const {
    std::printf("stopped alongside: %d ends; end > 10 mm off its vine's canes %d; other cane off "
                "%d; other on the end's own true cane %d (lost beyond %.3f m per stop), on "
                "another %d (lost beyond %.3f m per stop)\n",
                ends, end_off, other_off, same, lost_same / count, different,
                lost_different / count);
    std::printf("  another true cane, 3D gap < 10 / 10-20 / 20-40 / 40+ mm: %d (%.3f) %d (%.3f) "
                "%d (%.3f) %d (%.3f) ends (lost m per stop)\n",
                gap[0], lost_by_gap[0] / count, gap[1], lost_by_gap[1] / count, gap[2],
                lost_by_gap[2] / count, gap[3], lost_by_gap[3] / count);
    const char* names[8] = {"end unsupported", "unsupported", "contradicted", "alongside",
                            "thick", "turned", "outside", "capped"};
    std::printf("ends on the vine's canes by why growth stopped: ends (own cane's length beyond, "
                "unrecalled, m per stop):");
    for (int i = 0; i < 8; ++i)
      std::printf(" %s %d (%.3f);", names[i], by_stop[i], lost_by_stop[i] / count);
    std::printf("\n");
  }
};

int NearestCane(const Eigen::Vector3d& p, const std::vector<Cane>& canes, double* distance) {
  int best = -1;
  *distance = 1e9;
  for (size_t i = 0; i < canes.size(); ++i) {
    double d = 0;
    canes[i].polyline.Project(p, &d);
    if (d < *distance) {
      *distance = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

void AlongsideEnds(const VineModel& truth, const std::vector<Polyline3>& grown,
                   const GrowSummary& summary, AlongsideTally* tally) {
  std::vector<Cane> model;
  for (const Polyline3& line : grown) {
    Cane cane;
    cane.polyline = line;
    model.push_back(cane);
  }
  for (const GrowEnd& end : summary.ends) {
    const Polyline3& line = grown[end.cane];
    if (line.points.size() < 2) continue;
    const bool alongside = end.stop == GrowStop::kAlongside && end.other_cane >= 0;
    tally->ends += alongside;
    double d_end = 0, d_other = 0;
    const int own = NearestCane(end.stop_point, truth.canes, &d_end);
    if (own < 0 || d_end > 0.010) {
      tally->end_off += alongside;
      continue;
    }
    int other_true = -1;
    if (alongside) {
      const Polyline3& other = grown[end.other_cane];
      double d = 0;
      const Eigen::Vector3d on_other = other.PointAt(other.Project(end.stop_point, &d));
      other_true = NearestCane(on_other, truth.canes, &d_other);
      if (other_true < 0 || d_other > 0.010) {
        ++tally->other_off;
        continue;
      }
    }
    // The end's direction: from the cane's point 3 cm back to its end.
    const double length = line.Length();
    const Eigen::Vector3d tip = end.side == 0 ? line.points.back() : line.points.front();
    const Eigen::Vector3d back = line.PointAt(end.side == 0 ? std::max(0.0, length - 0.03)
                                                            : std::min(length, 0.03));
    const Eigen::Vector3d dir = (tip - back).normalized();
    const Polyline3& true_line = truth.canes[own].polyline;
    const double s0 = true_line.Project(end.stop_point);
    const double sign = true_line.TangentAt(s0).dot(dir) >= 0 ? 1.0 : -1.0;
    double lost = 0;
    for (double u = 0.0025; u <= 0.15; u += 0.005) {
      const double s = s0 + sign * u;
      if (s < 0 || s > true_line.Length()) break;
      if (DistanceToCanes(true_line.PointAt(s), model) > 0.010) lost += 0.005;
    }
    ++tally->by_stop[static_cast<int>(end.stop)];
    tally->lost_by_stop[static_cast<int>(end.stop)] += lost;
    if (!alongside) continue;
    if (other_true == own) {
      ++tally->same;
      tally->lost_same += lost;
    } else {
      ++tally->different;
      tally->lost_different += lost;
      double gap = 0;
      truth.canes[other_true].polyline.Project(true_line.PointAt(s0), &gap);
      const int b = gap < 0.01 ? 0 : gap < 0.02 ? 1 : gap < 0.04 ? 2 : 3;
      ++tally->gap[b];
      tally->lost_by_gap[b] += lost;
    }
  }
}

// VB_GROW_WHY=1: why the ends on the vine's canes that stopped unsupported (the end itself, or
// a step) failed the views' test. Per end: the stop point P (the end, or the rejected step) and
// the nearest point Q of its own true cane (within 10 mm of P). Per view that sees P: P's and Q's
// distance to the skeleton, the wood's half-width at Q (Q's skeleton distance plus its distance
// to the background: the band the skeleton runs in), Q's own projected radius, whether the band
// is a bundle (half-width > own radius + band_margin_px) and whether Q's cross-section then fits
// inside the wood (within band_tolerance_px: what band_support accepts; ViewProbe::BandExcess).
struct WhyTally {
  // [0] end unsupported, [1] unsupported.
  int ends[2] = {}, views[2] = {};
  int p_far[2] = {};                 // views with P > 2 px off the skeleton
  int q_bins[2][4] = {};             // views by Q's distance: <= 2, 2-4, 4-6, > 6 px
  int q_far_bundle[2] = {}, q_far_fits[2] = {};  // of the views with Q > 2 px
  int q_near_bundle[2] = {};         // of the views with Q <= 2 px: in a bundle
  double pq_mm[2] = {}, hw_minus_r[2] = {};      // sums: |P - Q|; over Q > 2 px views
  int q_old_pass[2] = {}, q_band_pass[2] = {};   // ends: Q would pass the old / band rule
  int p_two_near[2] = {};  // ends with 2+ views holding P within support_px
  std::vector<double> q_far_d[2];

  void Print() const {
    const char* names[2] = {"end unsupported", "unsupported (a step)"};
    for (int k = 0; k < 2; ++k) {
      const int far = q_bins[k][1] + q_bins[k][2] + q_bins[k][3];
      std::vector<double> d = q_far_d[k];
      std::sort(d.begin(), d.end());
      std::printf("WHY %s: %d ends, |P-Q| mean %.1f mm, %d views seeing P; P > 2 px in %d; Q "
                  "<= 2 / 2-4 / 4-6 / > 6 px: %d %d %d %d; of Q > 2 px: bundle %d, fits the "
                  "wood %d, half-width - own radius mean %.1f px, median distance %.1f px; of "
                  "Q <= 2 px in a bundle %d; ends where Q passes the old rule %d, the band rule "
                  "%d; ends with P within 2 px in 2+ views %d\n",
                  names[k], ends[k], pq_mm[k] / std::max(1, ends[k]), views[k], p_far[k],
                  q_bins[k][0], q_bins[k][1], q_bins[k][2], q_bins[k][3], q_far_bundle[k],
                  q_far_fits[k], hw_minus_r[k] / std::max(1, far),
                  d.empty() ? 0.0 : d[d.size() / 2], q_near_bundle[k], q_old_pass[k],
                  q_band_pass[k], p_two_near[k]);
    }
  }
};

void WhyUnsupported(const VineModel& truth, const std::vector<View2D>& views,
                    const RigCalibration& rig, const GrowOptions& options,
                    const GrowSummary& summary, WhyTally* tally) {
  std::vector<std::vector<float>> wood;
  for (const View2D& view : views) wood.push_back(grow_internal::WoodRadiusMap(view));
  std::vector<grow_internal::ViewProbe> probes;
  for (size_t v = 0; v < views.size(); ++v)
    probes.emplace_back(views[v], rig.cameras[v], options.image_margin_px, &wood[v]);
  for (const GrowEnd& end : summary.ends) {
    if (end.stop != GrowStop::kEndUnsupported && end.stop != GrowStop::kUnsupported) continue;
    const int k = end.stop == GrowStop::kEndUnsupported ? 0 : 1;
    double d_end = 0;
    const int own = NearestCane(end.stop_point, truth.canes, &d_end);
    if (own < 0 || d_end > 0.010) continue;
    const Polyline3& true_line = truth.canes[own].polyline;
    const double s = true_line.Project(end.stop_point);
    const Eigen::Vector3d q = true_line.PointAt(s);
    const double radius = true_line.RadiusAt(s);
    ++tally->ends[k];
    tally->pq_mm[k] += 1000 * (q - end.stop_point).norm();
    int seeing = 0, old_ok = 0, band_ok = 0, p_near = 0;
    for (const grow_internal::ViewProbe& probe : probes) {
      const auto uv_p = probe.Inside(end.stop_point);
      const auto uv_q = probe.Inside(q);
      if (!uv_p || !uv_q) continue;
      ++seeing;
      ++tally->views[k];
      tally->p_far[k] += probe.Distance(*uv_p) > options.support_px;
      p_near += probe.Distance(*uv_p) <= options.support_px;
      const double dq = probe.Distance(*uv_q);
      const double r_px = probe.RadiusPx(q, radius);
      const double half_width = dq + probe.WoodRadius(*uv_q) - 0.5;
      const std::optional<double> excess =
          probe.BandExcess(*uv_q, r_px, options.band_margin_px, options.band_tolerance_px);
      const bool bundle = excess.has_value();
      const bool fits = bundle && *excess <= 0;
      ++tally->q_bins[k][dq <= 2 ? 0 : dq <= 4 ? 1 : dq <= 6 ? 2 : 3];
      old_ok += dq <= options.support_px;
      band_ok += dq <= options.support_px || fits;
      if (dq > options.support_px) {
        tally->q_far_bundle[k] += bundle;
        tally->q_far_fits[k] += fits;
        tally->hw_minus_r[k] += half_width - r_px;
        tally->q_far_d[k].push_back(dq);
      } else {
        tally->q_near_bundle[k] += bundle;
      }
    }
    // The end needs every seeing view; a step needs two.
    const int need = k == 0 ? std::max(seeing, options.min_support_views)
                            : options.min_support_views;
    tally->q_old_pass[k] += old_ok >= need;
    tally->q_band_pass[k] += band_ok >= need;
    tally->p_two_near[k] += p_near >= 2;
  }
}

GrowOptions OptionsFromEnv() {
  GrowOptions o;
  OverrideFromEnv("VB_GROW_SUPPORT_PX", &o.support_px);
  OverrideFromEnv("VB_GROW_LEN", &o.max_length_m);
  OverrideFromEnv("VB_GROW_EPI", &o.min_epipolar_angle_deg);
  OverrideFromEnv("VB_GROW_TURN", &o.max_turn_deg);
  OverrideFromEnv("VB_GROW_OTHER", &o.other_cane_m);
  OverrideFromEnv("VB_GROW_PRIOR", &o.prior_px_per_mm);
  OverrideFromEnv("VB_GROW_OFFSET", &o.max_offset_m);
  OverrideFromEnv("VB_GROW_MIN_LEN", &o.min_length_m);
  OverrideFromEnv("VB_GROW_MIN_CANE", &o.min_cane_length_m);
  OverrideFromEnv("VB_GROW_ALONG_PX", &o.support_along_px);
  OverrideFromEnv("VB_GROW_TRIM", &o.trim_m);
  OverrideFromEnv("VB_GROW_VIEWS", &o.min_support_views);
  OverrideFromEnv("VB_GROW_END", &o.require_end_support);
  OverrideFromEnv("VB_GROW_BACKOFF", &o.end_backoff_m);
  OverrideFromEnv("VB_GROW_ALONG_MAX", &o.alongside_max_m);
  OverrideFromEnv("VB_GROW_ALONG_GAP", &o.alongside_min_gap_m);
  OverrideFromEnv("VB_GROW_ALONG_CONT", &o.continuation_m);
  OverrideFromEnv("VB_GROW_ALONG_PRIOR", &o.alongside_prior_px_per_mm);
  OverrideFromEnv("VB_GROW_ALONG_PART", &o.alongside_require_parting);
  OverrideFromEnv("VB_GROW_BAND", &o.band_support);
  OverrideFromEnv("VB_GROW_BAND_END", &o.band_end_support);
  OverrideFromEnv("VB_GROW_BAND_MARGIN", &o.band_margin_px);
  OverrideFromEnv("VB_GROW_BAND_PRIOR", &o.band_prior_px_per_mm);
  OverrideFromEnv("VB_GROW_REFIT", &o.refit_span_m);
  OverrideFromEnv("VB_GROW_REFIT_END", &o.refit_end_m);
  OverrideFromEnv("VB_GROW_REFIT_PX", &o.refit_search_px);
  OverrideFromEnv("VB_GROW_REFIT_SMOOTH", &o.refit_smooth_px_per_mm);
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
  // VB_GROW_BASE=1: compare against the default growth instead of none.
  bool base = false;
  OverrideFromEnv("VB_GROW_BASE", &base);
  ReconstructOptions off;
  off.grow.enabled = base;
  ReconstructOptions on;
  on.grow = grow;
  on.grow.enabled = true;
  double wrong_near_head = 0, wrong_10_20 = 0, end_stretch = 0, end_stretch_right = 0;
  double by_distance[4] = {}, by_distance_right[4] = {};
  double by_views[2] = {}, by_views_right[2] = {}, by_length[3] = {}, by_length_right[3] = {};
  double added = 0, right = 0, added_from_wrong_end = 0, right_from_wrong_end = 0, time = 0;
  int ends = 0, grown_ends = 0;
  GrowSummary totals;
  AlongsideTally along;
  WhyTally why;
  DriftTally drift;
  const bool explain = std::getenv("VB_GROW_WHY") != nullptr;
  const bool drifts = std::getenv("VB_GROW_DRIFT") != nullptr;
  std::vector<double> d_recall, d_precision, d_connectivity, d_bag_recall, d_bag_precision;
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
    totals.ends_alongside += summary.ends_alongside;
    totals.alongside_length_m += summary.alongside_length_m;
    AlongsideEnds(stop.scene.vine, grown, summary, &along);
    if (explain) WhyUnsupported(truth, stop.views, matched->rig, on.grow, summary, &why);
    if (drifts) drift.Add(truth, stop.views, matched->rig, on.grow, summary);
    if (base) {
      // The grown canes as a bag, before connection: the default growth against this one.
      std::vector<Polyline3> grown_base = *canes;
      ASSERT_TRUE(
          GrowCaneEnds(stop.views, matched->rig, off.volume, off.grow, &grown_base).ok());
      const auto bag_base = EvaluateReconstruction(Flat(grown_base), truth);
      const auto bag = EvaluateReconstruction(Flat(grown), truth);
      ASSERT_TRUE(bag_base.ok() && bag.ok());
      d_bag_recall.push_back(bag->cane_recall - bag_base->cane_recall);
      d_bag_precision.push_back(bag->cane_precision - bag_base->cane_precision);
    }
    const double added_before = added, right_before = right;
    for (size_t c = 0; c < grown.size(); ++c) {
      const Polyline3& before = (*canes)[c];
      const Polyline3& after = grown[c];
      // The original points are kept as a contiguous run; what lies outside it was added.
      // (An end backed off before growing, end_backoff_m, lost some of them.)
      const auto original = [&](const Eigen::Vector3d& p) {
        return std::find(before.points.begin(), before.points.end(), p) != before.points.end();
      };
      size_t first = 0, last = after.points.size() - 1;
      while (first < after.points.size() && !original(after.points[first])) ++first;
      while (last > first && !original(after.points[last])) --last;
      // (With refit_end_m a cane's own end points may move: then they count as added, and a
      // cane whose every point moved is left out.)
      if (first >= after.points.size()) continue;
      for (int side = 0; side < 2; ++side) {
        const size_t lo = side == 0 ? 0 : last;
        const size_t hi = side == 0 ? first : after.points.size() - 1;
        if (hi <= lo) continue;
        const Eigen::Vector3d& end = side == 0 ? after.points[first] : after.points[last];
        const bool end_right = DistanceToCanes(end, drawn.canes) <= 0.010;
        int seeing = 0;
        for (const CameraCalibration& camera : matched->rig.cameras) {
          const auto uv = camera.Project(end);
          seeing += uv && camera.InImage(*uv);
        }
        const int sv = std::clamp(seeing, 2, 3) - 2;
        const double cane_length = before.Length();
        const int lb = cane_length < 0.1 ? 0 : cane_length < 0.2 ? 1 : 2;
        // The grown end's own last 2 cm, for comparison.
        {
          const std::vector<double> arc = before.ArcLengths();
          for (size_t i = 0; i + 1 < before.points.size(); ++i) {
            const double from_end = side == 0 ? arc[i] : arc.back() - arc[i + 1];
            if (from_end >= 0.02) continue;
            const double step = (before.points[i + 1] - before.points[i]).norm();
            const bool ok =
                DistanceToCanes(0.5 * (before.points[i] + before.points[i + 1]), drawn.canes) <= 0.010;
            end_stretch += step;
            end_stretch_right += ok * step;
          }
        }
        const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
        if (verbose) {
          std::printf("GROW stop %llu cane %zu side %d len %.3f end %.1f mm:",
                      static_cast<unsigned long long>(first + k), c, side, before.Length(),
                      1000 * DistanceToCanes(end, drawn.canes));
        }
        // Walk from the original end outward, to bucket by the distance grown.
        double along = 0;
        for (size_t k2 = 0; k2 < hi - lo; ++k2) {
          const size_t i = side == 0 ? hi - 1 - k2 : lo + k2;
          const double step = (after.points[i + 1] - after.points[i]).norm();
          const Eigen::Vector3d mid = 0.5 * (after.points[i + 1] + after.points[i]);
          const bool ok = DistanceToCanes(mid, drawn.canes) <= 0.010;
          if (verbose) std::printf(" %.0f", 1000 * DistanceToCanes(mid, drawn.canes));
          added += step;
          right += ok * step;
          const int bucket = along < 0.02 ? 0 : along < 0.04 ? 1 : along < 0.08 ? 2 : 3;
          along += step;
          by_distance[bucket] += step;
          by_views[sv] += step;
          by_views_right[sv] += ok * step;
          by_length[lb] += step;
          by_length_right[lb] += ok * step;
          by_distance_right[bucket] += ok * step;
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
        if (verbose) std::printf("\n");
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
  std::printf("grown on alongside another cane: %d ends, %.3f m per stop\n", totals.ends_alongside,
              totals.alongside_length_m / count);
  along.Print(count);
  if (explain) why.Print();
  if (drifts) drift.Print();
  std::printf("added %.3f m per stop, right %.3f; from ends already > 10 mm off: %.3f m per stop, "
              "right %.3f; stage %.4f s per stop\n",
              added / count, right / std::max(added, 1e-9), added_from_wrong_end / count,
              right_from_wrong_end / std::max(added_from_wrong_end, 1e-9), time / count);
  std::printf("wrong within 3 cm of the head %.3f m per stop, 10-20 mm from wood %.3f m per stop\n",
              wrong_near_head / count, wrong_10_20 / count);
  std::printf("by distance grown 0-2 / 2-4 / 4-8 / 8+ cm: %.3f (%.2f) %.3f (%.2f) %.3f (%.2f) "
              "%.3f (%.2f) m per stop (right)\n",
              by_distance[0] / count, by_distance_right[0] / std::max(by_distance[0], 1e-9),
              by_distance[1] / count, by_distance_right[1] / std::max(by_distance[1], 1e-9),
              by_distance[2] / count, by_distance_right[2] / std::max(by_distance[2], 1e-9),
              by_distance[3] / count, by_distance_right[3] / std::max(by_distance[3], 1e-9));
  std::printf("end seen by 2 / 3 views: %.3f (%.2f) %.3f (%.2f); cane < 10 / 10-20 / 20+ cm: "
              "%.3f (%.2f) %.3f (%.2f) %.3f (%.2f)\n",
              by_views[0] / count, by_views_right[0] / std::max(by_views[0], 1e-9),
              by_views[1] / count, by_views_right[1] / std::max(by_views[1], 1e-9),
              by_length[0] / count, by_length_right[0] / std::max(by_length[0], 1e-9),
              by_length[1] / count, by_length_right[1] / std::max(by_length[1], 1e-9),
              by_length[2] / count, by_length_right[2] / std::max(by_length[2], 1e-9));
  std::printf("the grown ends' own last 2 cm: %.3f m per stop, right %.2f\n", end_stretch / count,
              end_stretch_right / std::max(end_stretch, 1e-9));
  std::printf("without: recall %.4f precision %.4f connectivity %.4f\n", recall0 / count,
              precision0 / count, connectivity0 / count);
  if (base) {
    double se_br = 0, se_bp = 0;
    const double br = MeanSe(d_bag_recall, &se_br), bp = MeanSe(d_bag_precision, &se_bp);
    std::printf("grown canes before connection, these options - default: recall %+.4f +- %.4f, "
                "precision %+.4f +- %.4f\n", br, se_br, bp, se_bp);
  }
  std::printf("with - without: recall %+.4f +- %.4f, precision %+.4f +- %.4f, connectivity "
              "%+.4f +- %.4f\n",
              dr, se_r, dp, se_p, dc, se_c);
}

}  // namespace
}  // namespace vb::reconstruct
