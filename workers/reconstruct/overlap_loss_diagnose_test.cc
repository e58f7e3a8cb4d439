// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: how much of the true length lies along another cane in the views
// (LyingAlongAnother, synthetic_views.h: within 2 px plus the two half-widths of another cane's
// projection, this vine's or a neighbour's, for more than 30 px), and how much of it the pipeline
// recalls. Every 5 mm sample of the vine's trunk and canes inside two or more images is classed by
// the number of views that see it lying along another cane, and counted as recalled when the final
// model has a cane within 10 mm (the recall metric's test). Run with
//   VB_INPUT=labels|images VB_SEED=1300 VB_STOPS=10 [VB_FIDUCIALS=0] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='OverlapLoss.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

constexpr double kStepM = 0.005;

// The distance from p to the surface of `vine`'s head (its nearest sphere; negative inside).
double ToHeadSurface(const VineModel& vine, const Eigen::Vector3d& p) {
  double to_head = 1e9;
  for (const Sphere& sphere : vine.head.spheres)
    to_head = std::min(to_head, (p - sphere.center).norm() - sphere.radius);
  return to_head;
}

TEST(OverlapLoss, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10);
  const ReconstructOptions options;
  constexpr int kRows = 4;  // lying along another cane in 0, 1, 2 or 3 of the views that see it
  double length[kRows] = {}, recalled[kRows] = {}, total = 0.0, outside = 0.0;
  // Of each row: lying along another cane of this vine (not a neighbour's) in 2+ views.
  double own[kRows] = {}, own_recalled[kRows] = {};
  // Lost length lying along another cane of this vine in 2+ views, by the 3D distance from the
  // sample to the nearest other cane of the vine (axis to axis): under 10, 10-20, 20-40, 40+ mm.
  constexpr int kBands = 4;
  const double band_edges_m[kBands - 1] = {0.01, 0.02, 0.04};
  double lost_by_gap[kBands] = {};
  // ... and by distance from the true head's surface: under 5 cm, 5-15 cm, farther.
  double lost_by_head[3] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const VineModel& vine = stop.scene.vine;
    for (const LengthSample& s : SampleTrueLength(stop, kStepM, true)) {
      const Eigen::Vector3d& p = s.p;
      const double w = s.weight_m;
      total += w;
      if (s.in_image < 2) {
        outside += w;
        continue;
      }
      const bool hit = NearAnyCane(p, result->model.canes);
      const int row = std::min(s.along, kRows - 1);
      length[row] += w;
      if (hit) recalled[row] += w;
      if (s.along_own < 2) continue;
      own[row] += w;
      if (hit) {
        own_recalled[row] += w;
        continue;
      }
      const double nearest = NearestOtherCane(vine, s.cane, p);
      int band = 0;
      while (band < kBands - 1 && nearest >= band_edges_m[band]) ++band;
      lost_by_gap[band] += w;
      const double to_head = ToHeadSurface(vine, p);
      lost_by_head[to_head < 0.05 ? 0 : to_head < 0.15 ? 1 : 2] += w;
    }
  }
  std::printf("OverlapLoss %s, seeds %llu-%llu: share of true length (trunk and canes)\n",
              images ? "images" : "labels", static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1));
  std::printf("  inside fewer than 2 images: %.3f\n", outside / total);
  std::printf("  %-44s %8s %8s %8s   %s\n", "inside 2+ images, lying along another cane in",
              "length", "recalled", "lost", "of which along this vine's own in 2+ views: length, lost");
  for (int r = 0; r < kRows; ++r) {
    std::printf("  %d view(s)%35s %8.3f %8.3f %8.3f   %8.3f %8.3f\n", r, "", length[r] / total,
                recalled[r] / total, (length[r] - recalled[r]) / total, own[r] / total,
                (own[r] - own_recalled[r]) / total);
  }
  std::printf("  lost, along this vine's own in 2+ views, by 3D distance to the nearest other cane "
              "of the vine: <10 mm %.3f, 10-20 mm %.3f, 20-40 mm %.3f, >=40 mm %.3f\n",
              lost_by_gap[0] / total, lost_by_gap[1] / total, lost_by_gap[2] / total,
              lost_by_gap[3] / total);
  std::printf("  ... by distance from the true head's surface: <5 cm %.3f, 5-15 cm %.3f, "
              ">=15 cm %.3f\n", lost_by_head[0] / total, lost_by_head[1] / total,
              lost_by_head[2] / total);
  EXPECT_GT(total, 0.0);
}

