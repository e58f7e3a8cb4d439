// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: the model's cane length farther than 10 mm from every true cane
// of the vine (cane precision's complement), by the stage that made it and by what it lies on
// (PrecisionLoss.DISABLED_Report). Run with
//   VB_SEED=1300 VB_STOPS=40 vb_reconstruct_test --gtest_also_run_disabled_tests
//     --gtest_filter='PrecisionLoss.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds"); knobs in docs/diagnosis.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/image_probes.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

// Over the views in whose image p projects: the largest distance (pixels) of the projection to
// the nearest skeleton point, and how many views that is.
std::pair<double, int> WorstResidual(const Eigen::Vector3d& p, const std::vector<View2D>& views,
                                     const RigCalibration& rig) {
  double worst = 0;
  int seen = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(p);
    if (!uv || !rig.cameras[v].InImage(*uv)) continue;
    worst = std::max(worst, CentrelineDistanceAt(views[v], *uv));
    ++seen;
  }
  return {worst, seen};
}

// How many views see p on background: inside the image, no foreground, wire or post pixel
// within 1.5 px (wires and posts may hide wood, so they neither support nor refute it).
int ViewsOnBackground(const Eigen::Vector3d& p, const std::vector<View2D>& views,
                      const RigCalibration& rig) {
  int n = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(p);
    if (!uv || !rig.cameras[v].InImage(*uv)) continue;
    n += !WoodNear(views[v], *uv, 1);
  }
  return n;
}

// Arc length along `trunk` (base first) of its first 5 mm sample inside two or more images. Not
// cane_fit's FirstSeenArc (cane_fit_trunk.cc), which refines the boundary between two samples:
// this report counts whole 5 mm samples below the first one seen.
double FirstSeenArc(const Polyline3& trunk, const RigCalibration& rig) {
  const double length = trunk.Length();
  for (double s = 0; s < length; s += 0.005) {
    int n = 0;
    for (const CameraCalibration& camera : rig.cameras) {
      const std::optional<Eigen::Vector2d> uv = camera.Project(trunk.PointAt(s));
      n += uv && camera.InImage(*uv);
    }
    if (n >= 2) return s;
  }
  return length;
}

std::vector<Polyline3> Lines(const std::vector<Cane>& canes) {
  std::vector<Polyline3> out;
  for (const Cane& c : canes) out.push_back(c.polyline);
  return out;
}

// The stage that made a false sample (first that holds, walking back from the final model):
enum Stage {
  kTrunk,        // the trunk (shape from silhouette, step 5)
  kRefinement,   // the cane before refinement was right here (drift in step 4b)
  kConnection,   // not on any assembled cane or trunk: drawn by step 6 (bases, seen gaps)
  kBridge,       // on an assembled cane but on no piece: assembly chained across a gap
  kFusion,       // on an assembled cane that lies off a right piece (averaging moved it)
  kPiece,        // the piece itself is wrong (correspondence, step 3)
  kStages
};
const char* kStageNames[kStages] = {"trunk (step 5)",         "refinement drift (4b)",
                                    "drawn by connection (6)", "assembly bridge (4a)",
                                    "assembly fusion (4a)",    "wrong piece (3)"};
// What the false sample lies on (first that holds).
enum Where {
  kNeighbour,   // within 10 mm of a neighbour's cane
  kNearTrunk,   // within 30 mm of the true trunk or head (a duplicate of them)
  kMisDepth,    // 10-30 mm from a true cane of the vine
  kWire,        // within 15 mm of a true wire
  kGhost,       // elsewhere
  kWheres
};
const char* kWhereNames[kWheres] = {"neighbour", "trunk/head", "10-30 mm", "wire", "ghost"};

