// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <cmath>

#include "workers/reconstruct/grow_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct::grow_internal {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

ViewProbe::ViewProbe(const View2D& view, const CameraCalibration& camera, int margin_px)
    : view_(view), camera_(camera), margin_(margin_px),
      has_thick_(view.thick_mask.size() == static_cast<size_t>(view.width) * view.height) {}

std::optional<Eigen::Vector2d> ViewProbe::Inside(const Eigen::Vector3d& p) const {
  return ProjectInside(camera_, p, margin_);
}

double ViewProbe::Distance(const Eigen::Vector2d& uv) const {
  return CentrelineDistanceBilinear(view_, uv);
}

bool ViewProbe::Thick(const Eigen::Vector2d& uv) const {
  if (!has_thick_) return false;
  const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
  return view_.thick_mask[static_cast<size_t>(y) * view_.width + x] != 0;
}

bool ViewProbe::Background(const Eigen::Vector2d& uv, const Eigen::Vector3d& p,
                           double radius_m) const {
  return !WoodInDisc(view_, uv, std::max(1.0, ProjectedRadiusPx(camera_, p, radius_m, 1e-6)));
}

GrowEvidence::GrowEvidence(const std::vector<View2D>& views, const RigCalibration& rig,
                           const GrowOptions& options)
    : options_(options) {
  for (size_t i = 0; i < views.size(); ++i)
    probes_.emplace_back(views[i], rig.cameras[i], options.image_margin_px);
}

double GrowEvidence::Cost(const Eigen::Vector3d& p) const {
  const double cap = options_.truncate_px * options_.truncate_px;
  double cost = 0;
  for (const ViewProbe& probe : probes_) {
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p);
    const double d = uv ? probe.Distance(*uv) : options_.truncate_px;
    cost += std::min(d * d, cap);
  }
  return cost;
}

Eigen::Vector3d GrowEvidence::Correct(const Eigen::Vector3d& predicted,
                                      const Eigen::Vector3d& tangent,
                                      double prior_px_per_mm) const {
  const Eigen::Vector3d u = tangent.unitOrthogonal();
  const Eigen::Vector3d w = tangent.cross(u).normalized();
  const double prior = prior_px_per_mm * 1000.0;  // px per metre of offset
  double best_a = 0, best_b = 0, best = Cost(predicted);
  const auto search = [&](double centre_a, double centre_b, double grid, int half) {
    double ba = centre_a, bb = centre_b;
    for (int i = -half; i <= half; ++i) {
      for (int j = -half; j <= half; ++j) {
        const double a = centre_a + i * grid, b = centre_b + j * grid;
        if (std::abs(a) > options_.max_offset_m + 1e-12 ||
            std::abs(b) > options_.max_offset_m + 1e-12) {
          continue;
        }
        const double c = Cost(predicted + a * u + b * w) + prior * prior * (a * a + b * b);
        if (c < best) {
          best = c;
          ba = a;
          bb = b;
        }
      }
    }
    best_a = ba;
    best_b = bb;
  };
  const int half = static_cast<int>(std::lround(options_.max_offset_m / options_.offset_grid_m));
  search(0, 0, options_.offset_grid_m, half);
  search(best_a, best_b, options_.offset_grid_m / 4, 4);
  return predicted + best_a * u + best_b * w;
}

bool GrowEvidence::AlongSkeleton(const ViewProbe& probe, const Eigen::Vector3d& p,
                                 const Eigen::Vector3d& step) const {
  if (options_.support_along_px <= 0) return true;
  for (const double sign : {-0.5, 0.5}) {
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p + sign * options_.step_m * step);
    if (uv && probe.Distance(*uv) > options_.support_along_px) return false;
  }
  return true;
}

bool GrowEvidence::EndSupported(const Eigen::Vector3d& p) const {
  int supports = 0;
  for (const ViewProbe& probe : probes_) {
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p);
    if (!uv) continue;
    if (probe.Distance(*uv) > options_.support_px) return false;
    ++supports;
  }
  return supports >= options_.min_support_views;
}

std::optional<GrowStop> GrowEvidence::Check(const Eigen::Vector3d& p,
                                            const Eigen::Vector3d& step,
                                            double radius_m) const {
  std::vector<int> supports;
  for (size_t v = 0; v < probes_.size(); ++v) {
    const std::optional<Eigen::Vector2d> uv = probes_[v].Inside(p);
    if (!uv) continue;
    if (probes_[v].Thick(*uv)) return GrowStop::kThick;
    if (probes_[v].Distance(*uv) <= options_.support_px) {
      if (AlongSkeleton(probes_[v], p, step)) supports.push_back(static_cast<int>(v));
    } else if (probes_[v].Background(*uv, p, radius_m)) {
      return GrowStop::kContradicted;
    }
  }
  if (static_cast<int>(supports.size()) < options_.min_support_views) return GrowStop::kUnsupported;
  if (supports.size() == 2) {
    // Two views fix a point along the cane only if the cane crosses their epipolar planes.
    const Eigen::Vector3d ca = probes_[supports[0]].Centre(), cb = probes_[supports[1]].Centre();
    const Eigen::Vector3d normal = (cb - ca).cross(p - ca).normalized();
    if (std::abs(normal.dot(step)) < std::sin(options_.min_epipolar_angle_deg * kDegToRad))
      return GrowStop::kUnsupported;
  }
  return std::nullopt;
}

}  // namespace vb::reconstruct::grow_internal
