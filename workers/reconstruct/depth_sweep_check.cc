// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/depth_sweep_check.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

bool ForegroundAt(const View2D& view, const Eigen::Vector2d& uv) {
  const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
  if (x < 0 || y < 0 || x >= view.width || y >= view.height) return false;
  return view.IsForeground(x, y);
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

// Total turning (radians) per metre of `run` resampled every `step_m`.
double TurningPerMetre(const Polyline3& run, double step_m) {
  const double length = run.Length();
  if (length <= 0.0) return 0.0;
  const int n = std::max(2, static_cast<int>(std::round(length / step_m)) + 1);
  const std::vector<double> arc = run.ArcLengths();
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < n; ++i) q.push_back(run.PointAt(length * i / (n - 1), arc));
  double turning = 0.0;
  for (int i = 1; i + 1 < n; ++i) {
    const Eigen::Vector3d a = q[i] - q[i - 1], b = q[i + 1] - q[i];
    if (a.norm() <= 0.0 || b.norm() <= 0.0) continue;
    turning += std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
  }
  return turning / length;
}

}  // namespace

double ForegroundWidthAcross(const View2D& view, const Eigen::Vector2d& uv,
                             const Eigen::Vector2d& along, double max_half_px) {
  if (view.classes.data.size() != static_cast<size_t>(view.width) * view.height ||
      along.norm() <= 0.0) {
    return 0.0;
  }
  const Eigen::Vector2d normal(-along.y() / along.norm(), along.x() / along.norm());
  std::optional<double> start;
  for (double t : {0.0, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5, 2.0, -2.0}) {
    if (ForegroundAt(view, uv + t * normal)) {
      start = t;
      break;
    }
  }
  if (!start) return 0.0;
  double hi = *start, lo = *start;
  while (hi - *start < max_half_px && ForegroundAt(view, uv + (hi + 0.5) * normal)) hi += 0.5;
  while (*start - lo < max_half_px && ForegroundAt(view, uv + (lo - 0.5) * normal)) lo -= 0.5;
  return hi - lo + 1.0;
}

SweptRunFeatures MeasureSweptRun(const Polyline3& run, const std::vector<View2D>& views,
                                 const RigCalibration& rig,
                                 const std::vector<ViewSamples>& samples) {
  SweptRunFeatures out;
  const double length = run.Length();
  const size_t n_views = std::min({views.size(), rig.cameras.size(), samples.size()});
  if (run.points.size() < 2 || length <= 0.0 || run.radii.size() != run.points.size()) return out;
  out.turning_per_m = TurningPerMetre(run, 0.015);
  out.straightness = (run.points.back() - run.points.front()).norm() / length;
  for (const Eigen::Vector3d& p : run.points) out.mean_y_m += p.y();
  out.mean_y_m /= static_cast<double>(run.points.size());

  const std::vector<double> arc = run.ArcLengths();
  const int n = std::max(2, static_cast<int>(std::floor(length / 0.005)) + 1);
  // Per point, per view: the log of the radius the view implies (NaN where not measured).
  std::vector<std::vector<double>> log_radius(n, std::vector<double>(n_views, NAN));
  for (size_t w = 0; w < n_views; ++w) {
    const CameraCalibration& camera = rig.cameras[w];
    const View2D& view = views[w];
    if (view.classes.data.size() != static_cast<size_t>(view.width) * view.height ||
        view.classes.width != view.width || view.classes.height != view.height) {
      continue;
    }
    const double fx = camera.camera_matrix(0, 0);
    const Eigen::Isometry3d from_platform = camera.camera_from_platform();
    int inside = 0, on_foreground = 0, tangent_count = 0;
    double tangent = 0.0;
    std::vector<double> excess;
    for (int i = 0; i < n; ++i) {
      const double s = length * i / (n - 1);
      const Eigen::Vector3d p = run.PointAt(s, arc);
      const double radius = run.radii[std::min(run.radii.size() - 1,
                                               static_cast<size_t>(i * run.radii.size() / n))];
      const auto uv = ProjectInside(camera, p, 2);
      const auto u0 = camera.Project(run.PointAt(std::max(0.0, s - 0.0025), arc));
      const auto u1 = camera.Project(run.PointAt(std::min(length, s + 0.0025), arc));
      if (!uv || !u0 || !u1 || (*u1 - *u0).norm() <= 1e-9) continue;
      ++inside;
      const Eigen::Vector2d along = (*u1 - *u0).normalized();
      const Eigen::Vector2d normal(-along.y(), along.x());
      const double r_px = ProjectedRadiusPx(camera, p, radius);
      on_foreground += ForegroundAt(view, *uv) && ForegroundAt(view, *uv + 0.7 * r_px * normal) &&
                       ForegroundAt(view, *uv - 0.7 * r_px * normal);
      const double width_px = ForegroundWidthAcross(view, *uv, along);
      if (width_px > 0.0) {
        const double depth = (from_platform * p).z();
        log_radius[i][w] = std::log(0.5 * width_px * depth / fx);
        excess.push_back(std::log(width_px / std::max(0.5, 2.0 * r_px)));
      }
      double distance = 0.0;
      Eigen::Vector2d piece;
      const Eigen::Vector2d x = camera.PixelToNormalised(*uv);
      const Eigen::Vector2d x1 = camera.PixelToNormalised(*uv + along);
      ++tangent_count;
      if (samples[w].NearestPiece(x, 3.0 / fx, &distance, &piece)) {
        tangent += std::abs((x1 - x).normalized().dot(piece));
      }
    }
    if (inside * 2 < n) continue;
    ++out.views;
    out.foreground = std::min(out.foreground, static_cast<double>(on_foreground) / inside);
    if (tangent_count > 0) out.tangent = std::min(out.tangent, tangent / tangent_count);
    if (!excess.empty())
      out.width_log_excess = std::max(out.width_log_excess, std::abs(Median(excess)));
  }
  std::vector<double> spread;
  for (const std::vector<double>& per_view : log_radius) {
    double lo = INFINITY, hi = -INFINITY;
    int measured = 0;
    for (double l : per_view) {
      if (std::isnan(l)) continue;
      lo = std::min(lo, l);
      hi = std::max(hi, l);
      ++measured;
    }
    if (measured >= 2) spread.push_back(hi - lo);
  }
  out.width_log_spread = Median(spread);
  return out;
}

}  // namespace vb::reconstruct
