// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: the first centimetres of the canes of the head (true parent the
// trunk/head), on rendered stops as the bench renders them (fiducials included) and run through
// ReconstructFromViews with the options from the environment. Per true cane of the head:
//  - where (arc length from its true base) the final model first covers it (a model cane within
//    10 mm), in bins;
//  - where it leaves the model head's spheres and the thick region of two or more views (the last
//    sample of its first 15 cm inside);
//  - per sample of the uncovered first stretch, by distance from the true base: what the views
//    show (in >= 2 images; foreground, skeleton within 3 px, thick region in >= 2 and >= 1 views;
//    inside the model head's spheres);
// and why growth (grow.h) stopped at the assembled ends lying within 15 cm of the model head, and
// the refined metrics and the head-bases stage's summary (head_bases.h).
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 [VB_BASES=1 VB_BASES_REACH=0.12 VB_BASES_THICK=2
//   VB_BASES_INSIDE=0.03 VB_BASES_COS=0.5 VB_BASES_LENGTH=0.12 VB_BASES_OFFSET=0.001
//   VB_BASES_TURN=45 VB_BASES_WOOD=3 VB_BASES_CURVE=0
//   VB_BASES_SKELETON=0 VB_BASES_CSV=path] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='HeadBases.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/head_bases.h"
#include "workers/reconstruct/join_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

double SurfaceDistance(const HeadModel& head, const Eigen::Vector3d& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const Sphere& s : head.spheres) d = std::min(d, (p - s.center).norm() - s.radius);
  return d;
}

constexpr int kCoverBins = 8;
const double kCoverUpper[kCoverBins] = {0.01, 0.02, 0.03, 0.05, 0.10, 0.15, 1e9, 2e9};
const char* kCoverNames[kCoverBins] = {"< 1 cm", "1-2 cm", "2-3 cm", "3-5 cm", "5-10 cm",
                                       "10-15 cm", ">= 15 cm", "never"};
int CoverBin(double s) {
  for (int b = 0; b < kCoverBins; ++b)
    if (s < kCoverUpper[b]) return b;
  return kCoverBins - 1;
}

constexpr int kStretchBins = 4;
const double kStretchUpper[kStretchBins] = {0.01, 0.03, 0.05, 0.15};
const char* kStretchNames[kStretchBins] = {"0-1 cm", "1-3 cm", "3-5 cm", "5-15 cm"};

struct StretchTally {
  int samples = 0, images2 = 0, foreground2 = 0, skeleton2 = 0, thick2 = 0, thick1 = 0,
      inside_head = 0;
};

// Per point of every tried end's course: where it lies against the end's own true cane (the
// true cane nearest the end; its polyline starts at its base): arc length and distance of its
// projection, whether the projection is the base itself (the point lies past the base), the
// distance to the nearest other true cane.
void WriteExtensions(std::FILE* csv, uint64_t seed, const VineModel& truth,
                     const HeadBasesSummary& bases) {
  for (size_t e = 0; e < bases.extensions.size(); ++e) {
    const HeadBaseExtension& x = bases.extensions[e];
    int own = -1;
    double own_d = std::numeric_limits<double>::infinity(), own_s = 0.0;
    for (size_t g = 0; g < truth.canes.size(); ++g) {
      double d = 0.0;
      const double s = truth.canes[g].polyline.Project(x.end, &d);
      if (d < own_d) own_d = d, own_s = s, own = int(g);
    }
    if (own < 0) continue;
    const Polyline3& line = truth.canes[own].polyline;
    const bool own_head = truth.canes[own].kind == CaneKind::kCane && TrueParent(truth, own) == 0;
    Eigen::Vector3d previous = x.end;
    for (size_t k = 0; k < x.points.size(); ++k) {
      const Eigen::Vector3d& p = x.points[k];
      double d = 0.0;
      const double s = line.Project(p, &d);
      double other = std::numeric_limits<double>::infinity();
      for (size_t g = 0; g < truth.canes.size(); ++g) {
        if (int(g) == own) continue;
        double dg = 0.0;
        truth.canes[g].polyline.Project(p, &dg);
        other = std::min(other, dg);
      }
      std::fprintf(csv, "%llu,%zu,%d,%.4f,%.1f,%.4f,%.4f,%d,%zu,%.4f,%.4f,%d,%.4f,%.4f,%.4f,%d,"
                        "%.4f,%.4f,%d,%.2f,%d\n",
                   static_cast<unsigned long long>(seed), e, int(x.stop), x.end_distance_m,
                   x.bend_deg, own_d, own_s, own_head ? 1 : 0, k,
                   (p - previous).norm(), x.inside_m[k], x.thick_views[k], x.other_cane_m[k], s,
                   d, s < 1e-4 ? 1 : 0, other, line.Length(), x.correcting_views[k],
                   x.skeleton_px[k], x.on_skeleton_views[k]);
      previous = p;
    }
  }
}

