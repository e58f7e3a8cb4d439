// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: how much larger than the true head the reconstructed head
// (head.h) is, and where the excess lies, on rendered stops as the bench renders them, with the
// head carved as ReconstructFromViews carves it (assembled and grown canes as depth hints). Per
// stop and in sum, for the head as configured, for each option of s18 and s19 alone (and some
// combinations) and for a variant (options from the environment):
//  - volume ratio (model / true head) and enclosed fraction, as the bench's metrics;
//  - the error of each face of the model head's bounding box against the true head's;
//  - the excess volume (model head outside the true head) split by where it lies, first class
//    that applies: below the true head's lowest point ("below"; within 2 cm of the true trunk's
//    axis plus its radius: "below, trunk"), beyond its x extent ("beside"), beyond its depth (y)
//    extent ("in depth"), within its bounding box ("in box": the silhouettes' inflation and
//    ambiguity);
//  - the true canes' length (not the trunk) inside the model head but outside the true head,
//    and the model head's volume within 10 mm of a true cane outside the true head;
//  - the base slide (s19), a proxy for the cut oracle "the truth with the model's head spheres
//    and the truth's scheme" (tests/cut_loss_diagnose_test.cc) that needs no decide stage: for
//    each true cane whose base lies within 1 cm of the true head's surface, how far beyond its
//    exit from the true head it first leaves the model head (capped at decide's 5 cm slide).
//    A cut at the base slid more than 30 mm is lost: the fraction of bases slid > 30 mm.
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='HeadHull.DISABLED_Report'
// Variant knobs (HeadOptions): VB_HEAD_MIN_CELL, VB_HEAD_MARGIN_PX, VB_HEAD_DEPTH_MARGIN,
// VB_HEAD_OVERLAP, VB_HEAD_DEPTH_FACTOR, VB_HEAD_PEEL (bool), VB_HEAD_PEEL_DEPTH_PX,
// VB_HEAD_PEEL_RADIUS, VB_HEAD_LEAF_FRACTION, VB_HEAD_CENTRE_ON_TRUNK (bool).
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/match_classifier.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

bool InSpheres(const Eigen::Vector3d& p, const std::vector<Sphere>& spheres) {
  for (const Sphere& s : spheres)
    if ((p - s.center).squaredNorm() <= s.radius * s.radius) return true;
  return false;
}

void Bounds(const std::vector<Sphere>& spheres, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(1e9);
  *hi = Eigen::Vector3d::Constant(-1e9);
  for (const Sphere& s : spheres) {
    *lo = lo->cwiseMin((s.center.array() - s.radius).matrix());
    *hi = hi->cwiseMax((s.center.array() + s.radius).matrix());
  }
}

enum Place { kBelowTrunk, kBelow, kBeside, kDepth, kBox, kPlaces };
const char* kPlaceNames[kPlaces] = {"below,trunk", "below", "beside", "in depth", "in box"};

struct Tally {
  int stops = 0;
  double ratio = 0, enclosed = 0, min_enclosed = 1.0;
  double true_volume = 0, model_volume = 0;
  double face_error[6] = {};  // lo x y z, hi x y z: model - truth, summed (mean later)
  double excess[kPlaces] = {};
  double cane_inside_m = 0, cane_near_volume = 0, true_cane_m = 0;
  int bases = 0, bases_slid_far = 0;  // head canes; those slid > 30 mm
  double base_slide_m = 0;            // summed
};

// How far along `cane` from where it leaves `truth` it first leaves `model`, capped at 5 cm
// (decide's max_head_slide_m); negative if its base lies more than 1 cm from truth's surface.
double BaseSlide(const Polyline3& cane, const std::vector<Sphere>& truth,
                 const std::vector<Sphere>& model) {
  const double cap = 0.05, step = 0.0025;
  double to_surface = 1e9;
  for (const Sphere& s : truth)
    to_surface = std::min(to_surface, (cane.PointAt(0.0) - s.center).norm() - s.radius);
  if (to_surface > 0.01) return -1.0;
  const double length = cane.Length();
  double exit = 0.0;
  while (exit < length && InSpheres(cane.PointAt(exit), truth)) exit += step;
  double s = exit;
  while (s < length && s - exit < cap && InSpheres(cane.PointAt(s), model)) s += step;
  return std::min(s - exit, cap);
}

