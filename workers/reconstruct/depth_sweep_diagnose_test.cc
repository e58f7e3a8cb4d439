// SPDX-License-Identifier: Apache-2.0
// Diagnosis tool, not a test: what the depth sweep along unexplained skeleton paths
// (depth_sweep.h) adds to the assembled canes of rendered stops (VB_SEED, VB_STOPS, VB_INPUT as
// ReportStopsFromEnv; 1300, 20 stops, images by default). Run with
// --gtest_also_run_disabled_tests --gtest_filter='DepthSweep.DISABLED_Report'. Tuning seeds
// only (1100-1999). Options from the environment: VB_SWEEP_MIN_VIEWS, VB_SWEEP_ACCEPT_PX,
// VB_SWEEP_RMS_PX, VB_SWEEP_MIN_LENGTH_M, VB_SWEEP_SMOOTH, VB_SWEEP_CAP_PX,
// VB_SWEEP_MIN_STRETCH_PX, VB_SWEEP_MAX_STEP, VB_SWEEP_UNIQUE_STEPS, VB_SWEEP_MAX_AMBIGUOUS,
// VB_SWEEP_MIN_STRETCH_SHARE,
// VB_SWEEP_LINE_MARGIN_PX, and the check's VB_SWEEP_CHECK (0/1), VB_SWEEP_CHECK_SPREAD,
// VB_SWEEP_CHECK_EXCESS, VB_SWEEP_CHECK_FOREGROUND. With VB_SWEEP_RUNS_CSV
// set to a path, one line per added cane (its labels and MeasureSweptRun features) goes there.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/cane_assembly.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/depth_sweep.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

DepthSweepOptions SweepOptionsFromEnv() {
  DepthSweepOptions options;
  options.enabled = true;
  OverrideFromEnv("VB_SWEEP_MIN_VIEWS", &options.min_views);
  OverrideFromEnv("VB_SWEEP_ACCEPT_PX", &options.accept_px);
  OverrideFromEnv("VB_SWEEP_RMS_PX", &options.accept_rms_px);
  OverrideFromEnv("VB_SWEEP_MIN_LENGTH_M", &options.min_length_m);
  OverrideFromEnv("VB_SWEEP_SMOOTH", &options.smooth_px2);
  OverrideFromEnv("VB_SWEEP_CAP_PX", &options.cap_px);
  OverrideFromEnv("VB_SWEEP_MIN_STRETCH_PX", &options.min_stretch_px);
  OverrideFromEnv("VB_SWEEP_MAX_STEP", &options.max_step);
  OverrideFromEnv("VB_SWEEP_UNIQUE_STEPS", &options.unique_exclusion_steps);
  OverrideFromEnv("VB_SWEEP_LINE_MARGIN_PX", &options.line_margin_px);
  OverrideFromEnv("VB_SWEEP_MAX_AMBIGUOUS", &options.max_ambiguous_share);
  OverrideFromEnv("VB_SWEEP_MIN_STRETCH_SHARE", &options.min_stretch_accepted_share);
  OverrideFromEnv("VB_SWEEP_CHECK", &options.check);
  OverrideFromEnv("VB_SWEEP_CHECK_SPREAD", &options.check_max_width_log_spread);
  OverrideFromEnv("VB_SWEEP_CHECK_EXCESS", &options.check_max_width_log_excess);
  OverrideFromEnv("VB_SWEEP_CHECK_FOREGROUND", &options.check_min_foreground);
  return options;
}

std::vector<Cane> AsCanes(const std::vector<Polyline3>& lines) {
  std::vector<Cane> out;
  for (const Polyline3& line : lines) {
    Cane cane;
    cane.polyline = line;
    out.push_back(cane);
  }
  return out;
}