// The two reports crossed: each 5 mm sample inside two or more images, lying along another cane
// of this vine in two or more views (as above), is followed through the stages of
// MatchLoss.DISABLED_Report (match_loss_diagnose_test.cc: the pipeline run one stage at a time,
// without extension), and the first stage where it is lost (FirstLostStage) is counted, split
// by the 3D distance to the nearest other cane of the vine and by the distance from the true
// head's surface. The first line is the samples lying along nothing in every view, for
// comparison. Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='OverlapLoss.DISABLED_ByStage'
TEST(OverlapLoss, DISABLED_ByStage) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10);
  const ReconstructOptions options;
  const double threshold = 1.0 / (1.0 + options.correspondence.alpha);
  // The columns: FirstLostStage's stages from kLossForeground (samples in < 2 images are left out).
  const char* names[kLossStageCount] = {"in", "fg", "skel", "pair", "raw", "fit", "thr", "gibbs",
                                        "assem", "conn", "refine", "kept"};
  // Rows: along nothing; along this vine's own in 2+ views, all; by 3D gap <10, 10-20, 20-40,
  // 40+ mm; by head distance <5, 5-15, 15+ cm.
  constexpr int kRowCount = 9;
  const char* rows[kRowCount] = {"along no cane in any view", "along own in 2+ views, all",
                                 "  nearest other cane < 10 mm", "  10-20 mm", "  20-40 mm",
                                 "  >= 40 mm", "  head surface < 5 cm", "  5-15 cm",
                                 "  >= 15 cm"};
  double table[kRowCount][kLossStageCount] = {};
  double total = 0.0, raw_cause[3] = {}, probable_band[3] = {};
  MatchFeatures feature_sum[2] = {}, weights = options.correspondence.classifier.multi_view;
  double feature_weight[2] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const auto run = RenderAndMatch(seed, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const SimulatedStop& stop = run->stop;
    const RigCalibration& rig = run->matched.rig;
    const std::vector<View2D>& views = run->views();
    const int n = static_cast<int>(views.size());
    const CandidateOptions co = CandidateOptionsFor(options.correspondence, n > 2);
    const std::vector<ViewSamples> samples =
        SampleViews(views, rig, options.correspondence.sample_step_px);
    const std::vector<MatchCandidate> raw = RawCandidates(samples, rig, co);
    // Every run of every pair (min_hits 1), its hits keyed by the pair's segments, with the run's
    // length: why a bundle sample has no raw candidate.
    std::map<std::tuple<int, int, int, int>, std::vector<std::pair<Eigen::Vector3d, int>>> runs;
    {
      CandidateOptions all_runs = co;
      all_runs.min_hits = 1;
      for (const MatchCandidate& c : RawCandidates(samples, rig, all_runs))
        for (const EpipolarHit& h : c.hits)
          runs[{c.view_a, c.segment_a, c.view_b, c.segment_b}].push_back(
              {h.point, static_cast<int>(c.hits.size())});
    }
    const auto scored = ScoreCandidates(views, rig, options.correspondence, Deadline::Infinite());
    ASSERT_TRUE(scored.ok());
    // The best candidate near a sample: probability to 1e-3, then the index (kIndexScale apart).
    constexpr double kIndexScale = 1e6;
    PointGrid best_grid;
    for (size_t i = 0; i < scored->size(); ++i) {
      const ScoredCandidate& s = (*scored)[i];
      best_grid.AddLine(s.fit.control_points,
                        std::floor(s.probability * 1000.0) * kIndexScale + static_cast<double>(i));
    }
    const auto assembled = AssembleStop(views, rig, run->matched.pieces, options);
    ASSERT_TRUE(assembled.ok()) << assembled.status();
    const auto connected = ConnectAndRefine(views, rig, *assembled, assembled->joins, options);
    ASSERT_TRUE(connected.ok()) << connected.status();
    const StageGrids grids =
        MakeStageGrids(raw, *scored, run->matched.pieces, *assembled, *connected);
    const SegmentMaps maps(views);

    const VineModel& vine = stop.scene.vine;
    for (const LengthSample& ls : SampleTrueLength(stop, kStepM, true)) {
      const Eigen::Vector3d& p = ls.p;
      const double w = ls.weight_m;
      total += w;
      const SampleInViews at = LocateSample(p, stop.true_rig, views, maps);
      if (at.in_image < 2) continue;
      const int beside = ls.along, beside_own = ls.along_own;
      const SampleEvidence e =
          EvidenceOf(at, stop.true_rig, p, ls.tangent, co.min_epipolar_sin);
      const std::vector<int>& seg = e.segment;
      const LossStage stage = FirstLostStage(p, e, grids, threshold);
      // Features of the best candidate near: bundle samples lost at the threshold against
      // samples along nothing that are kept.
      const int group = (stage == kLossProbable && beside_own >= 2) ? 0
                        : (stage == kLossKept && beside == 0)        ? 1
                                                                     : -1;
      if (group >= 0) {
        const double code = best_grid.MaxNear(p);
        if (code >= 0) {
          const ScoredCandidate& s =
              (*scored)[static_cast<size_t>(std::fmod(code, kIndexScale))];
          if (s.multi_view) {
            for (size_t f = 0; f < s.features.size(); ++f)
              feature_sum[group][f] += w * s.features[f];
            feature_weight[group] += w;
          }
        }
      }
      if (beside == 0) table[0][stage] += w;
      if (beside_own < 2) continue;
      table[1][stage] += w;
      if (stage == kLossRaw) {
        // 0 no crossing of a conditioned pair's segments within 10 mm; 1 only runs shorter
        // than min_hits, a segment shorter than that; 2 only short runs, both segments long.
        int cause = 0;
        for (int a = 0; a < n; ++a)
          for (int b = a + 1; b < n; ++b) {
            if (seg[a] < 0 || seg[b] < 0) continue;
            const auto it = runs.find({a, seg[a], b, seg[b]});
            if (it == runs.end()) continue;
            for (const auto& [q, size] : it->second) {
              if ((q - p).norm() > 0.01) continue;
              const int na = static_cast<int>(samples[a].segments()[seg[a]].normalised.size());
              const int nb = static_cast<int>(samples[b].segments()[seg[b]].normalised.size());
              cause = std::max(cause, std::min(na, nb) < co.min_hits ? 1 : 2);
            }
          }
        raw_cause[cause] += w;
      }
      if (stage == kLossProbable) {
        const double best = grids.fitted.MaxNear(p);
        probable_band[best < 0.05 ? 0 : best < 0.15 ? 1 : 2] += w;
      }
      const double nearest = NearestOtherCane(vine, ls.cane, p);
      table[nearest < 0.01 ? 2 : nearest < 0.02 ? 3 : nearest < 0.04 ? 4 : 5][stage] += w;
      const double to_head = ToHeadSurface(vine, p);
      table[to_head < 0.05 ? 6 : to_head < 0.15 ? 7 : 8][stage] += w;
    }
    std::printf("seed %llu done\n", static_cast<unsigned long long>(seed));
  }
  std::printf("OverlapLoss by stage, %s, seeds %llu-%llu: share of true length (trunk and canes) "
              "by the first stage where lost (MatchLoss stages)\n",
              images ? "images" : "labels", static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1));
  std::printf("  %-30s %7s", "", "length");
  for (int s = kLossForeground; s < kLossStageCount; ++s) std::printf(" %6s", names[s]);
  std::printf("\n");
  for (int r = 0; r < kRowCount; ++r) {
    double sum = 0.0;
    for (int s = kLossForeground; s < kLossStageCount; ++s) sum += table[r][s];
    std::printf("  %-30s %7.3f", rows[r], sum / total);
    for (int s = kLossForeground; s < kLossStageCount; ++s)
      std::printf(" %6.3f", table[r][s] / total);
    std::printf("\n");
  }
  std::printf("  raw column of the second row: no crossing of the pair's segments within 10 mm "
              "%.3f; only runs under min_hits, a segment that short %.3f; only short runs, both "
              "segments long (run broke) %.3f\n", raw_cause[0] / total, raw_cause[1] / total,
              raw_cause[2] / total);
  std::printf("  thr column of the second row: best fitted probability near < 0.05 %.3f, "
              "0.05-0.15 %.3f, above %.3f\n", probable_band[0] / total, probable_band[1] / total,
              probable_band[2] / total);
  std::printf("  best multi-view candidate near: feature, mean for bundle samples lost at the "
              "threshold / kept samples along nothing, weight x difference\n");
  for (size_t f = 0; f < weights.size(); ++f) {
    const double lost = feature_sum[0][f] / std::max(1e-9, feature_weight[0]);
    const double kept = feature_sum[1][f] / std::max(1e-9, feature_weight[1]);
    std::printf("    f%-2zu %8.3f %8.3f %+8.3f\n", f, lost, kept, weights[f] * (lost - kept));
  }
  EXPECT_GT(total, 0.0);
}

