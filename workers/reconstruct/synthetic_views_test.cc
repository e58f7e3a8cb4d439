// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/synthetic_views.h"

#include "gtest/gtest.h"
#include "core/vine_model_test_util.h"
#include "sim/rig.h"

namespace vb::reconstruct {
namespace {

TEST(SyntheticViews, SegmentsLieOnTheProjectedCane) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  ASSERT_EQ(views.size(), 3u);
  for (size_t v = 0; v < views.size(); ++v) {
    ASSERT_EQ(views[v].segments.size(), 1u);
    const Segment2D& segment = views[v].segments[0];
    const auto a = rig.cameras[v].Project({-0.1, 0.8, 0.9});
    const auto b = rig.cameras[v].Project({0.2, 0.8, 1.0});
    ASSERT_TRUE(a && b);
    EXPECT_LT((segment.points.front() - *a).norm(), 1e-6);
    EXPECT_LT((segment.points.back() - *b).norm(), 1e-6);
    // 8 mm at ~0.8 m with f ~ 600 px is ~6 px wide.
    EXPECT_GT(segment.widths_px[0], 4.0);
    EXPECT_LT(segment.widths_px[0], 9.0);
    const Eigen::Vector2d mid = segment.points[segment.points.size() / 2];
    const int x = static_cast<int>(std::lround(mid.x()));
    const int y = static_cast<int>(std::lround(mid.y()));
    EXPECT_TRUE(views[v].IsForeground(x, y));
    EXPECT_LE(views[v].centreline_distance_px[static_cast<size_t>(y) * views[v].width + x], 1.0f);
    EXPECT_GT(views[v].centreline_distance_px[static_cast<size_t>(y + 20) * views[v].width + x],
              15.0f);
  }
}

}  // namespace
}  // namespace vb::reconstruct
