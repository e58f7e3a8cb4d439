// SPDX-License-Identifier: Apache-2.0
#include "core/calibration.h"

#include <cmath>
#include <unordered_set>

#include "absl/strings/str_cat.h"

namespace vb {

absl::Status CameraCalibration::Validate() const {
  const std::string what = absl::StrCat("camera '", name, "'");
  if (name.empty()) return absl::InvalidArgumentError("camera name: empty");
  if (image_width <= 0 || image_height <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": image_width and image_height must be > 0, are ",
                                                   image_width, "x", image_height));
  }
  const Eigen::Matrix3d& k = camera_matrix;
  if (!k.allFinite()) return absl::InvalidArgumentError(what + ": camera_matrix is not finite");
  if (k(0, 0) <= 0.0 || k(1, 1) <= 0.0 || k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 ||
      k(2, 2) != 1.0) {
    return absl::InvalidArgumentError(
        what + ": camera_matrix is singular or malformed (need fx, fy > 0 and last row 0 0 1)");
  }
  for (size_t i = 0; i < distortion.size(); ++i) {
    if (!std::isfinite(distortion[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ": distortion_coefficients[", i, "] is not finite"));
    }
  }
  const Eigen::Matrix3d& r = rotation_camera_from_platform;
  if (!r.allFinite()) {
    return absl::InvalidArgumentError(what + ": rotation_camera_from_platform is not finite");
  }
  const double orthogonality_error = (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality_error > 1e-6 || std::abs(r.determinant() - 1.0) > 1e-6) {
    return absl::InvalidArgumentError(absl::StrCat(
        what, ": rotation_camera_from_platform is not a rotation (|R R^T - I| = ",
        orthogonality_error, ", det = ", r.determinant(), ")"));
  }
  if (!translation_camera_from_platform.allFinite()) {
    return absl::InvalidArgumentError(what + ": translation_camera_from_platform is not finite");
  }
  return absl::OkStatus();
}

Eigen::Isometry3d CameraCalibration::camera_from_platform() const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotation_camera_from_platform;
  t.translation() = translation_camera_from_platform;
  return t;
}

Eigen::Vector3d CameraCalibration::CentreInPlatform() const {
  return -rotation_camera_from_platform.transpose() * translation_camera_from_platform;
}

std::optional<Eigen::Vector2d> CameraCalibration::Project(const Eigen::Vector3d& p_in_platform) const {
  const Eigen::Vector3d p = rotation_camera_from_platform * p_in_platform + translation_camera_from_platform;
  if (p.z() <= 1e-9) return std::nullopt;
  const double x = p.x() / p.z();
  const double y = p.y() / p.z();
  // Beyond the fold of the radial polynomial (where r * radial(r) stops increasing) the model
  // maps points from outside the field of view back into the image; they are not seen.
  const double u = x * x + y * y;
  const auto& [k1, k2, p1, p2, k3] = distortion;
  if (1.0 + u * (3.0 * k1 + u * (5.0 * k2 + u * 7.0 * k3)) <= 0.0) return std::nullopt;
  return NormalisedToPixel(Eigen::Vector2d(x, y));
}

Eigen::Vector2d CameraCalibration::NormalisedToPixel(const Eigen::Vector2d& xy) const {
  const double x = xy.x();
  const double y = xy.y();
  const auto& [k1, k2, p1, p2, k3] = distortion;
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  return {camera_matrix(0, 0) * xd + camera_matrix(0, 1) * yd + camera_matrix(0, 2),
          camera_matrix(1, 1) * yd + camera_matrix(1, 2)};
}

Eigen::Vector2d CameraCalibration::PixelToNormalised(const Eigen::Vector2d& uv) const {
  const double fx = camera_matrix(0, 0);
  const double fy = camera_matrix(1, 1);
  const double yd = (uv.y() - camera_matrix(1, 2)) / fy;
  const double xd = (uv.x() - camera_matrix(0, 2) - camera_matrix(0, 1) * yd) / fx;
  const auto& [k1, k2, p1, p2, k3] = distortion;
  double x = xd;
  double y = yd;
  // Fixed-point iteration as cv::undistortPoints; converges quickly for moderate distortion.
  for (int it = 0; it < 50; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    const double nx = (xd - dx) / radial;
    const double ny = (yd - dy) / radial;
    const double change = std::abs(nx - x) + std::abs(ny - y);
    x = nx;
    y = ny;
    if (change < 1e-14) break;
  }
  return {x, y};
}

Eigen::Vector3d CameraCalibration::RayInPlatform(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d xy = PixelToNormalised(uv);
  return (rotation_camera_from_platform.transpose() * Eigen::Vector3d(xy.x(), xy.y(), 1.0)).normalized();
}

absl::Status Fiducial::Validate() const {
  if (name.empty()) return absl::InvalidArgumentError("fiducial name: empty");
  if (!position_in_platform.allFinite()) {
    return absl::InvalidArgumentError(absl::StrCat("fiducial ", name, ": position is not finite"));
  }
  if (!(std::isfinite(radius_m) && radius_m > 0.0 && radius_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("fiducial ", name, ": radius_m must be in (0, 0.5], is ", radius_m));
  }
  return absl::OkStatus();
}

absl::Status RigCalibration::Validate() const {
  if (cameras.empty()) return absl::InvalidArgumentError("cameras: the rig has no cameras");
  std::unordered_set<std::string> names;
  for (const CameraCalibration& c : cameras) {
    if (absl::Status s = c.Validate(); !s.ok()) return s;
    if (!names.insert(c.name).second) {
      return absl::InvalidArgumentError(absl::StrCat("cameras: duplicate camera name '", c.name, "'"));
    }
  }
  std::unordered_set<std::string> fiducial_names;
  for (const Fiducial& f : fiducials) {
    if (absl::Status s = f.Validate(); !s.ok()) return s;
    if (!fiducial_names.insert(f.name).second) {
      return absl::InvalidArgumentError(absl::StrCat("fiducials: duplicate name '", f.name, "'"));
    }
  }
  return absl::OkStatus();
}

std::optional<size_t> RigCalibration::IndexOf(const std::string& name) const {
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].name == name) return i;
  }
  return std::nullopt;
}

}  // namespace vb
