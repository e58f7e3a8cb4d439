// SPDX-License-Identifier: Apache-2.0
// Probes of one view's 2D evidence at the projection of a 3D point, for the stages that test
// points they add against the images (extend.h; grow.h's checks are the same probes): where the
// point lands inside an image, the radius it projects to, whether wood lies near that pixel, and
// its distance to the skeleton. Also the checks of option fields that those stages share.
// Pixel coordinates follow core/calibration.h (pixel centres at integers). A view's maps may be
// missing (empty or not width * height): each probe says what it returns then. Pure functions of
// their arguments; thread-safe.
#pragma once

#include <optional>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "core/calibration.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// OK when `value` is finite and > 0; else INVALID_ARGUMENT "<stage>.<field> must be finite and
// > 0, is <value>".
absl::Status CheckPositive(double value, absl::string_view stage, absl::string_view field);
// OK when `value` is finite and >= 0; else INVALID_ARGUMENT "<stage>.<field> must be finite and
// >= 0, is <value>".
absl::Status CheckNonNegative(double value, absl::string_view stage, absl::string_view field);

// The pixel of p in `camera` when it lies at least `margin_px` inside the camera's image
// (margin_px <= x <= image_width - 1 - margin_px, likewise y); nullopt otherwise or when p does
// not project (CameraCalibration::Project).
std::optional<Eigen::Vector2d> ProjectInside(const CameraCalibration& camera,
                                             const Eigen::Vector3d& p, int margin_px);

// The radius in pixels that a cross-section of `radius_m` at p subtends in `camera`:
// radius_m * fx / depth, the depth (p's z in the camera frame) taken as at least `min_depth_m`.
double ProjectedRadiusPx(const CameraCalibration& camera, const Eigen::Vector3d& p,
                         double radius_m, double min_depth_m = 0.05);

// Whether any pixel of the (2 r + 1)^2 square centred on uv's nearest pixel (clipped to the
// image) is not background: wood, a wire or a post (these may hide wood). True when the view has
// no class image, so that a missing map contradicts nothing.
bool WoodNear(const View2D& view, const Eigen::Vector2d& uv, int r);

// Whether any pixel whose centre lies within radius_px + 0.5 of uv is not background (the
// pixels of the disc around uv that the projection of a cross-section of radius radius_px
// touches). True when the view has no class image.
bool WoodInDisc(const View2D& view, const Eigen::Vector2d& uv, double radius_px);

// Whether the view has its skeleton distance map (View2D::centreline_distance_px, width * height).
bool HasCentrelineDistance(const View2D& view);

// The skeleton distance (px) at uv's nearest pixel, clamped into the image;
// kCentrelineDistanceCapPx when the view has no distance map.
double CentrelineDistanceAt(const View2D& view, const Eigen::Vector2d& uv);

// The same, interpolated bilinearly between the four pixel centres around uv (clamped into the
// image; the image must be at least 2 x 2).
double CentrelineDistanceBilinear(const View2D& view, const Eigen::Vector2d& uv);

}  // namespace vb::reconstruct
