// SPDX-License-Identifier: Apache-2.0
// Diagnosis tools, not tests (docs/diagnosis.md, "LostWhere"): where the length the final model
// does not recall lies, and pictures of it.
// - LostWhere.DISABLED_Report: every 5 mm sample of the vine's trunk and canes inside two or more
//   images that the final model does not recall (no model cane within 10 mm), split by distance
//   to the nearest wire, by the run of lost samples it is in (its length; the whole cane, at the
//   base, at the tip or between recalled stretches, and for the last whether the recalling model
//   canes on either side are one and whether the chord between them would recall it), by kind and
//   by the views where it lies along another cane of the vine.
// - LostWhere.DISABLED_Bridges: chords between the ends of two model canes that point at each
//   other (VB_BRIDGE_MAX, VB_BRIDGE_DEG): how much of them lies on true wood, what they recall.
// - LostWhere.DISABLED_Overlay and DISABLED_StageOverlay: one stop (VB_SEED) drawn per view as a
//   PPM under VB_OUT_DIR: recalled and lost samples over the classes, skeleton and model, or the
//   samples coloured by the first stage where they are lost (FirstLostStage).
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='LostWhere.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// The band of p's distance to the nearest wire of `vine`: under 2 cm, 2-5, 5-15, 15 cm or more.
int WireBand(const VineModel& vine, const Eigen::Vector3d& p) {
  double to_wire = 1e9;
  for (const Wire& w : vine.wires)
    for (size_t t = 1; t < w.points.size(); ++t)
      to_wire = std::min(to_wire, PointSegmentDistance(p, w.points[t - 1], w.points[t]));
  return to_wire < 0.02 ? 0 : to_wire < 0.05 ? 1 : to_wire < 0.15 ? 2 : 3;
}