void AddStop(uint64_t seed, const VineModel& truth, const HeadModel& head, bool verbose,
             Tally* t) {
  if (truth.head.spheres.empty() || head.spheres.empty()) return;
  VineModel model;
  model.head = head;
  VineModel true_head;
  true_head.head = truth.head;
  const ReconstructionMetrics m = EvaluateReconstruction(model, true_head).value();
  Eigen::Vector3d tlo, thi, mlo, mhi;
  Bounds(truth.head.spheres, &tlo, &thi);
  Bounds(head.spheres, &mlo, &mhi);
  const Polyline3* trunk = nullptr;
  std::vector<const Polyline3*> canes;
  for (const Cane& c : truth.canes) {
    if (c.kind == CaneKind::kTrunk && !trunk) trunk = &c.polyline;
    else canes.push_back(&c.polyline);
  }
  const double trunk_r = trunk && !trunk->radii.empty()
                             ? *std::max_element(trunk->radii.begin(), trunk->radii.end())
                             : 0.0;
  // Both heads rasterised on one 5 mm grid over the model head's box.
  const double h = 0.005;
  const Eigen::Vector3i n = ((mhi - mlo) / h).array().ceil().cast<int>().max(1);
  auto raster = [&](const std::vector<Sphere>& spheres) {
    std::vector<uint8_t> in(static_cast<size_t>(n.prod()), 0);
    for (const Sphere& s : spheres) {
      const Eigen::Vector3i a =
          ((s.center.array() - s.radius - mlo.array()) / h).floor().cast<int>().max(0);
      const Eigen::Vector3i b = ((s.center.array() + s.radius - mlo.array()) / h)
                                    .ceil()
                                    .cast<int>()
                                    .min(n.array() - 1);
      for (int k = a.z(); k <= b.z(); ++k)
        for (int j = a.y(); j <= b.y(); ++j)
          for (int i = a.x(); i <= b.x(); ++i) {
            const Eigen::Vector3d p = mlo + (Eigen::Vector3d(i, j, k).array() + 0.5).matrix() * h;
            if ((p - s.center).squaredNorm() <= s.radius * s.radius)
              in[(static_cast<size_t>(k) * n.y() + j) * n.x() + i] = 1;
          }
    }
    return in;
  };
  const std::vector<uint8_t> in_model = raster(head.spheres);
  const std::vector<uint8_t> in_truth = raster(truth.head.spheres);
  double excess[kPlaces] = {};
  double near_volume = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const size_t flat = (static_cast<size_t>(k) * n.y() + j) * n.x() + i;
        if (!in_model[flat] || in_truth[flat]) continue;
        const Eigen::Vector3d p = mlo + (Eigen::Vector3d(i, j, k).array() + 0.5).matrix() * h;
        Place place = kBox;
        if (p.z() < tlo.z()) {
          place = trunk && DistanceToPolyline(p, *trunk) < trunk_r + 0.02 ? kBelowTrunk : kBelow;
        } else if (p.x() < tlo.x() || p.x() > thi.x()) {
          place = kBeside;
        } else if (p.y() < tlo.y() || p.y() > thi.y()) {
          place = kDepth;
        }
        excess[place] += h * h * h;
        for (const Polyline3* c : canes) {
          if (DistanceToPolyline(p, *c) < 0.01) {
            near_volume += h * h * h;
            break;
          }
        }
      }
  double inside_m = 0, cane_m = 0;
  int bases = 0, slid_far = 0;
  double slide_m = 0;
  for (const Polyline3* c : canes) {
    const double slide = BaseSlide(*c, truth.head.spheres, head.spheres);
    if (slide >= 0) {
      ++bases;
      slide_m += slide;
      if (slide > 0.03) ++slid_far;
    }
    const double length = c->Length();
    cane_m += length;
    for (double s = 0.0025; s < length; s += 0.005) {
      const Eigen::Vector3d p = c->PointAt(s);
      if (InSpheres(p, head.spheres) && !InSpheres(p, truth.head.spheres)) inside_m += 0.005;
    }
  }
  ++t->stops;
  t->ratio += m.head_volume_ratio;
  t->enclosed += m.head_enclosed_fraction;
  t->min_enclosed = std::min(t->min_enclosed, m.head_enclosed_fraction);
  const double true_volume = SphereUnionVolume(truth.head.spheres, 0.002);
  t->true_volume += true_volume;
  t->model_volume += m.head_volume_ratio * true_volume;
  for (int a = 0; a < 3; ++a) {
    t->face_error[a] += mlo[a] - tlo[a];
    t->face_error[3 + a] += mhi[a] - thi[a];
  }
  for (int k = 0; k < kPlaces; ++k) t->excess[k] += excess[k];
  t->cane_inside_m += inside_m;
  t->cane_near_volume += near_volume;
  t->true_cane_m += cane_m;
  t->bases += bases;
  t->bases_slid_far += slid_far;
  t->base_slide_m += slide_m;
  if (verbose) {
    std::printf("  seed %llu: ratio %.2f enclosed %.4f; lo %+.3f %+.3f %+.3f hi %+.3f %+.3f %+.3f"
                "; excess (cm3) below,trunk %.0f below %.0f beside %.0f depth %.0f box %.0f; "
                "cane inside %.3f m; bases slid > 30 mm %d of %d\n",
                static_cast<unsigned long long>(seed), m.head_volume_ratio,
                m.head_enclosed_fraction, mlo.x() - tlo.x(), mlo.y() - tlo.y(),
                mlo.z() - tlo.z(), mhi.x() - thi.x(), mhi.y() - thi.y(), mhi.z() - thi.z(),
                excess[0] * 1e6, excess[1] * 1e6, excess[2] * 1e6, excess[3] * 1e6,
                excess[4] * 1e6, inside_m, slid_far, bases);
  }
}

