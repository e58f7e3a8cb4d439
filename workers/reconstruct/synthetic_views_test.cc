// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/synthetic_views.h"

#include <algorithm>

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

// Two canes crossing in the vine plane, and a third lying 3 mm beside the second's upper part.
VineModel CrossingAndLyingAlong() {
  VineModel model;
  model.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {-0.2, 0.8, 1.0},
                                     {0.2, 0.8, 1.0}, 0.004));
  model.canes.push_back(
      StraightCane(2, 1, CaneKind::kCane, {0.0, 0.8, 0.85}, {0.0, 0.8, 1.3}, 0.004));
  model.canes.push_back(
      StraightCane(3, 1, CaneKind::kCane, {0.003, 0.8, 1.1}, {0.003, 0.8, 1.3}, 0.004));
  return model;
}

int SegmentsOf(const View2D& view, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  // Segments whose both ends lie on the image line from a to b (within 2 px).
  int count = 0;
  const Eigen::Vector2d d = (b - a).normalized();
  for (const Segment2D& s : view.segments) {
    auto off = [&](const Eigen::Vector2d& p) {
      const Eigen::Vector2d r = p - a;
      return std::abs(r.x() * d.y() - r.y() * d.x());
    };
    if (off(s.points.front()) < 2.0 && off(s.points.back()) < 2.0) ++count;
  }
  return count;
}

TEST(SyntheticViews, CrossingsBreakSegmentsAndOverlapsMergeOnlyWhenAsked) {
  const RigCalibration rig = sim::MakeRig().value();
  const VineModel model = CrossingAndLyingAlong();
  const auto horizontal = [&](int v) {
    return std::pair(*rig.cameras[v].Project({-0.2, 0.8, 1.0}),
                     *rig.cameras[v].Project({0.2, 0.8, 1.0}));
  };
  const std::vector<View2D> whole = SyntheticViews(model, rig);
  SyntheticViewOptions broken;
  broken.break_at_crossings_px = 2.0;
  const std::vector<View2D> crossed = SyntheticViews(model, rig, broken);
  broken.merge_overlaps = true;
  const std::vector<View2D> merged = SyntheticViews(model, rig, broken);
  for (size_t v = 0; v < rig.cameras.size(); ++v) {
    EXPECT_EQ(whole[v].segments.size(), 3u);
    const auto [a, b] = horizontal(static_cast<int>(v));
    EXPECT_EQ(SegmentsOf(whole[v], a, b), 1);
    // The horizontal cane is broken where the upright one crosses it, and the upright one where
    // the horizontal one crosses it; cane 3 lies along cane 2 (a long run): kept whole.
    EXPECT_EQ(SegmentsOf(crossed[v], a, b), 2);
    EXPECT_EQ(crossed[v].segments.size(), 5u);
    // Merged: cane 3, listed after cane 2, loses the stretch beside it (all of it).
    EXPECT_EQ(merged[v].segments.size(), 4u);
    // The foreground is drawn the same in every case.
    EXPECT_EQ(whole[v].classes.data, merged[v].classes.data);
  }
}

TEST(SyntheticViews, LyingAlongAnotherFlagsParallelStretchesNotCrossings) {
  const RigCalibration rig = sim::MakeRig().value();
  const VineModel model = CrossingAndLyingAlong();
  for (const CameraCalibration& camera : rig.cameras) {
    const std::vector<std::vector<bool>> along = LyingAlongAnother(model, camera, 0.005, 2.0);
    ASSERT_EQ(along.size(), 3u);
    auto count = [](const std::vector<bool>& flags) {
      return static_cast<int>(std::count(flags.begin(), flags.end(), true));
    };
    EXPECT_EQ(count(along[0]), 0);  // crossed only
    EXPECT_EQ(count(along[2]), static_cast<int>(along[2].size()));  // beside cane 2 throughout
    // Cane 2 is flagged beside cane 3 (its upper 0.2 m of 0.45 m) and not at the crossing.
    EXPECT_GT(count(along[1]), static_cast<int>(along[1].size()) / 3);
    EXPECT_LT(count(along[1]), static_cast<int>(along[1].size()) * 2 / 3);
  }
}

}  // namespace
}  // namespace vb::reconstruct