TEST(LostWhere, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10);
  const ReconstructOptions options;
  double total = 0.0, inside = 0.0, lost = 0.0;
  double between_kind[2][2][4] = {};
  double by_wire[4] = {}, by_run[4][4] = {}, by_kind[2] = {}, by_along[4] = {};
  double wire_run[4][4] = {}, wire_total[4][2] = {}, wire_lost[4][2] = {};
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const VineModel& vine = stop.scene.vine;
    std::map<size_t, std::vector<LengthSample>> by_cane;
    for (const LengthSample& s : SampleTrueLength(stop, 0.005, true)) by_cane[s.cane].push_back(s);
    for (auto& [cane, samples] : by_cane) {
      std::sort(samples.begin(), samples.end(),
                [](const LengthSample& a, const LengthSample& b) { return a.index < b.index; });
      const size_t n = samples.size();
      std::vector<char> hit(n, 0);
      std::vector<int> by(n, -1);         // the nearest model cane, where within 10 mm
      std::vector<Eigen::Vector3d> at(n); // ... and its nearest point
      std::vector<int> wire_band(n, 0);   // WireBand of each sample inside 2+ images
      bool any = false;
      for (size_t i = 0; i < n; ++i) {
        hit[i] = DistanceToCanes(samples[i].p, result->model.canes, &at[i], &by[i]) <= 0.01;
        any = any || hit[i];
        if (samples[i].in_image >= 2) wire_band[i] = WireBand(vine, samples[i].p);
      }
      // Runs of lost samples: length and position.
      size_t i = 0;
      while (i < n) {
        if (hit[i]) { ++i; continue; }
        size_t j = i;
        double run_m = 0.0;
        while (j < n && !hit[j]) run_m += samples[j++].weight_m;
        // position: 0 whole cane, 1 at the base, 2 at the tip, 3 between
        const int pos = !any ? 0 : i == 0 ? 1 : j == n ? 2 : 3;
        const int len = run_m < 0.05 ? 0 : run_m < 0.15 ? 1 : run_m < 0.4 ? 2 : 3;
        if (pos == 3) {
          // Flanked: the same model cane on both sides? would the chord between the model's
          // flanking points recall the lost samples?
          const bool same = by[i - 1] == by[j];
          for (size_t q = i; q < j; ++q) {
            if (samples[q].in_image < 2) continue;
            const bool chord = PointSegmentDistance(samples[q].p, at[i - 1], at[j]) <= 0.01;
            between_kind[same ? 1 : 0][chord ? 1 : 0][len] += samples[q].weight_m;
          }
        }
        for (size_t q = i; q < j; ++q) {
          const LengthSample& s = samples[q];
          if (s.in_image < 2) continue;
          const int wb = wire_band[q];
          by_wire[wb] += s.weight_m;
          by_run[pos][len] += s.weight_m;
          wire_run[wb][pos] += s.weight_m;
          by_kind[vine.canes[cane].kind == CaneKind::kTrunk ? 0 : 1] += s.weight_m;
          by_along[std::min(s.along_own, 3)] += s.weight_m;
          lost += s.weight_m;
        }
        i = j;
      }
      for (size_t q = 0; q < n; ++q) {
        const LengthSample& s = samples[q];
        total += s.weight_m;
        if (s.in_image < 2) continue;
        inside += s.weight_m;
        const int wb = wire_band[q];
        const int dir = std::abs(s.tangent.x()) > 0.9 ? 1 : 0;
        wire_total[wb][dir] += s.weight_m;
        if (!hit[q]) wire_lost[wb][dir] += s.weight_m;
      }
    }
    std::printf("seed %llu done\n", static_cast<unsigned long long>(first + k));
  }
  std::printf("LostWhere seeds %llu-%llu: shares of true length; inside 2+ images %.3f, lost "
              "there %.3f\n", static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), inside / total, lost / total);
  std::printf("  by wire distance <2cm %.3f 2-5cm %.3f 5-15cm %.3f >=15cm %.3f\n",
              by_wire[0] / total, by_wire[1] / total, by_wire[2] / total, by_wire[3] / total);
  std::printf("  by kind trunk %.3f cane %.3f\n", by_kind[0] / total, by_kind[1] / total);
  std::printf("  by views along own 0 %.3f 1 %.3f 2 %.3f 3 %.3f\n", by_along[0] / total,
              by_along[1] / total, by_along[2] / total, by_along[3] / total);
  const char* pos[4] = {"whole cane", "at the base", "at the tip", "between"};
  std::printf("  run length:        <5cm   5-15cm  15-40cm  >=40cm\n");
  for (int p = 0; p < 4; ++p)
    std::printf("  %-12s %8.3f %8.3f %8.3f %8.3f\n", pos[p], by_run[p][0] / total,
                by_run[p][1] / total, by_run[p][2] / total, by_run[p][3] / total);
  std::printf("  by wire distance and run position: whole  base  tip  between\n");
  const char* wn[4] = {"<2cm", "2-5cm", "5-15cm", ">=15cm"};
  for (int w = 0; w < 4; ++w)
    std::printf("  %-8s %8.3f %8.3f %8.3f %8.3f\n", wn[w], wire_run[w][0] / total,
                wire_run[w][1] / total, wire_run[w][2] / total, wire_run[w][3] / total);
  std::printf("  between runs: flanking model canes same/different, chord within 10 mm, by run "
              "length <5, 5-15, 15-40, >=40 cm\n");
  for (int sm = 0; sm < 2; ++sm)
    for (int ch = 0; ch < 2; ++ch)
      std::printf("  %s, chord %s: %.3f %.3f %.3f %.3f\n", sm ? "same" : "different",
                  ch ? "recalls" : "misses", between_kind[sm][ch][0] / total,
                  between_kind[sm][ch][1] / total, between_kind[sm][ch][2] / total,
                  between_kind[sm][ch][3] / total);
  std::printf("  by wire band and direction (along x within 25 deg / not): length, lost\n");
  for (int w = 0; w < 4; ++w)
    std::printf("  %-8s along x %.3f lost %.3f | other %.3f lost %.3f\n", wn[w],
                wire_total[w][1] / total, wire_lost[w][1] / total, wire_total[w][0] / total,
                wire_lost[w][0] / total);
  EXPECT_GT(total, 0.0);
}