// Vineyard `seed`'s vine 1 seen through `rig`, for the reports from geometry alone: no images,
// the drawn canes the vine's and its neighbours'.
SimulatedStop GeometryStop(uint64_t seed, const RigCalibration& rig) {
  SimulatedStop stop;
  stop.scene = sim::GenerateScene(seed, 1).value();
  stop.drawn = stop.scene.vine;
  for (const VineModel& neighbour : stop.scene.neighbours)
    for (const Cane& cane : neighbour.canes) stop.drawn.canes.push_back(cane);
  stop.true_rig = rig;
  return stop;
}

// From geometry alone (no rendering), per rig: the share of the vine's true length (trunk and
// canes, 5 mm samples, vine 1 of each stop) inside two or more images, and of it the share
// lying along another cane (this vine's or a neighbour's; LyingAlongAnother, 2 px) in every view
// that sees it, in two or more of them, and the share with at least two views where it lies
// along nothing (a clean pair). Rigs from VB_RIGS, `;`-separated, each
// `side,apex_raise,apex_aim_up` (RigOptions baseline_m, apex_raise_m, apex_aim_up_m), or
// `side,apex_raise,apex_aim_up,cameras,upper_side` (also camera_count, upper_pair_side_m); the
// default lists the default rig and taller triangles. Stops: VB_SEED (1300), VB_STOPS (20).
//   VB_RIGS='0.4,0,0.03;0.4,0.2,0.1' vb_reconstruct_test --gtest_also_run_disabled_tests
//     --gtest_filter='OverlapLoss.DISABLED_RigGeometry'
TEST(OverlapLoss, DISABLED_RigGeometry) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20);
  const char* env = std::getenv("VB_RIGS");
  const std::string rigs = env ? env : "0.4,0,0.03;0.4,0.1,0.06;0.4,0.2,0.1;0.4,0.3,0.14";
  std::printf("%-20s %8s %8s %8s %8s\n", "side,raise,aim", "in>=2", "along_all", "along>=2",
              "clean2");
  for (const std::string& spec : std::vector<std::string>(absl::StrSplit(rigs, ';'))) {
    const std::vector<std::string> f = absl::StrSplit(spec, ',');
    ASSERT_TRUE(f.size() == 3u || f.size() == 5u) << spec;
    sim::RigOptions o;
    ASSERT_TRUE(absl::SimpleAtod(f[0], &o.baseline_m) &&
                absl::SimpleAtod(f[1], &o.apex_raise_m) &&
                absl::SimpleAtod(f[2], &o.apex_aim_up_m))
        << spec;
    if (f.size() == 5u) {
      ASSERT_TRUE(absl::SimpleAtoi(f[3], &o.camera_count) &&
                  absl::SimpleAtod(f[4], &o.upper_pair_side_m))
          << spec;
    }
    double total = 0.0, seen = 0.0, along_all = 0.0, along_two = 0.0, clean = 0.0;
    for (int k = 0; k < count; ++k) {
      const SimulatedStop stop = GeometryStop(first + k, sim::MakeRig(o).value());
      for (const LengthSample& s : SampleTrueLength(stop, kStepM, true)) {
        total += s.weight_m;
        if (s.in_image < 2) continue;
        seen += s.weight_m;
        if (s.along == s.in_image) along_all += s.weight_m;
        if (s.along >= 2) along_two += s.weight_m;
        if (s.in_image - s.along >= 2) clean += s.weight_m;
      }
    }
    ASSERT_GT(total, 0.0);
    std::printf("%-20s %8.4f %8.4f %8.4f %8.4f\n", spec.c_str(), seen / total,
                along_all / total, along_two / total, clean / total);
  }
}


