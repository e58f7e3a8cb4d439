// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: why true cane length with foreground in two views has no
// skeleton segment near it in two views (the "skeleton in fewer than 2 views" row of
// MatchLoss.DISABLED_Report), what hides the true cane where the foreground row loses it, and
// why matched pieces are lost in assembly. Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=10 vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='SkeletonLoss.DISABLED_*'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/mask_ops.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/skeleton.h"

namespace vb::reconstruct {
namespace {

// Distance in pixels from q to the polyline of 2D points.
double DistanceToPath(const Eigen::Vector2d& q, const std::vector<Eigen::Vector2d>& path) {
  double best = 1e9;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d d = path[i + 1] - path[i];
    const double l2 = d.squaredNorm();
    const double t = l2 > 0 ? std::clamp((q - path[i]).dot(d) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, (path[i] + t * d - q).norm());
  }
  if (path.size() == 1) best = (path[0] - q).norm();
  return best;
}

// Per view of a stop: the true canes' projections (drawn vine and neighbours), the cleaned
// foreground, its distance to background, and the thinned skeleton before pruning.
struct ViewDebug {
  BinaryImage fg, raw_skeleton;
  std::vector<float> distance;  // capped distance to the background
  std::vector<std::vector<Eigen::Vector2d>> drawn;  // projected drawn canes (2 mm steps)
  std::vector<std::vector<double>> drawn_depth;
};

TEST(SkeletonLoss, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 4, true);
  enum Cause { kSpeck, kPruned, kOffset, kThick, kOther, kCauses };
  const char* names[kCauses] = {"foreground removed as a speck / not cleaned fg",
                                "raw skeleton near, pruned away",
                                "a segment 3-6 px away (centring, junction offset)",
                                "thick foreground (half width > 1.5 x own + 1.5 px)",
                                "other"};
  double cause[kCauses] = {}, cause_other_cane[kCauses] = {}, total = 0, lost = 0;
  double lost_by_width[4] = {};
  double fg_lost = 0, fg_class[3] = {}, fg_thin[3] = {};  // post, wire, background
  double angle_bins[kCauses][4] = {}, behind_count[kCauses] = {};  // own projected diameter < 3, 3-5, 5-8, >= 8 px
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const int n = static_cast<int>(stop.views.size());
    std::vector<ViewDebug> debug(n);
    for (int v = 0; v < n; ++v) {
      const View2D& view = stop.views[v];
      ViewDebug& d = debug[v];
      d.fg = BinaryImage(view.width, view.height);
      for (int y = 0; y < view.height; ++y)
        for (int x = 0; x < view.width; ++x) d.fg.set(x, y, view.IsForeground(x, y));
      FlipSmallComponents(1, Structure2DOptions{}.min_speck_area_px - 1, true, false, &d.fg);
      FlipSmallComponents(0, Structure2DOptions{}.max_pinhole_area_px, false, true, &d.fg);
      BinaryImage bg = d.fg;
      for (auto& b : bg.data) b = !b;
      d.distance = CappedDistanceTransform(bg, 30);
      d.raw_skeleton = d.fg;
      ThinMask(&d.raw_skeleton);
      const CameraCalibration& cam = stop.true_rig.cameras[v];
      for (const Cane& cane : stop.drawn.canes) {
        std::vector<Eigen::Vector2d> path;
        std::vector<double> depth;
        for (const Eigen::Vector3d& p : cane.polyline.Sample(0.002)) {
          const auto uv = cam.Project(p);
          if (!uv) continue;
          path.push_back(*uv);
          depth.push_back((p - cam.CentreInPlatform()).norm());
        }
        d.drawn.push_back(std::move(path));
        d.drawn_depth.push_back(std::move(depth));
      }
    }
    const SegmentMaps maps(stop.views);
    for (size_t ci = 0; ci < stop.scene.vine.canes.size(); ++ci) {
      const Cane& cane = stop.scene.vine.canes[ci];
      if (cane.kind == CaneKind::kSpur) continue;
      const Polyline3& line = cane.polyline;
      const std::vector<Eigen::Vector3d> pts = line.Sample(0.005);
      for (size_t i = 0; i < pts.size(); ++i) {
        const Eigen::Vector3d& p = pts[i];
        total += 1;
        // The radius at this sample: nearest point's radius.
        size_t nearest = 0;
        for (size_t j = 1; j < line.points.size(); ++j)
          if ((line.points[j] - p).norm() < (line.points[nearest] - p).norm()) nearest = j;
        const double radius_m = line.radii[nearest];
        // Skeleton counts where the view also shows foreground, as the report.
        const SampleInViews at = LocateSample(p, stop.true_rig, stop.views, maps);
        const int in_image = at.in_image, fg = at.foreground;
        const std::vector<Eigen::Vector2d>& px = at.px;
        int skel = 0;
        std::vector<int> fg_view(n, 0), skel_view(n, 0);
        std::vector<double> radius_px(n, 0);
        for (int v = 0; v < n; ++v) {
          if (!at.inside[v]) continue;
          const CameraCalibration& cam = stop.true_rig.cameras[v];
          radius_px[v] = radius_m * cam.camera_matrix(0, 0) / (p - cam.CentreInPlatform()).norm();
          fg_view[v] = at.on_foreground[v];
          skel_view[v] = at.on_foreground[v] && at.segment[v] >= 0;
          skel += skel_view[v];
        }
        if (in_image >= 2 && fg < 2) {
          // Foreground missed: what the views without foreground there show instead.
          fg_lost += 1;
          for (int v = 0; v < n; ++v) {
            if (fg_view[v] || radius_px[v] <= 0) continue;
            const View2D& view = stop.views[v];
            const int x = std::clamp(static_cast<int>(std::lround(px[v].x())), 0, view.width - 1);
            const int y = std::clamp(static_cast<int>(std::lround(px[v].y())), 0, view.height - 1);
            const PixelClass c = view.classes.at(x, y);
            const int f = c == PixelClass::kPost ? 0 : c == PixelClass::kWire ? 1 : 2;
            const double weight = 1.0 / (in_image - fg);
            fg_class[f] += weight;
            fg_thin[f] += weight * (2 * radius_px[v] < 3.0);
          }
        }
        if (in_image < 2 || fg < 2 || skel >= 2) continue;
        lost += 1;
        double own_diameter = 0;
        int fails = 0;
        for (int v = 0; v < n; ++v) fails += fg_view[v] && !skel_view[v];
        for (int v = 0; v < n; ++v) {
          if (!fg_view[v] || skel_view[v]) continue;
          own_diameter = std::max(own_diameter, 2 * radius_px[v]);
          const View2D& view = stop.views[v];
          const ViewDebug& d = debug[v];
          const int x = static_cast<int>(std::lround(px[v].x()));
          const int y = static_cast<int>(std::lround(px[v].y()));
          bool clean = false, raw = false;
          float max_distance = 0;
          for (int dy = -3; dy <= 3; ++dy)
            for (int dx = -3; dx <= 3; ++dx) {
              const int xx = x + dx, yy = y + dy;
              if (xx < 0 || yy < 0 || xx >= view.width || yy >= view.height) continue;
              if (std::abs(dx) <= 2 && std::abs(dy) <= 2) {
                clean |= d.fg.at(xx, yy) != 0;
                max_distance = std::max(
                    max_distance, d.distance[static_cast<size_t>(yy) * view.width + xx]);
              }
              raw |= d.raw_skeleton.at(xx, yy) != 0;
            }
          double nearest_segment = 1e9;
          for (const Segment2D& seg : view.segments)
            nearest_segment = std::min(nearest_segment, DistanceToPath(px[v], seg.points));
          // Another drawn cane within its radius + own radius + 3 px in this view.
          bool other = false;
          double other_angle = 90, other_distance = 1e9;
          bool behind = false;
          const CameraCalibration& cam = stop.true_rig.cameras[v];
          const auto uv2 = cam.Project(pts[std::min(i + 1, pts.size() - 1)]);
          const auto uv1 = cam.Project(pts[i > 0 ? i - 1 : 0]);
          const Eigen::Vector2d own_dir = (*uv2 - *uv1).normalized();
          for (size_t dj = 0; dj < d.drawn.size(); ++dj) {
            if (dj == ci) continue;
            const double dist = DistanceToPath(px[v], d.drawn[dj]);
            if (dist >= 3 * radius_px[v] + 3.0 || dist >= other_distance) continue;
            other = true;
            other_distance = dist;
            size_t best = 0;
            for (size_t q = 0; q < d.drawn[dj].size(); ++q)
              if ((d.drawn[dj][q] - px[v]).norm() < (d.drawn[dj][best] - px[v]).norm()) best = q;
            const size_t q1 = std::min(best + 1, d.drawn[dj].size() - 1), q0 = best > 0 ? best - 1 : 0;
            const Eigen::Vector2d od = (d.drawn[dj][q1] - d.drawn[dj][q0]).normalized();
            other_angle = std::acos(std::min(1.0, std::abs(od.dot(own_dir)))) * 180 / 3.14159265;
            behind = d.drawn_depth[dj][best] < (p - cam.CentreInPlatform()).norm();
          }
          Cause c = kOther;
          if (!clean) c = kSpeck;
          else if (raw) c = kPruned;
          else if (nearest_segment <= 6.0) c = kOffset;
          else if (max_distance > 1.5 * radius_px[v] + 1.5) c = kThick;
          cause[c] += 1.0 / fails;
          if (other) {
            const int bin = other_angle < 5 ? 0 : other_angle < 15 ? 1 : other_angle < 30 ? 2 : 3;
            angle_bins[c][bin] += 1.0 / fails;
            behind_count[c] += behind / double(fails);
          }
          if (other) cause_other_cane[c] += 1.0 / fails;
        }
        lost_by_width[own_diameter < 3 ? 0 : own_diameter < 5 ? 1 : own_diameter < 8 ? 2 : 3] +=
            1;
      }
    }
    std::printf("seed %llu: lost at skeleton %.3f\n", static_cast<unsigned long long>(first + k),
                lost / total);
  }
  std::printf("foreground in < 2 views: %.3f of true length; the views without it show post "
              "%.3f (own diameter < 3 px %.3f), wire %.3f (%.3f), background %.3f (%.3f)\n",
              fg_lost / total, fg_class[0] / total, fg_thin[0] / total, fg_class[1] / total,
              fg_thin[1] / total, fg_class[2] / total, fg_thin[2] / total);
  std::printf("skeleton in < 2 views: %.3f of true length (%d stops)\n", lost / total, count);
  for (int c = 0; c < kCauses; ++c)
    std::printf("  %-52s %.3f (another cane within reach: %.3f; at <5 deg %.3f, 5-15 %.3f, "
                "15-30 %.3f, >30 %.3f; the other in front %.3f)\n", names[c], cause[c] / total,
                cause_other_cane[c] / total, angle_bins[c][0] / total, angle_bins[c][1] / total,
                angle_bins[c][2] / total, angle_bins[c][3] / total, behind_count[c] / total);
  std::printf("  by own diameter <3 px %.3f, 3-5 %.3f, 5-8 %.3f, >=8 %.3f\n",
              lost_by_width[0] / total, lost_by_width[1] / total, lost_by_width[2] / total,
              lost_by_width[3] / total);
}