// Bridges between model cane ends: every pair of ends of two different model canes within
// VB_BRIDGE_MAX (0.4 m) whose chord leaves each end within VB_BRIDGE_DEG (25) of its outward
// tangent; each end used once (shortest gap first). Reports the bridges' length, the share of it
// within 10 mm of a true cane of the vine or a neighbour, and the true length they would add to
// recall, by gap band.
TEST(LostWhere, DISABLED_Bridges) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10);
  const ReconstructOptions options;
  double max_gap = 0.4, max_deg = 25.0;
  OverrideFromEnv("VB_BRIDGE_MAX", &max_gap);
  OverrideFromEnv("VB_BRIDGE_DEG", &max_deg);
  const double cos_max = std::cos(max_deg * M_PI / 180.0);
  const double edges[4] = {0.02, 0.05, 0.15, 1e9};
  double total = 0.0, bridge_len[4] = {}, bridge_right[4] = {}, gained[4] = {};
  int bridges[4] = {};
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const std::vector<Cane>& canes = result->model.canes;
    struct End { int cane; Eigen::Vector3d p, out; };
    std::vector<End> ends;
    for (size_t c = 0; c < canes.size(); ++c) {
      if (canes[c].kind == CaneKind::kTrunk) continue;
      const Polyline3& pl = canes[c].polyline;
      const double len = pl.Length();
      if (len < 0.03) continue;
      ends.push_back({static_cast<int>(c), pl.points.front(), -pl.TangentAt(std::min(0.015, len))});
      ends.push_back(
          {static_cast<int>(c), pl.points.back(), pl.TangentAt(std::max(0.0, len - 0.015))});
    }
    struct Pair { double gap; int a, b; };
    std::vector<Pair> pairs;
    for (size_t a = 0; a < ends.size(); ++a)
      for (size_t b = a + 1; b < ends.size(); ++b) {
        if (ends[a].cane == ends[b].cane) continue;
        const Eigen::Vector3d d = ends[b].p - ends[a].p;
        const double gap = d.norm();
        if (gap < 0.005 || gap > max_gap) continue;
        const Eigen::Vector3d u = d / gap;
        if (ends[a].out.normalized().dot(u) < cos_max) continue;
        if (ends[b].out.normalized().dot(-u) < cos_max) continue;
        pairs.push_back({gap, static_cast<int>(a), static_cast<int>(b)});
      }
    std::sort(pairs.begin(), pairs.end(),
              [](const Pair& x, const Pair& y) { return x.gap < y.gap; });
    std::vector<char> used(ends.size(), 0);
    std::vector<std::pair<Polyline3, int>> chords;
    for (const Pair& pr : pairs) {
      if (used[pr.a] || used[pr.b]) continue;
      used[pr.a] = used[pr.b] = 1;
      Polyline3 chord;
      chord.points = {ends[pr.a].p, ends[pr.b].p};
      chord.radii = {0.003, 0.003};
      int band = 0;
      while (pr.gap >= edges[band]) ++band;
      chords.push_back({chord, band});
      ++bridges[band];
      for (const Eigen::Vector3d& q : chord.Sample(0.005)) {
        bridge_len[band] += 0.005;
        if (NearAnyCane(q, stop.drawn.canes)) bridge_right[band] += 0.005;
      }
    }
    for (const LengthSample& s : SampleTrueLength(stop, 0.005, false)) {
      total += s.weight_m;
      if (NearAnyCane(s.p, canes)) continue;
      for (const auto& [chord, band] : chords) {
        double d = 0.0;
        chord.Project(s.p, &d);
        if (d <= 0.01) { gained[band] += s.weight_m; break; }
      }
    }
  }
  std::printf("Bridges seeds %llu-%llu, max gap %.2f m, %.0f deg\n",
              static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), max_gap, max_deg);
  const char* names[4] = {"<2cm", "2-5cm", "5-15cm", ">=15cm"};
  for (int b = 0; b < 4; ++b)
    std::printf("  %-7s bridges %4d  length %.2f m/stop  right %.3f  recall gained %.4f\n",
                names[b], bridges[b], bridge_len[b] / count,
                bridge_len[b] > 0 ? bridge_right[b] / bridge_len[b] : 0.0, gained[b] / total);
  EXPECT_GT(total, 0.0);
}