void PrintTally(const char* title, const Tally& t) {
  const double n = std::max(1, t.stops);
  std::printf("== %s: %d stops; volume ratio mean %.2f (pooled %.2f); enclosed mean %.4f min "
              "%.4f\n", title, t.stops, t.ratio / n, t.model_volume / t.true_volume,
              t.enclosed / n, t.min_enclosed);
  std::printf("  face errors (model - truth, mean m): lo x %+.3f y %+.3f z %+.3f; hi x %+.3f y "
              "%+.3f z %+.3f\n", t.face_error[0] / n, t.face_error[1] / n, t.face_error[2] / n,
              t.face_error[3] / n, t.face_error[4] / n, t.face_error[5] / n);
  double total = 0;
  for (double e : t.excess) total += e;
  std::printf("  excess %.0f cm3 per stop (true head %.0f cm3):", total * 1e6 / n,
              t.true_volume * 1e6 / n);
  for (int k = 0; k < kPlaces; ++k)
    std::printf(" %s %.2f", kPlaceNames[k], t.excess[k] / std::max(total, 1e-12));
  std::printf("\n  true cane length inside the model head, outside the true head: %.3f m per "
              "stop (%.4f of true cane length); model head within 10 mm of true canes outside "
              "the true head: %.0f cm3 per stop\n", t.cane_inside_m / n,
              t.cane_inside_m / std::max(t.true_cane_m, 1e-9), t.cane_near_volume * 1e6 / n);
  std::printf("  base slide: %d head canes, slid > 30 mm %.3f, mean slide %.1f mm\n", t.bases,
              static_cast<double>(t.bases_slid_far) / std::max(1, t.bases),
              1000 * t.base_slide_m / std::max(1, t.bases));
}

