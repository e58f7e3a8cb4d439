// SPDX-License-Identifier: Apache-2.0
// The joint refinement's checks of its inputs and options, and its rejection test
// (cane_fit_internal.h).
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/cane_fit_internal.h"

namespace vb::reconstruct {
namespace cane_fit_internal {
namespace {

// Coordinates beyond this (metres) are garbage, not a vine; they would only produce overflow.
constexpr double kMaxCoordinateM = 1000.0;

}  // namespace

absl::Status ValidateViews(const std::vector<View2D>& views, const RigCalibration& rig) {
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("views: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  for (size_t v = 0; v < views.size(); ++v) {
    const View2D& view = views[v];
    const CameraCalibration& camera = rig.cameras[v];
    const std::string what = absl::StrCat("views[", v, "]");
    if (view.width != camera.image_width || view.height != camera.image_height) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": size ", view.width, "x", view.height,
                                                     " differs from camera '", camera.name, "' (",
                                                     camera.image_width, "x", camera.image_height,
                                                     ")"));
    }
    const size_t pixels = static_cast<size_t>(view.width) * view.height;
    if (view.centreline_distance_px.size() != pixels) {
      return absl::InvalidArgumentError(absl::StrCat(
          what, ": centreline_distance_px has ", view.centreline_distance_px.size(),
          " values, expected ", pixels));
    }
    if (view.classes.width != view.width || view.classes.height != view.height ||
        view.classes.data.size() != pixels) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": classes image is missing or mis-sized"));
    }
    for (size_t i = 0; i < pixels; ++i) {
      if (!std::isfinite(view.centreline_distance_px[i])) {
        return absl::InvalidArgumentError(absl::StrCat(
            what, ": centreline_distance_px is not finite at pixel (", i % view.width, ", ",
            i / view.width, ")"));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status ValidateModel(const VineModel& model) {
  if (absl::Status s = model.Validate(); !s.ok()) return s;
  for (size_t i = 0; i < model.canes.size(); ++i) {
    const Cane& cane = model.canes[i];
    for (size_t k = 0; k < cane.polyline.points.size(); ++k) {
      if (cane.polyline.points[k].cwiseAbs().maxCoeff() > kMaxCoordinateM ||
          cane.polyline.radii[k] > kMaxCoordinateM) {
        return absl::InvalidArgumentError(absl::StrCat("canes[", i, "] (id ", cane.id.value,
                                                       "): points[", k, "] is beyond 1 km"));
      }
    }
  }
  return absl::OkStatus();
}

std::pair<double, int> ForegroundFraction(const Polyline3& line, const std::vector<View2D>& views,
                                          const RigCalibration& rig, double tolerance_px) {
  const int reach = static_cast<int>(std::ceil(tolerance_px));
  int in_image = 0, on_wood = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    const View2D& view = views[v];
    for (const Eigen::Vector3d& p : line.points) {
      const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(p);
      if (!uv || !rig.cameras[v].InImage(*uv)) continue;
      ++in_image;
      const int x0 = static_cast<int>(std::lround(uv->x()));
      const int y0 = static_cast<int>(std::lround(uv->y()));
      bool found = false;
      for (int dy = -reach; dy <= reach && !found; ++dy) {
        for (int dx = -reach; dx <= reach && !found; ++dx) {
          const int x = x0 + dx, y = y0 + dy;
          if (x < 0 || y < 0 || x >= view.width || y >= view.height) continue;
          if (dx * dx + dy * dy > tolerance_px * tolerance_px) continue;
          found = view.IsForeground(x, y);
        }
      }
      on_wood += found;
    }
  }
  return {in_image > 0 ? static_cast<double>(on_wood) / in_image : 0.0, in_image};
}

}  // namespace cane_fit_internal

absl::Status FitOptions::Validate() const {
  const std::pair<const char*, double> positive[] = {
      {"point_spacing_m", point_spacing_m},       {"reprojection_sd_px", reprojection_sd_px},
      {"pseudo_huber_t_sd", pseudo_huber_t_sd},   {"kink_sd_m", kink_sd_m},
      {"spacing_sd_m", spacing_sd_m},             {"pin_sd_m", pin_sd_m},
      {"detached_base_sd_m", detached_base_sd_m}, {"function_tolerance", function_tolerance},
      {"unseen_prior_sd_m", unseen_prior_sd_m},
      {"foreground_tolerance_px", foreground_tolerance_px}};
  for (const auto& [name, value] : positive) {
    if (!(std::isfinite(value) && value > 0.0)) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": must be finite and > 0, is ", value));
    }
  }
  for (const auto& [name, value] : {std::pair{"attach_distance_m", attach_distance_m},
                                    std::pair{"trunk_unseen_keep_m", trunk_unseen_keep_m},
                                    std::pair{"ground_snap_m", ground_snap_m}}) {
    if (!(std::isfinite(value) && value >= 0.0)) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": must be finite and >= 0, is ", value));
    }
  }
  for (const auto& [name, value] :
       {std::pair{"max_outside_fraction", max_outside_fraction},
        std::pair{"min_foreground_fraction", min_foreground_fraction}}) {
    if (!(value >= 0.0 && value <= 1.0)) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": must be in [0, 1], is ", value));
    }
  }
  if (max_iterations < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_iterations: must be >= 1, is ", max_iterations));
  }
  if (trunk_min_views < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("trunk_min_views: must be >= 0, is ", trunk_min_views));
  }
  if (min_visible_points < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("min_visible_points: must be >= 1, is ", min_visible_points));
  }
  const Eigen::AlignedBox3d& box = working_volume.box;
  if (!box.min().allFinite() || !box.max().allFinite() || box.isEmpty()) {
    return absl::InvalidArgumentError("working_volume: box must be finite and non-empty");
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