// A picture of one view for the overlays: its classes (background dark, wood grey, wires blue,
// posts brown) and skeleton (light grey), drawn on by pixel, written as a binary PPM.
struct Canvas {
  int w = 0, h = 0;
  std::vector<uint8_t> rgb;

  explicit Canvas(const View2D& view)
      : w(view.width), h(view.height), rgb(static_cast<size_t>(w) * h * 3, 25) {
    const uint8_t wood[3] = {90, 90, 90}, wire[3] = {50, 50, 150}, post[3] = {110, 80, 50},
                  skeleton[3] = {190, 190, 190};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const PixelClass c = view.classes.at(x, y);
        if (c == PixelClass::kForeground) Put(x, y, wood);
        if (c == PixelClass::kWire) Put(x, y, wire);
        if (c == PixelClass::kPost) Put(x, y, post);
      }
    for (const Segment2D& seg : view.segments)
      for (const Eigen::Vector2d& q : seg.points) Put(q, skeleton);
  }
  void Put(int x, int y, const uint8_t* c) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    uint8_t* q = &rgb[(static_cast<size_t>(y) * w + x) * 3];
    q[0] = c[0];
    q[1] = c[1];
    q[2] = c[2];
  }
  void Put(const Eigen::Vector2d& px, const uint8_t* c) {
    Put(static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y())), c);
  }
  // Writes out/<name>_<seed>_v<view>.ppm and says so.
  void Write(const std::string& name, uint64_t seed, size_t view) const {
    const char* dir = std::getenv("VB_OUT_DIR");
    const std::string path = std::string(dir ? dir : "/tmp") + "/" + name + "_" +
                             std::to_string(seed) + "_v" + std::to_string(view) + ".ppm";
    FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr) << path;
    std::fprintf(f, "P6\n%d %d\n255\n", w, h);
    std::fwrite(rgb.data(), 1, rgb.size(), f);
    std::fclose(f);
    std::printf("wrote %s\n", path.c_str());
  }
};

// Overlays for one stop (VB_SEED): per view, lost_<seed>_v<view>.ppm under VB_OUT_DIR (/tmp): the
// Canvas, the model's canes (cyan) and the vine's true samples inside 2+ images, recalled (green)
// or lost (red).
TEST(LostWhere, DISABLED_Overlay) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 1);
  const SimulatedStop stop = MakeRenderedStop(first, images, fiducials);
  const auto result = ReconstructFromViews(stop.views, stop.rig, ReconstructOptions{},
                                           Deadline::Infinite());
  ASSERT_TRUE(result.ok()) << result.status();
  const std::vector<LengthSample> samples = SampleTrueLength(stop, 0.0025, false);
  const uint8_t model[3] = {0, 220, 220}, recalled[3] = {0, 200, 0}, lost[3] = {255, 0, 0};
  for (size_t v = 0; v < stop.views.size(); ++v) {
    Canvas canvas(stop.views[v]);
    const CameraCalibration& cam = stop.true_rig.cameras[v];
    for (const Cane& c : result->model.canes)
      for (const Eigen::Vector3d& p : c.polyline.Sample(0.002))
        if (const auto uv = cam.Project(p)) canvas.Put(*uv, model);
    for (const LengthSample& s : samples) {
      if (s.in_image < 2) continue;
      const auto uv = cam.Project(s.p);
      if (!uv) continue;
      if (NearAnyCane(s.p, result->model.canes)) {
        canvas.Put(*uv, recalled);
      } else {
        canvas.Put(*uv, lost);
        canvas.Put(*uv + Eigen::Vector2d(1, 0), lost);
      }
    }
    canvas.Write("lost", first, v);
  }
}

