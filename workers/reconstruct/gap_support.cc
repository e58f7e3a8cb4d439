// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/gap_support.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

// The samples along a-b: steps + 1 of them, ends included, at most step_m apart.
int Steps(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const GapSupportOptions& options) {
  return std::max(1, static_cast<int>(std::ceil((b - a).norm() / options.step_m)));
}

Eigen::Vector3d Sample(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int k, int steps) {
  return a + (b - a) * (static_cast<double>(k) / steps);
}

// Whether the view shows wood (any non-background class: cane wood, or a wire or post in front
// of it) near p's projection through `camera`; empty where the view has no class image or p does
// not fall inside the image.
std::optional<bool> WoodSeen(const View2D& view, const CameraCalibration& camera,
                             const Eigen::Vector3d& p, const GapSupportOptions& options) {
  if (view.classes.width <= 0) return std::nullopt;
  const auto uv = camera.Project(p);
  if (!uv || !camera.InImage(*uv)) return std::nullopt;
  return WoodNear(view, *uv, options.tolerance_px);
}

}  // namespace

double GapSupport(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const std::vector<View2D>& views, const RigCalibration& rig,
                  const GapSupportOptions& options) {
  if (!a.allFinite() || !b.allFinite()) return 0.0;
  const int steps = Steps(a, b, options);
  const size_t n = std::min(views.size(), rig.cameras.size());
  int supported = 0;
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector3d p = Sample(a, b, k, steps);
    int seen = 0;
    bool wood = true;
    for (size_t v = 0; v < n && wood; ++v) {
      const std::optional<bool> at = WoodSeen(views[v], rig.cameras[v], p, options);
      if (!at) continue;
      ++seen;
      wood = *at;
    }
    supported += wood && seen >= options.min_views;
  }
  return static_cast<double>(supported) / (steps + 1);
}

std::vector<double> GapSupportByView(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const std::vector<View2D>& views, const RigCalibration& rig,
                                     const GapSupportOptions& options) {
  std::vector<double> out(views.size(), 0.0);
  if (!a.allFinite() || !b.allFinite()) return out;
  const int steps = Steps(a, b, options);
  const size_t n = std::min(views.size(), rig.cameras.size());
  for (size_t v = 0; v < n; ++v) {
    int wood = 0;
    for (int k = 0; k <= steps; ++k) {
      wood += WoodSeen(views[v], rig.cameras[v], Sample(a, b, k, steps), options).value_or(false);
    }
    out[v] = static_cast<double>(wood) / (steps + 1);
  }
  return out;
}

}  // namespace vb::reconstruct