const char* kStopNames[] = {"end unsupported", "unsupported", "contradicted", "alongside",
                            "thick", "turned", "outside", "capped"};

TEST(HeadBases, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  ReconstructOptions options;
  OverrideFromEnv("VB_BASES", &options.head_bases.enabled);
  OverrideFromEnv("VB_BASES_REACH", &options.head_bases.reach_m);
  OverrideFromEnv("VB_BASES_THICK", &options.head_bases.min_thick_views);
  OverrideFromEnv("VB_BASES_INSIDE", &options.head_bases.max_inside_m);
  OverrideFromEnv("VB_BASES_COS", &options.head_bases.min_cos);
  OverrideFromEnv("VB_BASES_LENGTH", &options.head_bases.max_length_m);
  OverrideFromEnv("VB_BASES_OFFSET", &options.head_bases.max_offset_m);
  OverrideFromEnv("VB_BASES_TURN", &options.head_bases.max_turn_deg);
  OverrideFromEnv("VB_BASES_WOOD", &options.head_bases.wood_px);
  OverrideFromEnv("VB_BASES_CURVE", &options.head_bases.curve_gain);
  OverrideFromEnv("VB_BASES_SKELETON", &options.head_bases.max_skeleton_px);
  // VB_BASES_CSV=path: one row per point every tried end's course reached (WriteExtensions).
  const char* csv_path = std::getenv("VB_BASES_CSV");
  std::FILE* csv = csv_path != nullptr ? std::fopen(csv_path, "w") : nullptr;
  if (csv != nullptr) {
    std::fprintf(csv, "seed,ext,stop,end_dist,bend,end_own_d,end_own_s,own_head,k,seg,inside,"
                      "thick,other_model,own_s,own_d,past_base,other_true_d,own_len,corr,"
                      "skel_px,on_skel\n");
  }
  int cover[kCoverBins] = {}, hull_exit[kCoverBins] = {}, thick_exit[kCoverBins] = {};
  StretchTally stretch[kStretchBins];
  int canes = 0, grow_stops[8] = {};
  double cover_minus_hull = 0.0, cover_minus_thick = 0.0;
  int both = 0;
  double recall = 0, precision = 0, connectivity = 0, missed_m = 0;
  HeadBasesSummary bases;
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty()) << seed;
    const auto result =
        ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const VineModel& truth = stop.scene.vine;
    const VineModel& model = result->model;
    const auto m = EvaluateReconstruction(model, truth).value();
    recall += m.cane_recall / count;
    precision += m.cane_precision / count;
    connectivity += m.connectivity / count;
    bases.ends_tried += result->head_bases.ends_tried;
    bases.ends_extended += result->head_bases.ends_extended;
    bases.reached_thick += result->head_bases.reached_thick;
    bases.reached_inside += result->head_bases.reached_inside;
    bases.no_wood += result->head_bases.no_wood;
    bases.turned += result->head_bases.turned;
    bases.too_long += result->head_bases.too_long;
    bases.outside_images += result->head_bases.outside_images;
    bases.off_skeleton += result->head_bases.off_skeleton;
    bases.added_length_m += result->head_bases.added_length_m;
    if (csv != nullptr) WriteExtensions(csv, seed, truth, result->head_bases);
    for (const GrowEnd& e : result->grow.ends) {
      if (SurfaceDistance(model.head, e.stop_point) < 0.15) ++grow_stops[int(e.stop)];
    }
    std::vector<Cane> model_canes;
    for (const Cane& c : model.canes)
      if (c.kind == CaneKind::kCane) model_canes.push_back(c);
    const SegmentMaps maps(stop.views);
    for (size_t g = 0; g < truth.canes.size(); ++g) {
      if (truth.canes[g].kind != CaneKind::kCane || TrueParent(truth, int(g)) != 0) continue;
      ++canes;
      const Polyline3& line = truth.canes[g].polyline;
      double s_cover = 2e9 - 1, s_hull = -1, s_thick = -1;
      const double length = line.Length();
      for (double s = 0.0; s <= length; s += 0.005) {
        const Eigen::Vector3d p = line.PointAt(s);
        if (DistanceToCanes(p, model_canes) <= 0.01) {
          s_cover = s;
          break;
        }
      }
      for (double s = 0.0; s <= std::min(length, 0.15); s += 0.005) {
        const Eigen::Vector3d p = line.PointAt(s);
        const SampleInViews at = LocateSample(p, stop.true_rig, stop.views, maps);
        int thick = 0;
        for (size_t v = 0; v < stop.views.size(); ++v) {
          if (!at.inside[v]) continue;
          const View2D& view = stop.views[v];
          const int x = int(std::lround(at.px[v].x())), y = int(std::lround(at.px[v].y()));
          if (x < 0 || y < 0 || x >= view.width || y >= view.height) continue;
          if (view.thick_mask[size_t(y) * view.width + x]) ++thick;
        }
        const bool inside = SurfaceDistance(model.head, p) < 0.0;
        if (inside) s_hull = s;
        if (thick >= 2) s_thick = s;
        if (s >= s_cover) continue;
        int b = 0;
        while (b < kStretchBins - 1 && s >= kStretchUpper[b]) ++b;
        StretchTally& t = stretch[b];
        ++t.samples;
        missed_m += 0.005;
        t.images2 += at.in_image >= 2;
        t.foreground2 += at.foreground >= 2;
        t.skeleton2 += at.skeleton >= 2;
        t.thick2 += thick >= 2;
        t.thick1 += thick >= 1;
        t.inside_head += inside;
      }
      ++cover[CoverBin(s_cover)];
      ++hull_exit[s_hull < 0 ? kCoverBins - 1 : CoverBin(s_hull)];
      ++thick_exit[s_thick < 0 ? kCoverBins - 1 : CoverBin(s_thick)];
      if (s_cover < 1e9) {
        ++both;
        cover_minus_hull += s_cover - std::max(0.0, s_hull);
        cover_minus_thick += s_cover - std::max(0.0, s_thick);
      }
    }
  }
  std::printf("%d stops from %llu (%s); head bases %s\n", count,
              static_cast<unsigned long long>(first), images ? "images" : "labels",
              options.head_bases.enabled ? "on" : "off");
  std::printf("final recall %.4f precision %.4f connectivity %.4f\n", recall, precision,
              connectivity);
  std::printf("head bases: tried %d extended %d (thick %d inside %d) dropped: no wood %d turned "
              "%d too long %d outside images %d off skeleton %d; added %.2f m\n",
              bases.ends_tried, bases.ends_extended, bases.reached_thick, bases.reached_inside,
              bases.no_wood, bases.turned, bases.too_long, bases.outside_images,
              bases.off_skeleton, bases.added_length_m);
  std::printf("%d true canes of the head; uncovered first stretch %.2f m (%.3f m per cane)\n",
              canes, missed_m, missed_m / std::max(1, canes));
  std::printf("  %-9s | first covered | last inside model head | last thick in >= 2 views\n",
              "from base");
  for (int b = 0; b < kCoverBins; ++b)
    std::printf("  %-9s | %13d | %22d | %d\n", kCoverNames[b], cover[b], hull_exit[b],
                thick_exit[b]);
  std::printf("  mean (first covered - last inside head) %.3f m, (first covered - last thick>=2) "
              "%.3f m over %d covered canes\n", cover_minus_hull / std::max(1, both),
              cover_minus_thick / std::max(1, both), both);
  std::printf("uncovered samples by distance from the true base: fractions of the samples\n");
  std::printf("  %-8s | samples | in>=2 images | fg>=2 | skel>=2 | thick>=2 | thick>=1 | in "
              "model head\n", "");
  for (int b = 0; b < kStretchBins; ++b) {
    const StretchTally& t = stretch[b];
    const double n = std::max(1, t.samples);
    std::printf("  %-8s | %7d | %12.3f | %5.3f | %7.3f | %8.3f | %8.3f | %.3f\n", kStretchNames[b],
                t.samples, t.images2 / n, t.foreground2 / n, t.skeleton2 / n, t.thick2 / n,
                t.thick1 / n, t.inside_head / n);
  }
  if (csv != nullptr) std::fclose(csv);
  std::printf("growth stops of ends within 15 cm of the model head:");
  for (int i = 0; i < 8; ++i) std::printf(" %s %d;", kStopNames[i], grow_stops[i]);
  std::printf("\n");
}

}  // namespace
}  // namespace vb::reconstruct