// The same stop's samples coloured by the first stage where they are lost (FirstLostStage, the
// pipeline run stage by stage as OverlapLoss.DISABLED_ByStage runs it): fg magenta, skeleton
// orange, pair yellow, raw red, fit pink, threshold blue, Gibbs purple, assembly brown,
// connection white, refinement grey, kept green, over the Canvas (stage_<seed>_v<view>.ppm).
TEST(LostWhere, DISABLED_StageOverlay) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 1);
  const ReconstructOptions options;
  const double threshold = 1.0 / (1.0 + options.correspondence.alpha);
  const auto run = RenderAndMatch(first, images, fiducials, options);
  ASSERT_TRUE(run.ok()) << run.status();
  const SimulatedStop& stop = run->stop;
  const RigCalibration& rig = run->matched.rig;
  const std::vector<View2D>& views = run->views();
  const CandidateOptions co = CandidateOptionsFor(options.correspondence, views.size() > 2);
  const std::vector<ViewSamples> samples =
      SampleViews(views, rig, options.correspondence.sample_step_px);
  const std::vector<MatchCandidate> raw = RawCandidates(samples, rig, co);
  const auto scored = ScoreCandidates(views, rig, options.correspondence, Deadline::Infinite());
  ASSERT_TRUE(scored.ok());
  const auto assembled = AssembleStop(views, rig, run->matched.pieces, options);
  ASSERT_TRUE(assembled.ok());
  const auto connected = ConnectAndRefine(views, rig, *assembled, assembled->joins, options);
  ASSERT_TRUE(connected.ok());
  const StageGrids grids =
      MakeStageGrids(raw, *scored, run->matched.pieces, *assembled, *connected);
  const SegmentMaps maps(views);
  const uint8_t colours[kLossStageCount][3] = {
      {0, 0, 0},     {255, 0, 255}, {255, 140, 0}, {255, 255, 0}, {255, 0, 0},   {255, 150, 180},
      {60, 120, 255}, {170, 60, 255}, {150, 90, 30}, {255, 255, 255}, {150, 150, 150}, {0, 200, 0}};
  double tally[kLossStageCount] = {}, total = 0.0;
  const std::vector<LengthSample> true_samples = SampleTrueLength(stop, 0.0025, false);
  std::vector<LossStage> stage(true_samples.size(), kLossInImage);
  for (size_t i = 0; i < true_samples.size(); ++i) {
    const LengthSample& ls = true_samples[i];
    const SampleInViews at = LocateSample(ls.p, stop.true_rig, views, maps);
    if (at.in_image < 2) continue;
    const SampleEvidence e = EvidenceOf(at, stop.true_rig, ls.p, ls.tangent, co.min_epipolar_sin);
    stage[i] = FirstLostStage(ls.p, e, grids, threshold);
    tally[stage[i]] += ls.weight_m;
    total += ls.weight_m;
  }
  const char* names[kLossStageCount] = {"in", "fg", "skel", "pair", "raw", "fit", "thr", "gibbs",
                                        "assem", "conn", "refine", "kept"};
  std::printf("seed %llu, share of the length inside 2+ images by first stage lost:",
              static_cast<unsigned long long>(first));
  for (int k = kLossForeground; k < kLossStageCount; ++k)
    std::printf(" %s %.3f", names[k], tally[k] / total);
  std::printf("\n");
  for (size_t v = 0; v < views.size(); ++v) {
    Canvas canvas(views[v]);
    const CameraCalibration& cam = stop.true_rig.cameras[v];
    for (size_t i = 0; i < true_samples.size(); ++i) {
      if (stage[i] == kLossInImage) continue;
      if (const auto uv = cam.Project(true_samples[i].p)) canvas.Put(*uv, colours[stage[i]]);
    }
    canvas.Write("stage", first, v);
  }
}

}  // namespace
}  // namespace vb::reconstruct