TEST(DepthSweep, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  const DepthSweepOptions sweep = SweepOptionsFromEnv();
  ASSERT_TRUE(sweep.Validate().ok()) << sweep.Validate();
  const ReconstructOptions options;
  std::vector<double> unexplained(3, 0), stretches(3, 0);
  double samples = 0, accepted = 0, added = 0, right_vine = 0, right_drawn = 0, time = 0;
  double by_length[3] = {}, by_length_right[3] = {};  // added canes < 5, 5-10, >= 10 cm
  double true_length = 0, unrecalled = 0, recovered = 0;
  int canes_added = 0;
  // Added length (and of it on the vine's canes) by the cane's ambiguous share (0, < 0.3, >= 0.3)
  // and its stretch's accepted share (< 0.5, >= 0.5); off-wood length by its distance to the
  // nearest drawn cane (10-20, 20-50, >= 50 mm).
  double by_ambiguous[3] = {}, by_ambiguous_right[3] = {}, by_stretch[2] = {},
         by_stretch_right[2] = {}, wrong_by_distance[3] = {};
  // Added length by the best conditioned pair of the swept view and another (largest EpipolarSin:
  // < 0.3, 0.3-0.6, >= 0.6) and of it on the vine's canes; off-wood length whose nearest drawn
  // cane projects within 3 px of it in the swept view (a depth error on the right ray).
  double by_sin[3] = {}, by_sin_right[3] = {}, wrong_on_ray = 0;
  double wrong_near_wire = 0, wrong_near_post = 0;  // off-wood length within 10 mm / 5 cm
  double recall0 = 0, recall1 = 0, precision0 = 0, precision1 = 0;
  double rejected = 0;
  const char* csv_path = std::getenv("VB_SWEEP_RUNS_CSV");
  FILE* csv = csv_path != nullptr ? std::fopen(csv_path, "w") : nullptr;
  if (csv != nullptr) {
    std::fprintf(csv, "seed,view,length_m,on_vine_m,on_drawn_m,recovered_m,ambiguous,views,"
                      "width_log_spread,width_log_excess,foreground,tangent,turning_per_m,"
                      "straightness,mean_y_m,checked\n");
  }
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const VineModel& truth = stop.scene.vine;
    const auto matched =
        MatchWithRigRefinement(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(matched.ok()) << matched.status();
    auto canes = AssembleCanes(matched->pieces, options.assembly, Deadline::Infinite());
    ASSERT_TRUE(canes.ok());
    std::erase_if(*canes, [&](const Polyline3& c) { return options.volume.MostlyOutside(c); });
    std::vector<Polyline3> swept = *canes;
    DepthSweepSummary summary;
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(SweepUnexplainedPaths(stop.views, matched->rig, options.volume, sweep,
                                      Deadline::Infinite(), &swept, &summary).ok());
    time += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (size_t v = 0; v < 3 && v < summary.unexplained_px.size(); ++v) {
      unexplained[v] += summary.unexplained_px[v];
      stretches[v] += summary.stretches[v];
    }
    rejected += summary.rejected_length_m;
    samples += summary.samples;
    accepted += summary.accepted_samples;
    canes_added += summary.added_canes;
    // Added length on wood: within 10 mm of the vine's true canes, or of any drawn cane (the
    // neighbours' too, which connection may still sort out).
    for (size_t c = canes->size(); c < swept.size(); ++c) {
      const Polyline3& line = swept[c];
      const double length = line.Length();
      const int bin = length < 0.05 ? 0 : length < 0.10 ? 1 : 2;
      const SweptCane& info = summary.added[c - canes->size()];
      const int amb = info.ambiguous_share == 0 ? 0 : info.ambiguous_share < 0.3 ? 1 : 2;
      const int str = info.stretch_accepted_share < 0.5 ? 0 : 1;
      const std::vector<double> arc = line.ArcLengths();
      double run_vine = 0, run_drawn = 0;
      for (double s = 0.0025; s < length; s += 0.005) {
        const Eigen::Vector3d p = line.PointAt(s, arc);
        const bool on_vine = NearAnyCane(p, truth.canes);
        run_vine += 0.005 * on_vine;
        run_drawn += 0.005 * NearAnyCane(p, stop.drawn.canes);
        added += 0.005;
        right_vine += 0.005 * on_vine;
        right_drawn += 0.005 * NearAnyCane(p, stop.drawn.canes);
        by_length[bin] += 0.005;
        by_length_right[bin] += 0.005 * on_vine;
        by_ambiguous[amb] += 0.005;
        by_ambiguous_right[amb] += 0.005 * on_vine;
        by_stretch[str] += 0.005;
        by_stretch_right[str] += 0.005 * on_vine;
        Eigen::Vector3d nearest;
        const double d = DistanceToCanes(p, stop.drawn.canes, &nearest);
        if (d > 0.01) wrong_by_distance[d < 0.02 ? 0 : d < 0.05 ? 1 : 2] += 0.005;
        const CameraCalibration& camera = matched->rig.cameras[info.view];
        const auto px = camera.Project(p);
        const auto px_true = camera.Project(nearest);
        if (d > 0.01 && px && px_true && (*px - *px_true).norm() < 3.0) wrong_on_ray += 0.005;
        if (d > 0.01) {
          std::vector<Polyline3> wires;
          for (const Wire& wire : truth.wires) {
            Polyline3 w;
            w.points = wire.points;
            w.radii.assign(wire.points.size(), wire.radius);
            wires.push_back(w);
          }
          if (DistanceToLines(p, wires) < 0.01) wrong_near_wire += 0.005;
          for (const Post& post : truth.posts) {
            Polyline3 axis;
            axis.points = {post.base, post.top};
            axis.radii = {post.radius, post.radius};
            if (DistanceToLines(p, {axis}) < post.radius + 0.05) {
              wrong_near_post += 0.005;
              break;
            }
          }
        }
        double best_sin = 0.0;
        for (int w = 0; w < static_cast<int>(matched->rig.cameras.size()); ++w) {
          if (w == info.view || !px) continue;
          const auto sin = EpipolarSin(matched->rig, info.view, w, p, line.TangentAt(s, arc), *px);
          if (sin) best_sin = std::max(best_sin, *sin);
        }
        const int sb = best_sin < 0.3 ? 0 : best_sin < 0.6 ? 1 : 2;
        by_sin[sb] += 0.005;
        by_sin_right[sb] += 0.005 * on_vine;
      }
      if (csv != nullptr) {
        // The true length the assembled canes leave out that this cane holds.
        double run_recovered = 0;
        const std::vector<Cane> before = AsCanes(*canes), run = AsCanes({line});
        for (const Cane& cane : truth.canes) {
          const std::vector<double> true_arc = cane.polyline.ArcLengths();
          for (double s = 0.0025; s < cane.polyline.Length(); s += 0.005) {
            const Eigen::Vector3d p = cane.polyline.PointAt(s, true_arc);
            if (!NearAnyCane(p, before) && NearAnyCane(p, run)) run_recovered += 0.005;
          }
        }
        const SweptRunFeatures& f = info.features;
        std::fprintf(csv, "%lu,%d,%.4f,%.4f,%.4f,%.4f,%.3f,%d,%.4f,%.4f,%.4f,%.4f,%.3f,%.4f,%.4f,"
                          "%d\n",
                     static_cast<unsigned long>(first + k), info.view, length, run_vine,
                     run_drawn, run_recovered, info.ambiguous_share, f.views, f.width_log_spread,
                     f.width_log_excess, f.foreground, f.tangent, f.turning_per_m,
                     f.straightness, f.mean_y_m, info.checked ? 1 : 0);
      }
    }
    // The true length the assembled canes leave out, and how much of it the added canes hold.
    const std::vector<Cane> before = AsCanes(*canes);
    const std::vector<Cane> added_canes =
        AsCanes(std::vector<Polyline3>(swept.begin() + canes->size(), swept.end()));
    for (const Cane& cane : truth.canes) {
      const Polyline3& line = cane.polyline;
      const std::vector<double> arc = line.ArcLengths();
      for (double s = 0.0025; s < line.Length(); s += 0.005) {
        const Eigen::Vector3d p = line.PointAt(s, arc);
        true_length += 0.005;
        if (NearAnyCane(p, before)) continue;
        unrecalled += 0.005;
        recovered += 0.005 * NearAnyCane(p, added_canes);
      }
    }
    const auto bag0 = EvaluateReconstruction(Flat(*canes), truth);
    const auto bag1 = EvaluateReconstruction(Flat(swept), truth);
    ASSERT_TRUE(bag0.ok() && bag1.ok());
    recall0 += bag0->cane_recall;
    recall1 += bag1->cane_recall;
    precision0 += bag0->cane_precision;
    precision1 += bag1->cane_precision;
  }
  std::printf("depth sweep on %d stops from %lu (%s): min_views %d accept_px %.2f rms_px %.2f "
              "min_length %.3f smooth %.2f cap %.1f min_stretch %.0f\n",
              count, static_cast<unsigned long>(first), images ? "images" : "labels",
              sweep.min_views, sweep.accept_px, sweep.accept_rms_px, sweep.min_length_m,
              sweep.smooth_px2, sweep.cap_px, sweep.min_stretch_px);
  std::printf("per stop: unexplained skeleton px per view %.0f %.0f %.0f; stretches %.1f %.1f "
              "%.1f; samples %.0f, accepted %.0f; canes added %.2f; time %.3f s\n",
              unexplained[0] / count, unexplained[1] / count, unexplained[2] / count,
              stretches[0] / count, stretches[1] / count, stretches[2] / count, samples / count,
              accepted / count, static_cast<double>(canes_added) / count, time / count);
  std::printf("added length %.3f m per stop; on the vine's canes %.3f (share %.3f), on any drawn "
              "cane %.3f (share %.3f)\n",
              added / count, right_vine / count, right_vine / std::max(added, 1e-9),
              right_drawn / count, right_drawn / std::max(added, 1e-9));
  std::printf("by added cane length < 5 / 5-10 / >= 10 cm: %.3f (%.3f) %.3f (%.3f) %.3f (%.3f) m "
              "per stop (share on the vine)\n",
              by_length[0] / count, by_length_right[0] / std::max(by_length[0], 1e-9),
              by_length[1] / count, by_length_right[1] / std::max(by_length[1], 1e-9),
              by_length[2] / count, by_length_right[2] / std::max(by_length[2], 1e-9));
  std::printf("by ambiguous share 0 / < 0.3 / >= 0.3: %.3f (%.3f) %.3f (%.3f) %.3f (%.3f); by "
              "stretch accepted share < 0.5 / >= 0.5: %.3f (%.3f) %.3f (%.3f) m per stop (share "
              "on the vine)\n",
              by_ambiguous[0] / count, by_ambiguous_right[0] / std::max(by_ambiguous[0], 1e-9),
              by_ambiguous[1] / count, by_ambiguous_right[1] / std::max(by_ambiguous[1], 1e-9),
              by_ambiguous[2] / count, by_ambiguous_right[2] / std::max(by_ambiguous[2], 1e-9),
              by_stretch[0] / count, by_stretch_right[0] / std::max(by_stretch[0], 1e-9),
              by_stretch[1] / count, by_stretch_right[1] / std::max(by_stretch[1], 1e-9));
  std::printf("off any drawn cane, by distance to the nearest 10-20 / 20-50 / >= 50 mm: %.3f %.3f "
              "%.3f m per stop\n",
              wrong_by_distance[0] / count, wrong_by_distance[1] / count,
              wrong_by_distance[2] / count);
  std::printf("off wood on the swept ray (nearest drawn cane within 3 px there): %.3f m per stop;"
              " by best pair |sin| < 0.3 / 0.3-0.6 / >= 0.6: %.3f (%.3f) %.3f (%.3f) %.3f (%.3f)\n",
              wrong_on_ray / count, by_sin[0] / count, by_sin_right[0] / std::max(by_sin[0], 1e-9),
              by_sin[1] / count, by_sin_right[1] / std::max(by_sin[1], 1e-9), by_sin[2] / count,
              by_sin_right[2] / std::max(by_sin[2], 1e-9));
  std::printf("off wood within 10 mm of a true wire %.3f, within 5 cm of a post %.3f m per stop\n",
              wrong_near_wire / count, wrong_near_post / count);
  std::printf("true length %.3f m per stop; left out by the assembled canes %.3f (share %.3f); "
              "recovered by the added canes %.3f (share of the left out %.3f)\n",
              true_length / count, unrecalled / count, unrecalled / true_length,
              recovered / count, recovered / std::max(unrecalled, 1e-9));
  if (csv != nullptr) std::fclose(csv);
  std::printf("check %s (spread %.2f excess %.2f foreground %.2f): dropped %.3f m per stop\n",
              sweep.check ? "on" : "off", sweep.check_max_width_log_spread,
              sweep.check_max_width_log_excess, sweep.check_min_foreground, rejected / count);
  std::printf("as a bag (Flat): recall %.4f -> %.4f, precision %.4f -> %.4f\n", recall0 / count,
              recall1 / count, precision0 / count, precision1 / count);
}

}  // namespace
}  // namespace vb::reconstruct
