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
#include <cstdio>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

constexpr double kStepM = 0.005;

TEST(OverlapLoss, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10);
  const ReconstructOptions options;
  constexpr int kRows = 4;  // lying along another cane in 0, 1, 2 or 3 of the views that see it
  double length[kRows] = {}, recalled[kRows] = {}, total = 0.0, outside = 0.0;
  // Of each row: lying along another cane of this vine (not a neighbour's) in 2+ views.
  double own[kRows] = {}, own_recalled[kRows] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    // stop.drawn lists the vine's canes first, then the neighbours'.
    std::vector<std::vector<std::vector<bool>>> along, along_own;
    for (const CameraCalibration& camera : stop.true_rig.cameras) {
      along.push_back(LyingAlongAnother(stop.drawn, camera, kStepM, 2.0));
      along_own.push_back(LyingAlongAnother(stop.scene.vine, camera, kStepM, 2.0));
    }
    for (size_t c = 0; c < stop.scene.vine.canes.size(); ++c) {
      const Polyline3& line = stop.scene.vine.canes[c].polyline;
      const std::vector<double> arc = line.ArcLengths();
      const size_t n = along[0][c].size();
      const double step = arc.back() / static_cast<double>(n - 1);
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p = line.PointAt(arc.back() * i / (n - 1), arc);
        const double w = (i == 0 || i + 1 == n) ? 0.5 * step : step;
        total += w;
        int seen = 0, beside = 0, beside_own = 0;
        for (size_t v = 0; v < stop.true_rig.cameras.size(); ++v) {
          const auto uv = stop.true_rig.cameras[v].Project(p);
          if (!uv || !stop.true_rig.cameras[v].InImage(*uv)) continue;
          ++seen;
          if (along[v][c][i]) ++beside;
          if (along_own[v][c][i]) ++beside_own;
        }
        if (seen < 2) {
          outside += w;
          continue;
        }
        bool hit = false;
        for (const Cane& cane : result->model.canes) {
          double d = 0.0;
          cane.polyline.Project(p, &d);
          if (d <= 0.01) {
            hit = true;
            break;
          }
        }
        const int row = std::min(beside, kRows - 1);
        length[row] += w;
        if (hit) recalled[row] += w;
        if (beside_own >= 2) {
          own[row] += w;
          if (hit) own_recalled[row] += w;
        }
      }
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
  EXPECT_GT(total, 0.0);
}

}  // namespace
}  // namespace vb::reconstruct