// Why matched length is lost in assembly (the "lost in assembly" row): true samples within 10 mm
// of a selected piece but of no assembled cane (after the volume filter), and how many each
// relaxed variant of the assembly brings back, with the wrong length (no drawn cane within
// 10 mm) each variant adds. Run with --gtest_filter='SkeletonLoss.DISABLED_Assembly'.
TEST(SkeletonLoss, DISABLED_Assembly) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 4, true);
  const ReconstructOptions options;
  struct Variant {
    std::string name;
    AssemblyOptions assembly;
    bool volume_filter = true;
  };
  std::vector<Variant> variants;
  variants.push_back({"as is", options.assembly});
  variants.push_back({"no volume filter", options.assembly, false});
  {
    AssemblyOptions a = options.assembly;
    a.min_isolated_length_m = 0.0;
    variants.push_back({"min_isolated_length 0", a});
    a.min_cane_length_m = 0.0;
    a.min_evidence_m = 0.0;
    variants.push_back({"... and no length/evidence minimum", a});
  }
  {
    AssemblyOptions a = options.assembly;
    a.min_isolated_length_m = 0.06;
    variants.push_back({"min_isolated_length 0.06", a});
  }
  for (const double length : {0.08, 0.09, 0.10}) {
    AssemblyOptions a = options.assembly;
    a.min_isolated_length_m = length;
    variants.push_back({absl::StrCat("min_isolated_length ", length), a});
  }
  {
    AssemblyOptions a = options.assembly;
    a.merge_distance_m = 0.004;
    variants.push_back({"merge distance 4 mm", a});
  }
  {
    AssemblyOptions a = options.assembly;
    a.max_gap_m = 0.0001;
    variants.push_back({"no chaining", a});
  }
  const int nv = static_cast<int>(variants.size());
  std::vector<double> recovered(nv, 0.0), wrong(nv, 0.0), length(nv, 0.0);
  double total = 0, lost = 0;
  // [bin][right]: samples of dropped pieces.
  double by_probability[4][2] = {}, by_support[4][2] = {}, by_length[5][2] = {};
  double by_length_probable[5][2] = {}, own_samples = 0;
  for (int k = 0; k < count; ++k) {
    const auto run = RenderAndMatch(first + k, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const SimulatedStop& stop = run->stop;
    std::vector<std::vector<Polyline3>> canes(nv);
    for (int v = 0; v < nv; ++v) {
      auto c = AssembleCanes(run->matched.pieces, variants[v].assembly, Deadline::Infinite());
      ASSERT_TRUE(c.ok());
      if (variants[v].volume_filter)
        std::erase_if(*c, [&](const Polyline3& l) { return options.volume.MostlyOutside(l); });
      canes[v] = std::move(*c);
      for (const Polyline3& l : canes[v])
        for (const Eigen::Vector3d& p : l.Sample(0.005)) {
          length[v] += 1;
          wrong[v] += !NearAnyCane(p, stop.drawn.canes);
        }
    }
    const auto near_any = [](const Eigen::Vector3d& p, const std::vector<Polyline3>& lines) {
      for (const Polyline3& l : lines)
        if (DistanceToPolyline(p, l) <= 0.01) return true;
      return false;
    };
    std::vector<Polyline3> pieces;
    for (const Piece3D& piece : run->matched.pieces) pieces.push_back(piece.polyline);
    for (const Cane& cane : stop.scene.vine.canes) {
      if (cane.kind == CaneKind::kSpur) continue;
      for (const Eigen::Vector3d& p : cane.polyline.Sample(0.005)) {
        total += 1;
        if (!near_any(p, pieces) || near_any(p, canes[0])) continue;
        lost += 1;
        for (int v = 1; v < nv; ++v) recovered[v] += near_any(p, canes[v]);
      }
    }
    // The pieces the assembly drops whole (no sample within 10 mm of an assembled cane), by
    // probability, support and length: the samples near a drawn cane (right) and not (wrong).
    for (const Piece3D& piece : run->matched.pieces) {
      if (piece.probability < options.assembly.min_piece_probability) continue;
      const std::vector<Eigen::Vector3d> samples = piece.polyline.Sample(0.005);
      bool kept = false;
      for (const Eigen::Vector3d& p : samples)
        if (near_any(p, canes[0])) {
          kept = true;
          break;
        }
      if (kept) continue;
      const double length = piece.polyline.Length();
      const int pb = piece.probability < 0.5 ? 0 : piece.probability < 0.8 ? 1
                     : piece.probability < 0.95 ? 2 : 3;
      const int sb = piece.support < 0.8 ? 0 : piece.support < 0.9 ? 1
                     : piece.support < 0.97 ? 2 : 3;
      const int lb = length < 0.04 ? 0 : length < 0.06 ? 1 : length < 0.09 ? 2 : length < 0.12 ? 3 : 4;
      for (const Eigen::Vector3d& p : samples) {
        const bool right = NearAnyCane(p, stop.drawn.canes);
        const bool own = NearAnyCane(p, stop.scene.vine.canes);
        by_probability[pb][right] += 1;
        by_support[sb][right] += 1;
        by_length[lb][right] += 1;
        by_length_probable[lb][right] += piece.probability >= 0.8 && piece.support >= 0.9;
        own_samples += own;
      }
    }
    std::printf("seed %llu: lost in assembly %.3f so far\n",
                static_cast<unsigned long long>(first + k), lost / total);
  }
  std::printf("lost in assembly: %.3f of true length (%d stops)\n", lost / total, count);
  for (int v = 0; v < nv; ++v)
    std::printf("  %-40s recovers %.3f; assembled length wrong %.4f (%.0f samples)\n",
                variants[v].name.c_str(), recovered[v] / total, wrong[v] / std::max(1.0, length[v]),
                length[v]);
  const auto row = [&](const char* name, const double (*bins)[2], int nb, const char** labels) {
    std::printf("  dropped pieces by %s (samples right / wrong):", name);
    for (int b = 0; b < nb; ++b)
      std::printf(" %s %.0f/%.0f", labels[b], bins[b][1], bins[b][0]);
    std::printf("\n");
  };
  const char* pl[] = {"<0.5", "0.5-0.8", "0.8-0.95", ">=0.95"};
  const char* sl[] = {"<0.8", "0.8-0.9", "0.9-0.97", ">=0.97"};
  const char* ll[] = {"<4cm", "4-6", "6-9", "9-12", ">=12"};
  row("probability", by_probability, 4, pl);
  row("support", by_support, 4, sl);
  row("length", by_length, 5, ll);
  row("length, p >= 0.8 and support >= 0.9", by_length_probable, 5, ll);
  std::printf("  of them near this vine's canes: %.0f samples\n", own_samples);
}

}  // namespace
}  // namespace vb::reconstruct
