// SPDX-License-Identifier: Apache-2.0
// Diagnosis tool, not a test: the prize of the single-view extension (extend.h) and its
// trade-off, on rendered stops (VB_SEED, VB_STOPS, VB_INPUT as ReportStopsFromEnv; images by
// default). Run with --gtest_also_run_disabled_tests --gtest_filter='Extend.DISABLED_Report'.
// Tuning seeds only (1100-1999).

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "core/view_coverage.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/extend.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

// Per stop, the model without the extension; then (a) the prize: shares of the true trunk + cane
// length inside exactly one image (CoverageSample, true rig), recalled or not, and the part of
// it on a true cane that the model recalls elsewhere and that continues, through samples inside
// at least one image, from a recalled sample (what following a tip can reach); the trunk inside
// fewer than two images and its recall; (b) for each max_depth_sd_m in VB_EXT_SD (comma list)
// and second_difference_sd_m in VB_EXT_DD, ExtendCanes on a copy of the model: mean recall and
// precision over the stops, their change (mean +- standard error), the added length and its
// share within 10 mm of the true vine; the wrong added length split by cause (a ray through the
// true vine in some camera: wrong depth; else a wrong 2D path), inside one image, and added to
// tips already more than 10 mm from the true vine. VB_EXT_LEN: max_length_m; VB_EXT_SPAN,
// VB_EXT_TURN, VB_EXT_OTHER, VB_EXT_BACKGROUND: the ExtendOptions fields of like names;
// VB_VERBOSE: one line per extended tip of the first setting (its features, right or not).
TEST(Extend, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10, true);
  const std::vector<double> sds = ListFromEnv("VB_EXT_SD", {0.004, 0.006, 0.010});
  const std::vector<double> dds =
      ListFromEnv("VB_EXT_DD", {ExtendOptions{}.second_difference_sd_m});
  const std::vector<double> lens = ListFromEnv("VB_EXT_LEN", {0.3});
  double total = 0, one = 0, one_recalled = 0, one_continuing = 0, one_in_volume = 0;
  double trunk_below = 0, trunk_below_recalled = 0;
  struct Arm {
    ExtendOptions options;
    std::vector<double> d_recall, d_precision;
    double added = 0, added_right = 0, recall = 0, precision = 0, time = 0;
    // Wrong added length: on a ray that passes within 10 mm of the true vine in some camera
    // (the 2D path was right, the depth wrong), or not; and added length inside one image.
    double wrong_depth = 0, wrong_path = 0, added_one_view = 0, right_one_view = 0;
    double added_wrong_tip = 0, right_wrong_tip = 0;  // added to a cane whose tip misses the vine
    int extended = 0, contradicted = 0, uncertain = 0;
  };
  std::vector<Arm> arms;
  for (double sd : sds)
    for (double dd : dds)
      for (double len : lens) {
        Arm arm;
        arm.options.enabled = true;
        arm.options.max_depth_sd_m = sd;
        arm.options.second_difference_sd_m = dd;
        arm.options.max_length_m = len;
        OverrideFromEnv("VB_EXT_SPAN", &arm.options.anchor_span_m);
        OverrideFromEnv("VB_EXT_TURN", &arm.options.max_turn_rad);
        OverrideFromEnv("VB_EXT_OTHER", &arm.options.other_cane_px);
        OverrideFromEnv("VB_EXT_BACKGROUND", &arm.options.background_px);
        arms.push_back(arm);
      }
  double base_recall = 0, base_precision = 0;
  ReconstructOptions options;
  options.extend.enabled = false;
  for (int k = 0; k < count; ++k) {
    const SimulatedStop stop = MakeRenderedStop(first + k, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const VineModel& truth = stop.scene.vine;
    const VineModel& model = result->model;
    const auto samples = SampleViewCoverage(truth, stop.true_rig);
    ASSERT_TRUE(samples.ok());
    // Per true cane, in order: recalled flags, to find one-view stretches reachable from a
    // recalled sample through samples inside an image.
    std::vector<bool> recalled(samples->size());
    for (size_t i = 0; i < samples->size(); ++i) {
      const CoverageSample& s = (*samples)[i];
      recalled[i] = DistanceToCanes(s.point, model.canes) <= 0.010;
      total += s.length_m;
      if (s.kind == CaneKind::kTrunk && s.views < 2) {
        trunk_below += s.length_m;
        trunk_below_recalled += recalled[i] * s.length_m;
      }
      if (s.views != 1) continue;
      one += s.length_m;
      one_recalled += recalled[i] * s.length_m;
      if (!recalled[i] && WorkingVolume{}.Contains(s.point)) one_in_volume += s.length_m;
    }
    for (size_t i = 0; i < samples->size(); ++i) {
      const CoverageSample& s = (*samples)[i];
      if (s.views != 1 || recalled[i] || s.kind != CaneKind::kCane) continue;
      bool reach = false;
      for (int dir : {-1, 1}) {
        for (long j = long(i) + dir; j >= 0 && j < long(samples->size()); j += dir) {
          const CoverageSample& q = (*samples)[j];
          if (q.cane_index != s.cane_index || q.views < 1) break;
          if (recalled[j]) {
            reach = true;
            break;
          }
        }
      }
      one_continuing += reach * s.length_m;
    }
    const auto before = EvaluateReconstruction(model, truth);
    ASSERT_TRUE(before.ok());
    base_recall += before->cane_recall;
    base_precision += before->cane_precision;
    for (Arm& arm : arms) {
      VineModel extended = model;
      ExtendSummary summary;
      const auto t0 = std::chrono::steady_clock::now();
      ASSERT_TRUE(
          ExtendCanes(stop.views, result->rig, options.volume, arm.options, &extended, &summary)
              .ok());
      arm.time += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const auto after = EvaluateReconstruction(extended, truth);
      ASSERT_TRUE(after.ok());
      arm.recall += after->cane_recall;
      arm.precision += after->cane_precision;
      arm.d_recall.push_back(after->cane_recall - before->cane_recall);
      arm.d_precision.push_back(after->cane_precision - before->cane_precision);
      arm.extended += summary.tips_extended;
      arm.contradicted += summary.contradicted;
      arm.uncertain += summary.uncertain;
      for (size_t c = 0; c < extended.canes.size(); ++c) {
        const std::vector<Eigen::Vector3d>& pts = extended.canes[c].polyline.points;
        const size_t old = model.canes[c].polyline.points.size();
        const bool tip_right = DistanceToCanes(pts[old - 1], truth.canes) <= 0.010;
        if (std::getenv("VB_VERBOSE") != nullptr && pts.size() > old && &arm == &arms.front()) {
          const Cane& cane = model.canes[c];
          int fg = 0, inside = 0;
          for (size_t v = 0; v < stop.views.size(); ++v) {
            const auto uv = result->rig.cameras[v].Project(pts[old - 1]);
            if (!uv || !result->rig.cameras[v].InImage(*uv)) continue;
            ++inside;
            fg += ForegroundWithin(stop.views[v], int(std::lround(uv->x())),
                                   int(std::lround(uv->y())), 2);
          }
          bool parent_trunk = false, children = false;
          for (const Cane& other : model.canes) {
            parent_trunk |=
                cane.parent_id && other.id == *cane.parent_id && other.kind == CaneKind::kTrunk;
            children |= other.parent_id && *other.parent_id == cane.id;
          }
          double right_len = 0, len = 0;
          for (const Eigen::Vector3d& q : cane.polyline.Sample(0.005)) {
            len += 0.005;
            right_len += 0.005 * (DistanceToCanes(q, truth.canes) <= 0.010);
          }
          const Eigen::Vector3d d =
              (pts[old - 1] - cane.polyline.PointAt(std::max(0.0, cane.polyline.Length() - 0.03)))
                  .normalized();
          std::printf(
              "TIP stop %llu right %d len %.3f cane_right %.2f x %.3f y %.3f z %.3f dir %.2f %.2f "
              "%.2f "
              "parent_trunk %d children %d inside %d fg %d radius %.4f added %zu\n",
              static_cast<unsigned long long>(first + k), tip_right, len, right_len / len,
              pts[old - 1].x(), pts[old - 1].y(), pts[old - 1].z(), d.x(), d.y(), d.z(),
              parent_trunk, children, inside, fg, cane.polyline.radii.back(), pts.size() - old);
        }
        for (size_t i = old; i < pts.size(); ++i) {
          const double step = (pts[i] - pts[i - 1]).norm();
          arm.added += step;
          const bool right = DistanceToCanes(pts[i], truth.canes) <= 0.010;
          arm.added_right += step * right;
          if (!tip_right) arm.added_wrong_tip += step, arm.right_wrong_tip += step * right;
          int seen = 0;
          for (const CameraCalibration& camera : stop.true_rig.cameras) {
            const auto uv = camera.Project(pts[i]);
            seen += uv && camera.InImage(*uv);
          }
          if (seen == 1) arm.added_one_view += step, arm.right_one_view += step * right;
          if (right) continue;
          bool on_ray = false;
          for (const CameraCalibration& camera : stop.true_rig.cameras) {
            const Eigen::Vector3d c = camera.CentreInPlatform();
            const Eigen::Vector3d dir = (pts[i] - c).normalized();
            for (const Cane& t : truth.canes)
              for (const Eigen::Vector3d& q : t.polyline.Sample(0.005))
                on_ray |= ((q - c) - (q - c).dot(dir) * dir).norm() <= 0.010;
          }
          (on_ray ? arm.wrong_depth : arm.wrong_path) += step;
        }
      }
    }
  }
  auto share = [&](double x) { return total > 0 ? x / total : 0.0; };
  std::printf("stops %llu-%llu (%s)\n", static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), images ? "images" : "labels");
  std::printf(
      "true length inside exactly one image: %.4f (recalled %.4f; not recalled, in the "
      "working volume %.4f; on a recalled cane, reachable from a recalled sample %.4f)\n",
      share(one), share(one_recalled), share(one_in_volume), share(one_continuing));
  std::printf("trunk inside fewer than two images: %.4f (recalled %.4f)\n", share(trunk_below),
              share(trunk_below_recalled));
  std::printf("without extension: recall %.4f precision %.4f\n", base_recall / count,
              base_precision / count);
  auto mean_se = [](const std::vector<double>& v) {
    double m = 0, s2 = 0;
    for (double x : v) m += x;
    m /= v.size();
    for (double x : v) s2 += (x - m) * (x - m);
    return std::make_pair(m, v.size() > 1 ? std::sqrt(s2 / (v.size() - 1) / v.size()) : 0.0);
  };
  for (const Arm& arm : arms) {
    const auto [dr, dr_se] = mean_se(arm.d_recall);
    const auto [dp, dp_se] = mean_se(arm.d_precision);
    std::printf(
        "sd %.4f dd %.5f len %.2f: recall %.4f (%+.4f +- %.4f) precision %.4f (%+.4f +- "
        "%.4f); added %.2f m/stop, %.2f right; tips %d, contradicted %d, uncertain %d; "
        "%.1f ms/stop\n    wrong: depth %.3f m/stop, path %.3f m/stop; inside one image %.3f "
        "m/stop, %.2f right; from wrong tips %.3f m/stop, %.2f right\n",
        arm.options.max_depth_sd_m, arm.options.second_difference_sd_m, arm.options.max_length_m,
        arm.recall / count, dr, dr_se, arm.precision / count, dp, dp_se, arm.added / count,
        arm.added > 0 ? arm.added_right / arm.added : 0.0, arm.extended, arm.contradicted,
        arm.uncertain, 1000 * arm.time / count, arm.wrong_depth / count, arm.wrong_path / count,
        arm.added_one_view / count,
        arm.added_one_view > 0 ? arm.right_one_view / arm.added_one_view : 0.0,
        arm.added_wrong_tip / count,
        arm.added_wrong_tip > 0 ? arm.right_wrong_tip / arm.added_wrong_tip : 0.0);
  }
}

}  // namespace
}  // namespace vb::reconstruct
