// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/diagnose_util.h"

#include <cstdlib>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/match_segments_test_util.h"

namespace vb::reconstruct {
namespace {

TEST(SegmentMaps, FindsTheSegmentWithin3PixelsALaterSegmentWinning) {
  View2D view;
  view.width = 20;
  view.height = 10;
  Segment2D a, b;
  a.points = {{5.0, 5.0}};
  a.widths_px = {1.0};
  b.points = {{8.0, 5.0}};
  b.widths_px = {1.0};
  view.segments = {a, b};
  const SegmentMaps maps({view});
  EXPECT_EQ(maps.At(0, 2, 5), 0);   // 3 px from a
  EXPECT_EQ(maps.At(0, 1, 5), -1);  // 4 px from a
  EXPECT_EQ(maps.At(0, 4, 8), 0);   // 3 px from a either way, 4 from b
  EXPECT_EQ(maps.At(0, 5, 5), 1);   // near both: the later one
  EXPECT_EQ(maps.At(0, 11, 2), 1);
  EXPECT_EQ(maps.At(0, 12, 5), -1);
  EXPECT_EQ(maps.At(0, -1, 5), -1);  // outside the image
  EXPECT_EQ(maps.At(0, 20, 5), -1);
}

TEST(LocateSample, APointOnACaneIsOnItsSegmentInEveryViewAndAPointOffItIsNot) {
  const auto [model, rig, views] =
      DrawOneCane({-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, 3);
  const SegmentMaps maps(views);
  const Polyline3& cane = model.canes[0].polyline;
  const SampleInViews on = LocateSample(0.5 * (cane.points[0] + cane.points[1]), rig, views, maps);
  EXPECT_EQ(on.in_image, 3);
  EXPECT_EQ(on.foreground, 3);
  EXPECT_EQ(on.skeleton, 3);
  for (int v = 0; v < 3; ++v) {
    EXPECT_TRUE(on.inside[v]);
    EXPECT_EQ(on.segment[v], 0);
  }
  // 10 cm above the cane's middle: in the images, away from the wood.
  const SampleInViews off = LocateSample(
      0.5 * (cane.points[0] + cane.points[1]) + Eigen::Vector3d(0, 0, 0.1), rig, views, maps);
  EXPECT_EQ(off.foreground, 0);
  EXPECT_EQ(off.skeleton, 0);
  for (int v = 0; v < 3; ++v) EXPECT_EQ(off.segment[v], -1);
  // Behind the cameras: in no image.
  const SampleInViews behind = LocateSample(Eigen::Vector3d(0, -2.0, 1.0), rig, views, maps);
  EXPECT_EQ(behind.in_image, 0);
  EXPECT_EQ(behind.skeleton, 0);
}

// The horizontal pair's epipolar lines run across the image: a cane along them cannot be placed
// (|sin| near 0), an upright one can (near 1).
TEST(EpipolarSin, SmallAlongTheHorizontalPairsEpipolarLinesLargeAcrossThem) {
  const RigCalibration rig = Rig(2);
  const Eigen::Vector3d p(0.0, 0.8, 1.0);
  const auto px = rig.cameras[0].Project(p);
  ASSERT_TRUE(px.has_value());
  const auto along = EpipolarSin(rig, 0, 1, p, Eigen::Vector3d::UnitX(), *px);
  const auto across = EpipolarSin(rig, 0, 1, p, Eigen::Vector3d::UnitZ(), *px);
  ASSERT_TRUE(along.has_value());
  ASSERT_TRUE(across.has_value());
  EXPECT_LT(*along, 0.2);
  EXPECT_GT(*across, 0.9);
}

TEST(DistanceToCanes, NearestPointOfTheNearestCane) {
  std::vector<Cane> canes = {MakeCane(1, {0, 0, 0}, {1, 0, 0}, 0.004),
                             MakeCane(2, {0, 1, 0}, {1, 1, 0}, 0.004)};
  Eigen::Vector3d nearest;
  EXPECT_NEAR(DistanceToCanes({0.5, 0.005, 0}, canes, &nearest), 0.005, 1e-12);
  EXPECT_NEAR((nearest - Eigen::Vector3d(0.5, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(DistanceToCanes({0.5, 0.9, 0}, canes), 0.1, 1e-12);
  EXPECT_TRUE(NearAnyCane({0.5, 0.005, 0}, canes));
  EXPECT_FALSE(NearAnyCane({0.5, 0.02, 0}, canes));
  EXPECT_TRUE(NearAnyCane({0.5, 0.02, 0}, canes, 0.03));
  EXPECT_EQ(DistanceToCanes({0, 0, 0}, {}), 1e9);
  // The index of the nearest cane, and the same over bare polylines.
  int index = -1;
  EXPECT_NEAR(DistanceToCanes({0.5, 0.9, 0}, canes, nullptr, &index), 0.1, 1e-12);
  EXPECT_EQ(index, 1);
  EXPECT_NEAR(DistanceToCanes({0.5, 0.2, 0}, canes, nullptr, &index), 0.2, 1e-12);
  EXPECT_EQ(index, 0);
  const std::vector<Polyline3> lines = {canes[0].polyline, canes[1].polyline};
  EXPECT_NEAR(DistanceToLines({0.5, 0.995, 0}, lines, &nearest, &index), 0.005, 1e-12);
  EXPECT_EQ(index, 1);
  EXPECT_NEAR((nearest - Eigen::Vector3d(0.5, 1, 0)).norm(), 0.0, 1e-12);
  index = 7;
  EXPECT_EQ(DistanceToLines({0, 0, 0}, {}, nullptr, &index), 1e9);
  EXPECT_EQ(index, 7);
}

TEST(Flat, FirstLineIsTheTrunkTheRestHangOnIt) {
  const std::vector<Cane> canes = {MakeCane(1, {0, 0, 0}, {0, 0, 1}, 0.01),
                                   MakeCane(2, {0, 0, 1}, {1, 0, 1}, 0.004),
                                   MakeCane(3, {0, 0, 1}, {-1, 0, 1}, 0.004)};
  const VineModel model = Flat({canes[0].polyline, canes[1].polyline, canes[2].polyline});
  ASSERT_EQ(model.canes.size(), 3u);
  EXPECT_EQ(model.canes[0].kind, CaneKind::kTrunk);
  EXPECT_FALSE(model.canes[0].parent_id.has_value());
  for (int i : {1, 2}) {
    EXPECT_EQ(model.canes[i].kind, CaneKind::kCane);
    EXPECT_EQ(model.canes[i].parent_id, model.canes[0].id);
    EXPECT_EQ(model.canes[i].polyline.points, canes[i].polyline.points);
  }
}

TEST(OverrideFromEnv, SetsOnlyWhatTheEnvironmentGives) {
  unsetenv("VB_DIAGNOSE_UTIL_TEST");
  double d = 1.5;
  int n = 3;
  bool b = true;
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d));
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &n));
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &b));
  EXPECT_EQ(d, 1.5);
  EXPECT_EQ(n, 3);
  EXPECT_TRUE(b);
  setenv("VB_DIAGNOSE_UTIL_TEST", "0", 1);
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d));
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &n));
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &b));
  EXPECT_EQ(d, 0.0);
  EXPECT_EQ(n, 0);
  EXPECT_FALSE(b);
  setenv("VB_DIAGNOSE_UTIL_TEST", "2.25", 1);
  OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d);
  EXPECT_EQ(d, 2.25);
  unsetenv("VB_DIAGNOSE_UTIL_TEST");
}

TEST(ListFromEnv, ParsesACommaListUpToTheFirstNonNumber) {
  unsetenv("VB_DIAGNOSE_UTIL_LIST");
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({7.0}));
  setenv("VB_DIAGNOSE_UTIL_LIST", "1,2.5,-0.1", 1);
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({1.0, 2.5, -0.1}));
  setenv("VB_DIAGNOSE_UTIL_LIST", "0.3,x,4", 1);
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({0.3}));
  unsetenv("VB_DIAGNOSE_UTIL_LIST");
}

}  // namespace
}  // namespace vb::reconstruct
