// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "workers/reconstruct/grow_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct::grow_internal {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

std::vector<float> WoodRadiusMap(const View2D& view) {
  const size_t size = static_cast<size_t>(view.width) * view.height;
  std::vector<float> out(size, 0.0f);
  if (view.classes.data.size() != size || size == 0) return out;
  cv::Mat wood(view.height, view.width, CV_8U);
  for (size_t i = 0; i < size; ++i)
    wood.data[i] = view.classes.data[i] == static_cast<uint8_t>(PixelClass::kBackground) ? 0 : 255;
  cv::Mat distance;
  cv::distanceTransform(wood, distance, cv::DIST_L2, cv::DIST_MASK_5);
  for (int y = 0; y < view.height; ++y) {
    const float* row = distance.ptr<float>(y);
    std::copy(row, row + view.width, out.begin() + static_cast<size_t>(y) * view.width);
  }
  return out;
}

ViewProbe::ViewProbe(const View2D& view, const CameraCalibration& camera, int margin_px,
                     const std::vector<float>* wood_radius)
    : view_(view), camera_(camera), margin_(margin_px),
      has_thick_(view.thick_mask.size() == static_cast<size_t>(view.width) * view.height),
      wood_radius_(wood_radius) {}

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

double ViewProbe::RadiusPx(const Eigen::Vector3d& p, double radius_m) const {
  return ProjectedRadiusPx(camera_, p, radius_m, 1e-6);
}