// For every stop, the pipeline is run as ReconstructFromViews runs it (without the extension,
// off by default, and the trellis) and each false 5 mm sample of the final model is put in a
// stage (Stage) and a place (Where). Also: the share of false length on canes that are mostly
// false (whole ghosts) against stretches of mostly right canes, and of those stretches how much
// lies within 3 cm of a cane end; the mis-placed length's depth (|dy|) against the error across
// (x, z); per stop with VB_VERBOSE. Fractions of the model's cane length, summed over stops.
TEST(PrecisionLoss, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  ReconstructOptions options;
  if (const char* v = std::getenv("VB_TRUNK_MIN_VIEWS")) options.fit.trunk_min_views = std::atoi(v);
  if (const char* v = std::getenv("VB_TRUNK_KEEP")) options.fit.trunk_unseen_keep_m = std::atof(v);
  const Deadline deadline = Deadline::Infinite();
  double total = 0, table[kStages][kWheres] = {};
  double whole_false = 0, end_false = 0, interior_false = 0;
  double misdepth_m = 0, misdepth_dy = 0, misdepth_dxz = 0;
  // Model samples by their worst residual over the views (bins below), right and false, and
  // within 3 cm of the cane's tip (its last point) or elsewhere.
  constexpr int kBins = 6;
  // The trunk before refinement below its first point inside two images, by the distance below
  // it (5 cm bins; the last: 30 cm and more): right and false length.
  constexpr int kBelowBins = 7;
  double below_right[kBelowBins] = {}, below_false[kBelowBins] = {};
  const double kBinEdges[kBins] = {1, 2, 3, 5, 10, 1e9};
  double residual[2][2][kBins] = {};  // [false][at tip][bin]
  double background[2][2][3] = {};    // [false][at tip][views on background: 0, 1, 2+]
  // The model's trunk by height (0.1 m bins from z = 0; the last: 1.2 m and above): right
  // length, false length, false before refinement, false length in fewer than two images, and
  // the false samples' summed distance to the nearest true cane.
  constexpr int kZBins = 13;
  double trunk_right[kZBins] = {}, trunk_false[kZBins] = {}, trunk_false_before[kZBins] = {},
         trunk_unseen[kZBins] = {}, trunk_distance[kZBins] = {}, trunk_true[kZBins] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto matched = MatchWithRigRefinement(stop.views, stop.rig, options, deadline);
    ASSERT_TRUE(matched.ok()) << matched.status();
    const RigCalibration& rig = matched->rig;
    std::vector<Polyline3> pieces;
    for (const Piece3D& p : matched->pieces)
      if (p.probability >= options.assembly.min_piece_probability) pieces.push_back(p.polyline);
    auto canes = AssembleCanes(matched->pieces, options.assembly, deadline);
    ASSERT_TRUE(canes.ok()) << canes.status();
    std::erase_if(*canes, [&](const Polyline3& c) { return options.volume.MostlyOutside(c); });
    std::vector<Eigen::Vector3d> hints;
    for (const Polyline3& c : *canes) hints.insert(hints.end(), c.points.begin(), c.points.end());
    const auto head = ReconstructHeadAndTrunk(stop.views, rig, options.volume, options.head,
                                              deadline, hints);
    ASSERT_TRUE(head.ok()) << head.status();
    const GapSupportFn gap_support = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return GapSupport(a, b, stop.views, rig);
    };
    auto connected = ConnectCanes(*canes, head->trunk, head->head, options.connect, nullptr,
                                  gap_support);
    ASSERT_TRUE(connected.ok()) << connected.status();
    VineModel model = *connected;
    ASSERT_TRUE(RefineModel(&model, stop.views, rig, options.fit, deadline).ok());

    const VineModel& truth = stop.scene.vine;
    const std::vector<Polyline3> true_lines = Lines(truth.canes);
    std::vector<Polyline3> trunk_lines;
    for (const Cane& c : truth.canes)
      if (c.kind == CaneKind::kTrunk) trunk_lines.push_back(c.polyline);
    std::vector<Polyline3> neighbour_lines;
    for (const VineModel& n : stop.scene.neighbours)
      for (const Cane& c : n.canes) neighbour_lines.push_back(c.polyline);
    std::vector<Polyline3> assembled = *canes;
    if (head->trunk) assembled.push_back(*head->trunk);
    auto right = [&](const Eigen::Vector3d& p) {
      return DistanceToLines(p, true_lines) <= 0.010;
    };

    for (const Cane& c : truth.canes)
      if (c.kind == CaneKind::kTrunk)
        for (const Eigen::Vector3d& p : c.polyline.Sample(0.005))
          trunk_true[std::clamp(static_cast<int>(p.z() / 0.1), 0, kZBins - 1)] += 0.005;
    for (const Cane& c : connected->canes) {
      if (c.kind != CaneKind::kTrunk) continue;
      const double seen = FirstSeenArc(c.polyline, rig);
      const std::vector<double> arc = c.polyline.ArcLengths();
      for (double s = 0.0025; s < seen; s += 0.005) {
        const int bin = std::min(kBelowBins - 1, static_cast<int>((seen - s) / 0.05));
        (right(c.polyline.PointAt(s, arc)) ? below_right : below_false)[bin] += 0.005;
      }
    }
    double stop_total = 0, stop_false = 0, stop_stage[kStages] = {};
    for (const Cane& cane : model.canes) {
      const std::vector<Eigen::Vector3d> samples = cane.polyline.Sample(0.005);
      std::vector<bool> is_false(samples.size());
      int n_false = 0;
      for (size_t i = 0; i < samples.size(); ++i) n_false += (is_false[i] = !right(samples[i]));
      const bool mostly_false = 2 * n_false > static_cast<int>(samples.size());
      const double length = cane.polyline.Length();
      const std::vector<Polyline3> before = {
          connected->canes[*connected->IndexOf(cane.id)].polyline};
      for (size_t i = 0; i < samples.size(); ++i) {
        stop_total += 0.005;
        const Eigen::Vector3d& p = samples[i];
        const double s = length * i / std::max<size_t>(1, samples.size() - 1);
        if (cane.kind != CaneKind::kTrunk) {
          const double worst = WorstResidual(p, stop.views, rig).first;
          int bin = 0;
          while (worst > kBinEdges[bin]) ++bin;
          residual[is_false[i]][length - s <= 0.03][bin] += 0.005;
          background[is_false[i]][length - s <= 0.03]
                    [std::min(2, ViewsOnBackground(p, stop.views, rig))] += 0.005;
        }
        if (cane.kind == CaneKind::kTrunk && !is_false[i])
          trunk_right[std::clamp(static_cast<int>(p.z() / 0.1), 0, kZBins - 1)] += 0.005;
        if (!is_false[i]) continue;
        stop_false += 0.005;
        if (mostly_false) whole_false += 0.005;
        else if (std::min(s, length - s) <= 0.03) end_false += 0.005;
        else interior_false += 0.005;
        // Stage, walking back.
        Stage stage = kPiece;
        Eigen::Vector3d q = p, a = p;
        if (cane.kind == CaneKind::kTrunk) {
          stage = kTrunk;
          DistanceToLines(p, before, &q);
          const int z = std::clamp(static_cast<int>(p.z() / 0.1), 0, kZBins - 1);
          trunk_false[z] += 0.005;
          trunk_false_before[z] += right(q) ? 0 : 0.005;
          trunk_unseen[z] += WorstResidual(p, stop.views, rig).second < 2 ? 0.005 : 0;
          trunk_distance[z] += DistanceToLines(p, true_lines);
        } else {
          DistanceToLines(p, before, &q);
          if (right(q)) {
            stage = kRefinement;
          } else if (DistanceToLines(q, assembled, &a) > 0.010) {
            stage = kConnection;
          } else {
            Eigen::Vector3d b = a;
            if (DistanceToLines(a, pieces, &b) > 0.010) stage = kBridge;
            else if (right(b)) stage = kFusion;
          }
        }
        // Place.
        Eigen::Vector3d t = p;
        const double d = DistanceToLines(p, true_lines, &t);
        Where where = kGhost;
        bool near_head = false;
        for (const Sphere& sp : truth.head.spheres)
          near_head |= (p - sp.center).norm() <= sp.radius + 0.030;
        if (DistanceToLines(p, neighbour_lines) <= 0.010) {
          where = kNeighbour;
        } else if (near_head || DistanceToLines(p, trunk_lines) <= 0.030) {
          where = kNearTrunk;
        } else if (d <= 0.030) {
          where = kMisDepth;
          misdepth_m += 0.005;
          misdepth_dy += 0.005 * std::abs(t.y() - p.y());
          misdepth_dxz += 0.005 * std::hypot(t.x() - p.x(), t.z() - p.z());
        } else if (DistanceToWires(p, truth.wires) <= 0.015) {
          where = kWire;
        }
        table[stage][where] += 0.005;
        stop_stage[stage] += 0.005;
      }
    }
    total += stop_total;
    if (verbose) {
      std::printf("seed %llu: model %.2f m, precision %.3f, false m by stage:",
                  static_cast<unsigned long long>(seed), stop_total,
                  1 - stop_false / std::max(stop_total, 1e-9));
      for (int s = 0; s < kStages; ++s) std::printf(" %.3f", stop_stage[s]);
      std::printf("\n");
    }
  }
  ASSERT_GT(total, 0);
  std::printf("stops %llu-%llu (%s): model cane length %.2f m; false length by stage (rows) and "
              "place (columns), share of the model's length\n",
              static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), images ? "images" : "labels",
              total);
  std::printf("%-26s", "");
  for (int w = 0; w < kWheres; ++w) std::printf(" %10s", kWhereNames[w]);
  std::printf(" %10s\n", "all");
  double column[kWheres] = {}, all = 0;
  for (int s = 0; s < kStages; ++s) {
    double row = 0;
    std::printf("%-26s", kStageNames[s]);
    for (int w = 0; w < kWheres; ++w) {
      std::printf(" %10.4f", table[s][w] / total);
      row += table[s][w];
      column[w] += table[s][w];
    }
    all += row;
    std::printf(" %10.4f\n", row / total);
  }
  std::printf("%-26s", "all");
  for (int w = 0; w < kWheres; ++w) std::printf(" %10.4f", column[w] / total);
  std::printf(" %10.4f\n", all / total);
  std::printf("false length on canes mostly false %.4f, within 3 cm of an end of a mostly right "
              "cane %.4f, elsewhere on one %.4f\n",
              whole_false / total, end_false / total, interior_false / total);
  std::printf("canes' samples by worst residual over the views (px, skeleton distance; share of "
              "the model's length):\n  %-22s", "");
  for (int b = 0; b < kBins; ++b) std::printf(" %8s%g", "<=", kBinEdges[b]);
  std::printf("\n");
  for (int f = 0; f < 2; ++f)
    for (int tip = 0; tip < 2; ++tip) {
      std::printf("  %-22s", f ? (tip ? "false, tip 3 cm" : "false, elsewhere")
                               : (tip ? "right, tip 3 cm" : "right, elsewhere"));
      for (int b = 0; b < kBins; ++b) std::printf(" %10.4f", residual[f][tip][b] / total);
      std::printf("\n");
    }
  std::printf("canes' samples by views that see them on background (0, 1, 2+):\n");
  for (int f = 0; f < 2; ++f)
    for (int tip = 0; tip < 2; ++tip)
      std::printf("  %-22s %10.4f %10.4f %10.4f\n",
                  f ? (tip ? "false, tip 3 cm" : "false, elsewhere")
                    : (tip ? "right, tip 3 cm" : "right, elsewhere"),
                  background[f][tip][0] / total, background[f][tip][1] / total,
                  background[f][tip][2] / total);
  std::printf("the model's trunk by height (m summed over stops): z from, true trunk, right, "
              "false, false before refinement, false in < 2 images, false's mean distance mm\n");
  for (int z = 0; z < kZBins; ++z)
    std::printf("  %.1f %7.3f %7.3f %7.3f %7.3f %7.3f %7.1f\n", 0.1 * z, trunk_true[z],
                trunk_right[z], trunk_false[z], trunk_false_before[z], trunk_unseen[z],
                trunk_false[z] > 0 ? 1000 * trunk_distance[z] / (trunk_false[z] / 0.005) : 0.0);
  std::printf("the trunk before refinement below its first point inside two images, by distance "
              "below it (m): right / false\n");
  for (int b = 0; b < kBelowBins; ++b)
    std::printf("  %2d-%s cm %7.3f %7.3f\n", 5 * b,
                b + 1 < kBelowBins ? std::to_string(5 * b + 5).c_str() : "", below_right[b],
                below_false[b]);
  if (misdepth_m > 0)
    std::printf("10-30 mm: mean |dy| (depth) %.1f mm, across (x, z) %.1f mm\n",
                1000 * misdepth_dy / misdepth_m, 1000 * misdepth_dxz / misdepth_m);
}

}  // namespace
}  // namespace vb::reconstruct
