// SPDX-License-Identifier: Apache-2.0
#include "core/calibration.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb {
namespace {

CameraCalibration WideCamera() {
  CameraCalibration c;
  c.name = "cam0";
  c.image_width = 1280;
  c.image_height = 1024;
  c.camera_matrix << 540, 0, 643.5, 0, 540, 508.2, 0, 0, 1;
  c.distortion = {-0.28, 0.09, 0.0005, -0.0003, -0.012};
  // Looking along platform +y, image down = platform -z.
  c.rotation_camera_from_platform << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  c.translation_camera_from_platform = -c.rotation_camera_from_platform * Eigen::Vector3d(0.1, 0, 1.0);
  return c;
}

TEST(CameraCalibration, ProjectsAlongOpticalAxisToPrincipalPoint) {
  const CameraCalibration c = WideCamera();
  ASSERT_TRUE(c.Validate().ok());
  EXPECT_TRUE(c.CentreInPlatform().isApprox(Eigen::Vector3d(0.1, 0, 1.0)));
  const auto uv = c.Project({0.1, 0.8, 1.0});
  ASSERT_TRUE(uv.has_value());
  EXPECT_NEAR(uv->x(), 643.5, 1e-9);
  EXPECT_NEAR(uv->y(), 508.2, 1e-9);
  // A point above the camera appears higher in the image (smaller v).
  EXPECT_LT(c.Project({0.1, 0.8, 1.3})->y(), 508.2);
  EXPECT_FALSE(c.Project({0.1, -0.5, 1.0}).has_value());  // behind
}

TEST(CameraCalibration, PointsBeyondTheDistortionFoldAreNotProjected) {
  const CameraCalibration c = WideCamera();
  // r * (1 + k1 r^2 + k2 r^4 + k3 r^6) peaks near r = 1.8 for this lens: a point at r = 2.5
  // would otherwise land back inside the image.
  const Eigen::Vector3d far_out(0.1 + 2.5 * 0.8, 0.8, 1.0);
  const Eigen::Vector2d folded = c.NormalisedToPixel({2.5, 0.0});
  ASSERT_TRUE(c.InImage(folded));  // what the bare polynomial would claim
  EXPECT_FALSE(c.Project(far_out).has_value());
  EXPECT_TRUE(c.Project({0.1 + 1.2 * 0.8, 0.8, 1.0}).has_value());
}

TEST(CameraCalibration, PixelToNormalisedInvertsDistortion) {
  const CameraCalibration c = WideCamera();
  for (double x = -1.1; x <= 1.1; x += 0.1) {
    for (double y = -0.9; y <= 0.9; y += 0.1) {
      const Eigen::Vector2d uv = c.NormalisedToPixel({x, y});
      const Eigen::Vector2d back = c.PixelToNormalised(uv);
      EXPECT_NEAR(back.x(), x, 1e-8) << x << "," << y;
      EXPECT_NEAR(back.y(), y, 1e-8) << x << "," << y;
    }
  }
}

TEST(CameraCalibration, RayThroughProjectionHitsThePoint) {
  const CameraCalibration c = WideCamera();
  const Eigen::Vector3d p(-0.6, 0.85, 1.45);
  const Eigen::Vector2d uv = *c.Project(p);
  const Eigen::Vector3d ray = c.RayInPlatform(uv);
  const Eigen::Vector3d to_p = (p - c.CentreInPlatform()).normalized();
  EXPECT_NEAR(ray.dot(to_p), 1.0, 1e-12);
}

TEST(CameraCalibration, ValidateRejectsBadValues) {
  CameraCalibration c = WideCamera();
  c.camera_matrix(0, 0) = std::nan("");
  EXPECT_NE(c.Validate().message().find("camera_matrix"), std::string::npos);
  c = WideCamera();
  c.camera_matrix(1, 1) = 0.0;
  EXPECT_NE(c.Validate().message().find("singular"), std::string::npos);
  c = WideCamera();
  c.rotation_camera_from_platform(0, 0) = 1.1;
  EXPECT_NE(c.Validate().message().find("rotation_camera_from_platform"), std::string::npos);
  c = WideCamera();
  c.rotation_camera_from_platform *= -1.0;  // orthogonal but a reflection
  EXPECT_EQ(c.Validate().code(), absl::StatusCode::kInvalidArgument);
  c = WideCamera();
  c.distortion[4] = INFINITY;
  EXPECT_NE(c.Validate().message().find("distortion_coefficients[4]"), std::string::npos);
  c = WideCamera();
  c.image_width = 0;
  EXPECT_NE(c.Validate().message().find("image_width"), std::string::npos);
}

TEST(RigCalibration, ValidateRejectsEmptyAndDuplicateNames) {
  RigCalibration rig;
  EXPECT_EQ(rig.Validate().code(), absl::StatusCode::kInvalidArgument);
  rig.cameras = {WideCamera(), WideCamera()};
  EXPECT_NE(rig.Validate().message().find("duplicate"), std::string::npos);
  rig.cameras[1].name = "cam1";
  EXPECT_TRUE(rig.Validate().ok());
  EXPECT_EQ(rig.IndexOf("cam1"), 1u);
  EXPECT_FALSE(rig.IndexOf("cam9").has_value());
}

TEST(RigCalibration, ValidateRejectsBadFiducials) {
  RigCalibration rig;
  rig.cameras = {WideCamera()};
  rig.fiducials = {{"fid0", Eigen::Vector3d(0, 1.25, 0.3), 0.02},
                   {"fid1", Eigen::Vector3d(0.5, 1.25, 0.3), 0.02}};
  EXPECT_TRUE(rig.Validate().ok());
  rig.fiducials[1].name = "fid0";
  EXPECT_NE(rig.Validate().message().find("duplicate name 'fid0'"), std::string::npos);
  rig.fiducials[1].name = "fid1";
  rig.fiducials[1].radius_m = 0.0;
  EXPECT_NE(rig.Validate().message().find("fid1: radius_m"), std::string::npos);
  rig.fiducials[1].radius_m = 0.02;
  rig.fiducials[1].position_in_platform.z() = std::nan("");
  EXPECT_NE(rig.Validate().message().find("fid1: position"), std::string::npos);
}

}  // namespace
}  // namespace vb