TEST(HeadHull, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  ReconstructOptions options;
  HeadOptions variant = options.head;
  OverrideFromEnv("VB_HEAD_MIN_CELL", &variant.min_cell_m);
  OverrideFromEnv("VB_HEAD_MARGIN_PX", &variant.silhouette_margin_px);
  OverrideFromEnv("VB_HEAD_DEPTH_MARGIN", &variant.depth_margin_m);
  OverrideFromEnv("VB_HEAD_OVERLAP", &variant.head_overlap_m);
  OverrideFromEnv("VB_HEAD_DEPTH_FACTOR", &variant.head_depth_factor);
  OverrideFromEnv("VB_HEAD_PEEL", &variant.peel_canes);
  OverrideFromEnv("VB_HEAD_PEEL_DEPTH_PX", &variant.peel_depth_px);
  OverrideFromEnv("VB_HEAD_PEEL_RADIUS", &variant.peel_cane_radius_m);
  OverrideFromEnv("VB_HEAD_LEAF_FRACTION", &variant.leaf_radius_fraction);
  OverrideFromEnv("VB_HEAD_CENTRE_ON_TRUNK", &variant.head_centre_on_trunk);
  ASSERT_TRUE(variant.Validate().ok()) << variant.Validate();
  // The fixed variants, each option of s18 alone, then the environment's.
  std::vector<std::pair<std::string, HeadOptions>> variants = {{"as configured", options.head}};
  HeadOptions v = options.head;
  v.min_cell_m = 0.005;
  variants.push_back({"min_cell_m 0.005", v});
  v = options.head;
  v.peel_canes = true;
  variants.push_back({"peel_canes", v});
  v = options.head;
  v.head_depth_factor = 0.6;
  variants.push_back({"head_depth_factor 0.6", v});
  v = options.head;
  v.head_overlap_m = 0.02;
  variants.push_back({"head_overlap_m 0.02", v});
  // s19: tighter leaves, the head centred on the trunk, and their combinations with depth 0.6.
  for (double fraction : {0.5, 0.0}) {
    v = options.head;
    v.leaf_radius_fraction = fraction;
    variants.push_back({"leaf_radius_fraction " + std::to_string(fraction).substr(0, 3), v});
  }
  v = options.head;
  v.head_centre_on_trunk = true;
  variants.push_back({"head_centre_on_trunk", v});
  v.head_depth_factor = 0.6;
  variants.push_back({"head_centre_on_trunk, depth 0.6", v});
  v = options.head;
  v.leaf_radius_fraction = 0.5;
  v.head_depth_factor = 0.6;
  variants.push_back({"leaf 0.5, depth 0.6", v});
  variants.push_back({"environment's variant", variant});
  std::vector<Tally> tallies(variants.size());
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const auto rendered = RenderAndMatch(seed, images, fiducials, options);
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    const std::vector<View2D>& views = rendered->views();
    const RigCalibration& rig = rendered->matched.rig;
    const VineModel& truth = rendered->stop.scene.vine;
    const Deadline deadline = Deadline::Infinite();
    const auto grown = AssembleAndGrow(views, rig, rendered->matched.pieces, options);
    ASSERT_TRUE(grown.ok()) << grown.status();
    for (size_t i = 0; i < variants.size(); ++i) {
      const auto head = ReconstructHeadAndTrunk(views, rig, options.volume, variants[i].second,
                                                deadline, grown->hints);
      ASSERT_TRUE(head.ok());
      if (verbose) std::printf("%s\n", variants[i].first.c_str());
      AddStop(seed, truth, head->head, verbose, &tallies[i]);
    }
    std::fflush(stdout);
  }
  std::printf("%d stops from %llu (%s)\n", count, static_cast<unsigned long long>(first),
              images ? "images" : "labels");
  for (size_t i = 0; i < variants.size(); ++i) PrintTally(variants[i].first.c_str(), tallies[i]);
}

}  // namespace
}  // namespace vb::reconstruct
