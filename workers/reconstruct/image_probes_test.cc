// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/image_probes.h"

#include <cmath>
#include <limits>
#include <string>

#include "gtest/gtest.h"
#include "sim/rig.h"

namespace vb::reconstruct {
namespace {

// A w x h view of background, with a distance map of x + 10 y (px), so that reads can be told
// apart.
View2D BlankView(int w, int h) {
  View2D view;
  view.width = w;
  view.height = h;
  view.classes = ClassImage(w, h);
  view.centreline_distance_px.resize(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      view.centreline_distance_px[static_cast<size_t>(y) * w + x] = x + 10 * y;
  return view;
}

TEST(CheckPositive, AcceptsPositiveAndNamesTheFieldOtherwise) {
  EXPECT_TRUE(CheckPositive(0.5, "extend", "step_m").ok());
  for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const absl::Status s = CheckPositive(bad, "extend", "step_m");
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(std::string(s.message()).find("extend.step_m must be finite and > 0"),
              std::string::npos)
        << s;
  }
}

TEST(CheckNonNegative, AcceptsZeroAndNamesTheFieldOtherwise) {
  EXPECT_TRUE(CheckNonNegative(0.0, "grow", "trim_m").ok());
  EXPECT_TRUE(CheckNonNegative(2.0, "grow", "trim_m").ok());
  for (double bad : {-0.1, std::nan("")}) {
    const absl::Status s = CheckNonNegative(bad, "grow", "trim_m");
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(std::string(s.message()).find("grow.trim_m must be finite and >= 0"),
              std::string::npos)
        << s;
  }
}

TEST(ProjectInside, KeepsPixelsInsideTheMarginOnly) {
  const CameraCalibration camera = sim::MakeRig().value().cameras[0];
  const Eigen::Vector3d centre = camera.CentreInPlatform();
  const Eigen::Vector3d p = centre + 1.0 * camera.RayInPlatform({100.0, 200.0});
  const auto uv = ProjectInside(camera, p, 3);
  ASSERT_TRUE(uv.has_value());
  EXPECT_NEAR(uv->x(), 100.0, 1e-6);
  EXPECT_NEAR(uv->y(), 200.0, 1e-6);
  // 2.5 px from the left border: inside the image and a 2 px margin, not a 3 px one.
  const Eigen::Vector3d near_border = centre + 1.0 * camera.RayInPlatform({2.5, 200.0});
  EXPECT_TRUE(ProjectInside(camera, near_border, 0).has_value());
  EXPECT_TRUE(ProjectInside(camera, near_border, 2).has_value());
  EXPECT_FALSE(ProjectInside(camera, near_border, 3).has_value());
  const Eigen::Vector3d far_right =
      centre + 1.0 * camera.RayInPlatform({camera.image_width - 3.5, 200.0});
  EXPECT_TRUE(ProjectInside(camera, far_right, 2).has_value());
  EXPECT_FALSE(ProjectInside(camera, far_right, 3).has_value());
  // Behind the camera.
  EXPECT_FALSE(
      ProjectInside(camera, centre - 1.0 * camera.RayInPlatform({100.0, 200.0}), 0).has_value());
}

TEST(ProjectedRadiusPx, IsRadiusTimesFocalOverDepthWithAFloorOnTheDepth) {
  const CameraCalibration camera = sim::MakeRig().value().cameras[0];
  const Eigen::Vector3d centre = camera.CentreInPlatform();
  const Eigen::Vector3d ray = camera.RayInPlatform({300.0, 250.0});
  const Eigen::Vector3d p = centre + 1.5 * ray;
  const double depth = (camera.camera_from_platform() * p).z();
  ASSERT_GT(depth, 0.5);
  EXPECT_NEAR(ProjectedRadiusPx(camera, p, 0.01), 0.01 * camera.camera_matrix(0, 0) / depth,
              1e-9);
  // 1 cm from the camera: the default floor of 5 cm applies, a lower one does not.
  const Eigen::Vector3d q = centre + 0.01 * ray;
  const double q_depth = (camera.camera_from_platform() * q).z();
  EXPECT_NEAR(ProjectedRadiusPx(camera, q, 0.01), 0.01 * camera.camera_matrix(0, 0) / 0.05, 1e-9);
  EXPECT_NEAR(ProjectedRadiusPx(camera, q, 0.01, 1e-6),
              0.01 * camera.camera_matrix(0, 0) / q_depth, 1e-6);
}

TEST(WoodNear, LooksInASquareAroundTheNearestPixel) {
  View2D view = BlankView(20, 20);
  view.classes.set(10, 10, PixelClass::kForeground);
  EXPECT_TRUE(WoodNear(view, {10.2, 9.8}, 0));
  EXPECT_TRUE(WoodNear(view, {12.4, 12.4}, 2));   // a corner of the square
  EXPECT_FALSE(WoodNear(view, {12.6, 10.0}, 2));  // nearest pixel (13, 10): 3 px away
  EXPECT_FALSE(WoodNear(view, {5.0, 5.0}, 4));
  // Wires and posts may hide wood: they count as not background.
  view.classes.set(10, 10, PixelClass::kWire);
  EXPECT_TRUE(WoodNear(view, {11.0, 10.0}, 1));
  // Clipped to the image at the border.
  view.classes.set(0, 0, PixelClass::kForeground);
  EXPECT_TRUE(WoodNear(view, {-0.4, 1.0}, 1));
  // No class image: nothing is contradicted.
  view.classes = ClassImage();
  EXPECT_TRUE(WoodNear(view, {5.0, 5.0}, 0));
}

TEST(WoodInDisc, LooksInADiscHalfAPixelWiderThanTheRadius) {
  View2D view = BlankView(20, 20);
  view.classes.set(12, 12, PixelClass::kForeground);  // 2.83 px from (10, 10)
  EXPECT_FALSE(WoodInDisc(view, {10.0, 10.0}, 2.0));  // reach 2.5
  EXPECT_TRUE(WoodInDisc(view, {10.0, 10.0}, 2.4));   // reach 2.9
  EXPECT_TRUE(WoodNear(view, {10.0, 10.0}, 2));       // the square holds the corner
  view.classes.set(12, 12, PixelClass::kPost);
  EXPECT_TRUE(WoodInDisc(view, {10.0, 10.0}, 2.4));
  view.classes = ClassImage();
  EXPECT_TRUE(WoodInDisc(view, {10.0, 10.0}, 1.0));
}

TEST(CentrelineDistance, NearestPixelAndBilinearReadsClampedToTheImage) {
  View2D view = BlankView(8, 6);
  EXPECT_TRUE(HasCentrelineDistance(view));
  EXPECT_DOUBLE_EQ(CentrelineDistanceAt(view, {3.4, 2.0}), 23.0);
  EXPECT_DOUBLE_EQ(CentrelineDistanceAt(view, {3.6, 1.6}), 24.0);
  EXPECT_DOUBLE_EQ(CentrelineDistanceAt(view, {-3.0, 9.0}), 50.0);  // clamped to (0, 5)
  EXPECT_NEAR(CentrelineDistanceBilinear(view, {3.4, 2.25}), 3.4 + 22.5, 1e-9);
  EXPECT_NEAR(CentrelineDistanceBilinear(view, {7.0, 5.0}), 57.0, 1e-9);  // the last pixel
  EXPECT_NEAR(CentrelineDistanceBilinear(view, {9.0, 1.0}), 17.0, 1e-9);  // clamped to x = 7
  view.centreline_distance_px.clear();
  EXPECT_FALSE(HasCentrelineDistance(view));
  EXPECT_EQ(CentrelineDistanceAt(view, {3.0, 2.0}), kCentrelineDistanceCapPx);
  EXPECT_EQ(CentrelineDistanceBilinear(view, {3.0, 2.0}), kCentrelineDistanceCapPx);
}

}  // namespace
}  // namespace vb::reconstruct
