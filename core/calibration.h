// SPDX-License-Identifier: Apache-2.0
// Calibrated cameras of the rig. The camera model is OpenCV's (pinhole + Brown-Conrady
// distortion k1 k2 p1 p2 k3) so that pixels agree with cv::projectPoints:
//   x_cam = R * x_platform + t;  (x, y) = x_cam.xy / x_cam.z;  distort;  u = fx x'' + cx, ...
// Plain value types; thread-compatible.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "Eigen/Core"
#include "Eigen/Geometry"

namespace vb {

struct CameraCalibration {
  std::string name;
  int image_width = 0;
  int image_height = 0;
  Eigen::Matrix3d camera_matrix = Eigen::Matrix3d::Identity();     // [fx 0 cx; 0 fy cy; 0 0 1]
  std::array<double, 5> distortion{};                              // k1 k2 p1 p2 k3
  Eigen::Matrix3d rotation_camera_from_platform = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_camera_from_platform = Eigen::Vector3d::Zero();  // metres

  // INVALID_ARGUMENT naming the field (prefixed by the camera name) for: empty name, size <= 0,
  // non-finite or singular camera matrix (fx, fy <= 0 or bottom row not [0 0 1]), non-finite
  // distortion, rotation not orthonormal with det +1 (tolerance 1e-6), non-finite translation.
  absl::Status Validate() const;

  Eigen::Isometry3d camera_from_platform() const;
  // Camera centre in the platform frame.
  Eigen::Vector3d CentreInPlatform() const;

  // Pixel of a platform point; nullopt if it lies behind (or on) the image plane, or beyond the
  // fold of the radial distortion (where d(r * radial(r))/dr <= 0: the lens model would map a
  // point outside the field of view back into the image). Does not check the image bounds.
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_in_platform) const;
  // Applies distortion to normalised coordinates (x/z, y/z) and returns pixel coordinates.
  Eigen::Vector2d NormalisedToPixel(const Eigen::Vector2d& xy) const;
  // Inverse of NormalisedToPixel by fixed-point iteration (as cv::undistortPoints); accurate to
  // ~1e-9 within the field of view of realistic lenses.
  Eigen::Vector2d PixelToNormalised(const Eigen::Vector2d& uv) const;
  // Unit ray direction, in the platform frame, through pixel uv (pixel centres at integers).
  Eigen::Vector3d RayInPlatform(const Eigen::Vector2d& uv) const;
  bool InImage(const Eigen::Vector2d& uv) const {
    return uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < image_width - 0.5 &&
           uv.y() < image_height - 0.5;
  }
};

// A fiducial marker on the platform whose position was surveyed with the rig's calibration: a
// white disc printed on the backdrop (or on the frame), facing the cameras. Seen in every stop's
// images, it anchors the calibration there (workers/reconstruct/fiducials.h, rig_refine.h).
struct Fiducial {
  std::string name;
  Eigen::Vector3d position_in_platform = Eigen::Vector3d::Zero();  // centre of the disc, metres
  double radius_m = 0.02;                                          // disc radius

  // INVALID_ARGUMENT naming the field (prefixed by the fiducial's name): empty name, position
  // not finite, radius not finite or outside (0, 0.5] m.
  absl::Status Validate() const;
};

// The calibrated rig: every camera's intrinsics and pose in the platform frame, and the
// platform's surveyed fiducials (none on a rig without them).
struct RigCalibration {
  std::vector<CameraCalibration> cameras;
  std::vector<Fiducial> fiducials;

  // Validates each camera and fiducial and requires >= 1 camera, unique camera names and unique
  // fiducial names.
  absl::Status Validate() const;
  // Index of the named camera, or nullopt.
  std::optional<size_t> IndexOf(const std::string& name) const;
};

}  // namespace vb
