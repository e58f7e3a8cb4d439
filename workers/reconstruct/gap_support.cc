// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/gap_support.h"

#include <algorithm>
#include <cmath>

namespace vb::reconstruct {
namespace {

bool WoodNear(const View2D& view, int x, int y, int tolerance) {
  for (int dy = -tolerance; dy <= tolerance; ++dy) {
    for (int dx = -tolerance; dx <= tolerance; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx < 0 || yy < 0 || xx >= view.classes.width || yy >= view.classes.height) continue;
      // Any non-background class: cane wood, or a wire or post in front of it.
      if (view.classes.at(xx, yy) != PixelClass::kBackground) return true;
    }
  }
  return false;
}

}  // namespace

double GapSupport(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const std::vector<View2D>& views, const RigCalibration& rig,
                  const GapSupportOptions& options) {
  if (!a.allFinite() || !b.allFinite()) return 0.0;
  const double length = (b - a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / options.step_m)));
  const size_t n = std::min(views.size(), rig.cameras.size());
  int supported = 0;
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / steps);
    int seen = 0;
    bool wood = true;
    for (size_t v = 0; v < n && wood; ++v) {
      const View2D& view = views[v];
      if (view.classes.width <= 0) continue;
      const auto uv = rig.cameras[v].Project(p);
      if (!uv || !rig.cameras[v].InImage(*uv)) continue;
      ++seen;
      wood = WoodNear(view, static_cast<int>(std::lround(uv->x())),
                      static_cast<int>(std::lround(uv->y())), options.tolerance_px);
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
  const double length = (b - a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / options.step_m)));
  const size_t n = std::min(views.size(), rig.cameras.size());
  for (size_t v = 0; v < n; ++v) {
    const View2D& view = views[v];
    if (view.classes.width <= 0) continue;
    int wood = 0;
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / steps);
      const auto uv = rig.cameras[v].Project(p);
      if (!uv || !rig.cameras[v].InImage(*uv)) continue;
      wood += WoodNear(view, static_cast<int>(std::lround(uv->x())),
                       static_cast<int>(std::lround(uv->y())), options.tolerance_px);
    }
    out[v] = static_cast<double>(wood) / (steps + 1);
  }
  return out;
}

}  // namespace vb::reconstruct
