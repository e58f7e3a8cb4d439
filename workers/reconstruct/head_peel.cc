// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_peel.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "opencv2/imgproc.hpp"

namespace vb::reconstruct {
namespace {

struct Projected {
  cv::Point px;
  int radius_px = 0;
};

std::optional<Projected> ProjectCanePoint(const CameraCalibration& camera,
                                          const Eigen::Vector3d& p, double radius_m) {
  const double depth = (camera.camera_from_platform() * p).z();
  if (!(depth > radius_m)) return std::nullopt;
  const auto uv = camera.Project(p);
  if (!uv || !std::isfinite(uv->x()) || !std::isfinite(uv->y())) return std::nullopt;
  // Points far outside the image are left out (cv::line clips, but not huge coordinates).
  if (std::abs(uv->x()) > 1e5 || std::abs(uv->y()) > 1e5) return std::nullopt;
  Projected out;
  out.px = cv::Point(static_cast<int>(std::lround(uv->x())),
                     static_cast<int>(std::lround(uv->y())));
  out.radius_px = std::max(1, static_cast<int>(std::lround(camera.camera_matrix(0, 0) * radius_m /
                                                           depth)));
  return out;
}

}  // namespace

std::vector<uint8_t> PeelCanesOffSilhouette(const View2D& view, const CameraCalibration& camera,
                                            const std::vector<Eigen::Vector3d>& canes,
                                            const HeadOptions& options) {
  std::vector<uint8_t> peeled = view.thick_mask;
  if (canes.empty() || view.width <= 0 || view.height <= 0) return peeled;
  cv::Mat mask(view.height, view.width, CV_8U, peeled.data());
  cv::Mat drawn = cv::Mat::zeros(view.height, view.width, CV_8U);
  for (size_t i = 0; i < canes.size(); ++i) {
    const auto a = ProjectCanePoint(camera, canes[i], options.peel_cane_radius_m);
    if (!a) continue;
    const bool linked_before = i > 0 && (canes[i] - canes[i - 1]).norm() < options.peel_link_m;
    const bool linked_after =
        i + 1 < canes.size() && (canes[i + 1] - canes[i]).norm() < options.peel_link_m;
    if (!linked_before && !linked_after) cv::circle(drawn, a->px, a->radius_px, 255, cv::FILLED);
    if (!linked_after) continue;
    const auto b = ProjectCanePoint(camera, canes[i + 1], options.peel_cane_radius_m);
    if (!b) continue;
    cv::line(drawn, a->px, b->px, 255, a->radius_px + b->radius_px);
  }
  // Distance of each silhouette pixel to the nearest pixel outside it.
  cv::Mat to_background;
  cv::distanceTransform(mask != 0, to_background, cv::DIST_L2, 3);
  const float depth = static_cast<float>(options.peel_depth_px);
  for (int y = 0; y < view.height; ++y) {
    uint8_t* row = mask.ptr<uint8_t>(y);
    const uint8_t* cane = drawn.ptr<uint8_t>(y);
    const float* d = to_background.ptr<float>(y);
    for (int x = 0; x < view.width; ++x)
      if (row[x] != 0 && cane[x] != 0 && d[x] <= depth) row[x] = 0;
  }
  return peeled;
}

}  // namespace vb::reconstruct