// A copy of `like`'s intrinsics named `name`, centred at `centre` (platform frame) and looking at
// `aim` (sim::LookAlong, as sim::MakeRig aims its cameras).
CameraCalibration CameraAt(const CameraCalibration& like, const std::string& name,
                           const Eigen::Vector3d& centre, const Eigen::Vector3d& aim) {
  CameraCalibration c = like;
  c.name = name;
  c.rotation_camera_from_platform = sim::LookAlong(aim - centre);
  c.translation_camera_from_platform = -c.rotation_camera_from_platform * centre;
  return c;
}

// From geometry alone: what one more camera anywhere would show. Each entry of VB_EXTRA
// (`;`-separated `x,y,z,aim_x,aim_y,aim_z`, platform frame, metres) adds a camera with cam2's
// intrinsics at (x, y, z) looking at the aim point to the default triangle, and prints the share
// of the vine's true length inside two or more images, lying along another cane in every view
// that sees it (and of that, with no other drawn cane, the vine's or a neighbour's, within 10 mm
// and within 20 mm in 3D: length one model cane along the shared strand could not recall
// together with the other), and with a clean pair of views, as DISABLED_RigGeometry. The
// arm base and the platform's structure are not checked. Stops: VB_SEED (1300), VB_STOPS (20).
TEST(OverlapLoss, DISABLED_ExtraCamera) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20);
  const char* env = std::getenv("VB_EXTRA");
  const std::string extras = env ? env : "none";
  std::printf("%-32s %8s %8s %8s %8s %8s\n", "extra camera (centre, aim)", "in>=2",
              "along_all", "far10", "far20", "clean2");
  for (const std::string& spec : std::vector<std::string>(absl::StrSplit(extras, ';'))) {
    std::vector<double> v;
    if (spec != "none") {
      for (const std::string& f : std::vector<std::string>(absl::StrSplit(spec, ','))) {
        double x = 0.0;
        ASSERT_TRUE(absl::SimpleAtod(f, &x)) << spec;
        v.push_back(x);
      }
      ASSERT_EQ(v.size(), 6u) << spec;
    }
    double total = 0.0, seen = 0.0, along_all = 0.0, all_far = 0.0, all_far20 = 0.0, clean = 0.0;
    for (int k = 0; k < count; ++k) {
      RigCalibration rig = sim::MakeRig().value();
      if (!v.empty()) {
        rig.cameras.push_back(
            CameraAt(rig.cameras[2], "cam3", {v[0], v[1], v[2]}, {v[3], v[4], v[5]}));
      }
      const SimulatedStop stop = GeometryStop(first + k, rig);
      for (const LengthSample& s : SampleTrueLength(stop, kStepM, true)) {
        total += s.weight_m;
        if (s.in_image < 2) continue;
        seen += s.weight_m;
        if (s.along == s.in_image) {
          along_all += s.weight_m;
          const double other = NearestOtherCane(stop.drawn, s.cane, s.p);
          if (other >= 0.01) all_far += s.weight_m;
          if (other >= 0.02) all_far20 += s.weight_m;
        }
        if (s.in_image - s.along >= 2) clean += s.weight_m;
      }
    }
    ASSERT_GT(total, 0.0);
    std::printf("%-32s %8.4f %8.4f %8.4f %8.4f %8.4f\n", spec.c_str(), seen / total,
                along_all / total, all_far / total, all_far20 / total, clean / total);
  }
}

}  // namespace
}  // namespace vb::reconstruct
