// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/image_probes.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

bool HasClasses(const View2D& view) {
  return view.classes.data.size() == static_cast<size_t>(view.width) * view.height;
}

}  // namespace

absl::Status CheckPositive(double value, absl::string_view stage, absl::string_view field) {
  if (!std::isfinite(value) || value <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(stage, ".", field, " must be finite and > 0, is ", value));
  }
  return absl::OkStatus();
}

absl::Status CheckNonNegative(double value, absl::string_view stage, absl::string_view field) {
  if (!std::isfinite(value) || value < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(stage, ".", field, " must be finite and >= 0, is ", value));
  }
  return absl::OkStatus();
}

std::optional<Eigen::Vector2d> ProjectInside(const CameraCalibration& camera,
                                             const Eigen::Vector3d& p, int margin_px) {
  const std::optional<Eigen::Vector2d> uv = camera.Project(p);
  const int m = margin_px;
  if (!uv || uv->x() < m || uv->y() < m || uv->x() > camera.image_width - 1 - m ||
      uv->y() > camera.image_height - 1 - m) {
    return std::nullopt;
  }
  return uv;
}

double ProjectedRadiusPx(const CameraCalibration& camera, const Eigen::Vector3d& p,
                         double radius_m, double min_depth_m) {
  const double depth = (camera.camera_from_platform() * p).z();
  return radius_m * camera.camera_matrix(0, 0) / std::max(depth, min_depth_m);
}

bool WoodNear(const View2D& view, const Eigen::Vector2d& uv, int r) {
  if (!HasClasses(view)) return true;
  const int cx = static_cast<int>(std::lround(uv.x())), cy = static_cast<int>(std::lround(uv.y()));
  for (int y = std::max(0, cy - r); y <= std::min(view.height - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(view.width - 1, cx + r); ++x)
      if (view.classes.at(x, y) != PixelClass::kBackground) return true;
  return false;
}

bool WoodInDisc(const View2D& view, const Eigen::Vector2d& uv, double radius_px) {
  if (!HasClasses(view)) return true;
  const int r = static_cast<int>(std::ceil(radius_px));
  const double reach2 = (radius_px + 0.5) * (radius_px + 0.5);
  const int cx = static_cast<int>(std::lround(uv.x())), cy = static_cast<int>(std::lround(uv.y()));
  for (int y = std::max(0, cy - r); y <= std::min(view.height - 1, cy + r); ++y) {
    for (int x = std::max(0, cx - r); x <= std::min(view.width - 1, cx + r); ++x) {
      if ((x - uv.x()) * (x - uv.x()) + (y - uv.y()) * (y - uv.y()) > reach2) continue;
      if (view.classes.at(x, y) != PixelClass::kBackground) return true;
    }
  }
  return false;
}

bool HasCentrelineDistance(const View2D& view) {
  return view.centreline_distance_px.size() == static_cast<size_t>(view.width) * view.height;
}

double CentrelineDistanceAt(const View2D& view, const Eigen::Vector2d& uv) {
  if (!HasCentrelineDistance(view)) return kCentrelineDistanceCapPx;
  const int x = std::clamp(static_cast<int>(std::lround(uv.x())), 0, view.width - 1);
  const int y = std::clamp(static_cast<int>(std::lround(uv.y())), 0, view.height - 1);
  return view.centreline_distance_px[static_cast<size_t>(y) * view.width + x];
}

double CentrelineDistanceBilinear(const View2D& view, const Eigen::Vector2d& uv) {
  if (!HasCentrelineDistance(view)) return kCentrelineDistanceCapPx;
  const int x0 = std::clamp(static_cast<int>(std::floor(uv.x())), 0, view.width - 2);
  const int y0 = std::clamp(static_cast<int>(std::floor(uv.y())), 0, view.height - 2);
  const double fx = std::clamp(uv.x() - x0, 0.0, 1.0), fy = std::clamp(uv.y() - y0, 0.0, 1.0);
  const auto at = [&](int x, int y) {
    return static_cast<double>(
        view.centreline_distance_px[static_cast<size_t>(y) * view.width + x]);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace vb::reconstruct