double ViewProbe::WoodRadius(const Eigen::Vector2d& uv) const {
  if (wood_radius_ == nullptr || view_.width < 2 || view_.height < 2) return 0.0;
  const int x0 = std::clamp(static_cast<int>(std::floor(uv.x())), 0, view_.width - 2);
  const int y0 = std::clamp(static_cast<int>(std::floor(uv.y())), 0, view_.height - 2);
  const double fx = std::clamp(uv.x() - x0, 0.0, 1.0), fy = std::clamp(uv.y() - y0, 0.0, 1.0);
  const auto at = [&](int x, int y) {
    return static_cast<double>((*wood_radius_)[static_cast<size_t>(y) * view_.width + x]);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

std::optional<double> ViewProbe::BandExcess(const Eigen::Vector2d& uv, double radius_px,
                                            double margin_px, double tolerance_px) const {
  if (wood_radius_ == nullptr) return std::nullopt;
  // Pixel centres: the background pixel's edge lies half a pixel nearer than its centre.
  const double to_edge = WoodRadius(uv) - 0.5;
  if (Distance(uv) + to_edge < radius_px + margin_px) return std::nullopt;
  return std::max(0.0, radius_px - to_edge - tolerance_px);
}

GrowEvidence::GrowEvidence(const std::vector<View2D>& views, const RigCalibration& rig,
                           const GrowOptions& options)
    : options_(options) {
  const bool bands = options.band_support || options.band_end_support;
  if (bands) {
    for (const View2D& view : views) wood_radius_.push_back(WoodRadiusMap(view));
  }
  for (size_t i = 0; i < views.size(); ++i) {
    probes_.emplace_back(views[i], rig.cameras[i], options.image_margin_px,
                         bands ? &wood_radius_[i] : nullptr);
  }
}

std::optional<double> GrowEvidence::BandExcess(const ViewProbe& probe, const Eigen::Vector2d& uv,
                                               const Eigen::Vector3d& p, double radius_m) const {
  return probe.BandExcess(uv, probe.RadiusPx(p, radius_m), options_.band_margin_px,
                          options_.band_tolerance_px);
}

bool GrowEvidence::InBand(const ViewProbe& probe, const Eigen::Vector2d& uv,
                          const Eigen::Vector3d& p, double radius_m) const {
  const std::optional<double> excess = BandExcess(probe, uv, p, radius_m);
  return excess && *excess <= 0.0;
}

double GrowEvidence::Cost(const Eigen::Vector3d& p, double radius_m) const {
  const double cap = options_.truncate_px * options_.truncate_px;
  double cost = 0;
  for (const ViewProbe& probe : probes_) {
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p);
    double d = uv ? probe.Distance(*uv) : options_.truncate_px;
    if (uv && options_.band_support && d > 0) {
      // In a bundle the cane may lie anywhere its cross-section stays inside the wood.
      if (const std::optional<double> excess = BandExcess(probe, *uv, p, radius_m); excess)
        d = std::min(d, *excess);
    }
    cost += std::min(d * d, cap);
  }
  return cost;
}

Eigen::Vector3d GrowEvidence::Correct(const Eigen::Vector3d& predicted,
                                      const Eigen::Vector3d& tangent, double prior_px_per_mm,
                                      double radius_m) const {
  const Eigen::Vector3d u = tangent.unitOrthogonal();
  const Eigen::Vector3d w = tangent.cross(u).normalized();
  const double prior = prior_px_per_mm * 1000.0;  // px per metre of offset
  double best_a = 0, best_b = 0, best = Cost(predicted, radius_m);
  const auto search = [&](double centre_a, double centre_b, double grid, int half) {
    double ba = centre_a, bb = centre_b;
    for (int i = -half; i <= half; ++i) {
      for (int j = -half; j <= half; ++j) {
        const double a = centre_a + i * grid, b = centre_b + j * grid;
        if (std::abs(a) > options_.max_offset_m + 1e-12 ||
            std::abs(b) > options_.max_offset_m + 1e-12) {
          continue;
        }
        const double c =
            Cost(predicted + a * u + b * w, radius_m) + prior * prior * (a * a + b * b);
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

template <typename Near>
bool GrowEvidence::Along(const ViewProbe& probe, const Eigen::Vector3d& p,
                         const Eigen::Vector3d& step, const Near& near) const {
  for (const double sign : {-0.5, 0.5}) {
    const Eigen::Vector3d q = p + sign * options_.step_m * step;
    const std::optional<Eigen::Vector2d> uv = probe.Inside(q);
    if (uv && !near(*uv, q)) return false;
  }
  return true;
}

bool GrowEvidence::EndSupported(const Eigen::Vector3d& p, double radius_m) const {
  int supports = 0;
  for (const ViewProbe& probe : probes_) {
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p);
    if (!uv) continue;
    if (probe.Distance(*uv) > options_.support_px &&
        !(options_.band_end_support && InBand(probe, *uv, p, radius_m))) {
      return false;
    }
    ++supports;
  }
  return supports >= options_.min_support_views;
}

std::optional<GrowStop> GrowEvidence::Check(const Eigen::Vector3d& p,
                                            const Eigen::Vector3d& step, double radius_m,
                                            bool* banded) const {
  if (banded != nullptr) *banded = false;
  std::vector<int> supports;
  bool used_band = false;
  for (size_t v = 0; v < probes_.size(); ++v) {
    const ViewProbe& probe = probes_[v];
    const std::optional<Eigen::Vector2d> uv = probe.Inside(p);
    if (!uv) continue;
    const auto on_skeleton = [&](const Eigen::Vector2d& at, const Eigen::Vector3d&) {
      return probe.Distance(at) <= options_.support_along_px;
    };
    const auto in_band = [&](const Eigen::Vector2d& at, const Eigen::Vector3d& q) {
      return probe.Distance(at) <= options_.support_along_px || InBand(probe, at, q, radius_m);
    };
    if (probe.Thick(*uv)) return GrowStop::kThick;
    if (probe.Distance(*uv) <= options_.support_px) {
      if (options_.support_along_px <= 0 || Along(probe, p, step, on_skeleton))
        supports.push_back(static_cast<int>(v));
    } else if (options_.band_support && InBand(probe, *uv, p, radius_m)) {
      // Inside a bundle's band: the cane's own axis need not be near the skeleton.
      if (Along(probe, p, step, in_band)) {
        supports.push_back(static_cast<int>(v));
        used_band = true;
      }
    } else if (probe.Background(*uv, p, radius_m)) {
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
  if (banded != nullptr) *banded = used_band;
  return std::nullopt;
}

}  // namespace vb::reconstruct::grow_internal
