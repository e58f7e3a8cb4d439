// SPDX-License-Identifier: Apache-2.0
// The joint refit of a grown stretch (GrowOptions::refit_span_m; grow_internal.h). Each grown
// point is corrected on its own (GrowEvidence::Correct) on a +-2 mm grid that, where only two
// views hold it and the step runs near their epipolar plane, leaves the depth to the noise of
// the skeletons; the chord of the last 3 cm then carries that error into the next prediction.
// Here the stretch is fitted as one curve: per point and view a linearised skeleton residual
// (Gauss-Newton, as in bundle adjustment: Triggs et al., "Bundle Adjustment - A Modern
// Synthesis", 1999) and a bending term that holds the directions the views leave free.

#include <algorithm>
#include <cmath>

#include "Eigen/Dense"
#include "workers/reconstruct/grow_internal.h"

namespace vb::reconstruct::grow_internal {
namespace {

constexpr int kIterations = 4;
constexpr double kSearchStepPx = 0.25;
// The skeleton crosses the normal where its (bilinear) distance falls to this.
constexpr double kOnSkeletonPx = 1.0;
constexpr double kDerivativeStepMm = 0.1;
// Damping (px^2 per mm^2) so that a point no view holds and no bend fixes stays where it is.
constexpr double kDamping = 1e-3;

}  // namespace

std::optional<ViewProbe::Observation> ViewProbe::Observe(const Eigen::Vector3d& p,
                                                         const Eigen::Vector3d& tangent,
                                                         const Eigen::Vector3d& u,
                                                         const Eigen::Vector3d& w,
                                                         double search_px) const {
  const std::optional<Eigen::Vector2d> uv = Inside(p);
  if (!uv) return std::nullopt;
  const std::optional<Eigen::Vector2d> ahead = camera_.Project(p + 0.001 * tangent);
  if (!ahead || (*ahead - *uv).norm() < 1e-3) return std::nullopt;
  const Eigen::Vector2d along = (*ahead - *uv).normalized();
  const Eigen::Vector2d normal(-along.y(), along.x());
  // The nearest crossing of the skeleton along the normal: walking out from the projection, the
  // first offset where the skeleton is within a pixel, then down to the distance's minimum.
  std::optional<double> best;
  const int steps = static_cast<int>(std::floor(search_px / kSearchStepPx));
  for (int k = 0; k <= steps && !best; ++k) {
    for (const int sign : {1, -1}) {
      const double s = sign * k * kSearchStepPx;
      if (Distance(*uv + s * normal) > kOnSkeletonPx) continue;
      double at = s, dist = Distance(*uv + s * normal);
      for (int slide = 0; slide < 16; ++slide) {
        const double lo = Distance(*uv + (at - kSearchStepPx) * normal);
        const double hi = Distance(*uv + (at + kSearchStepPx) * normal);
        if (std::min(lo, hi) >= dist) break;
        at += lo < hi ? -kSearchStepPx : kSearchStepPx;
        dist = std::min(lo, hi);
      }
      if (!best || std::abs(at) < std::abs(*best)) best = at;
    }
  }
  if (!best) return std::nullopt;
  Observation out;
  out.residual_px = -*best;
  const double h = kDerivativeStepMm / 1000.0;
  for (int axis = 0; axis < 2; ++axis) {
    const Eigen::Vector3d& e = axis == 0 ? u : w;
    const std::optional<Eigen::Vector2d> moved = camera_.Project(p + h * e);
    if (!moved) return std::nullopt;
    out.jacobian[axis] = normal.dot(*moved - *uv) / kDerivativeStepMm;
  }
  return out;
}

void GrowEvidence::Refit(std::vector<Eigen::Vector3d>* curve, size_t first_free) const {
  std::vector<Eigen::Vector3d>& c = *curve;
  const size_t n = c.size();
  if (first_free < 2 || first_free >= n) return;
  const int m = static_cast<int>(n - first_free);
  // Each free point moves on the plane normal to the curve there (as first given), and the
  // chord weights of the bending term are the first spacings: a straight, evenly or unevenly
  // spaced curve does not bend.
  std::vector<Eigen::Vector3d> u(m), w(m);
  for (int k = 0; k < m; ++k) {
    const size_t j = first_free + k;
    const Eigen::Vector3d t = (c[std::min(j + 1, n - 1)] - c[j - 1]).normalized();
    u[k] = t.unitOrthogonal();
    w[k] = t.cross(u[k]).normalized();
  }
  std::vector<double> h(n, 0.0);
  for (size_t j = 1; j < n; ++j) h[j] = std::max((c[j] - c[j - 1]).norm(), 1e-6);
  const double smooth = options_.refit_smooth_px_per_mm;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    Eigen::MatrixXd normal_matrix = kDamping * Eigen::MatrixXd::Identity(2 * m, 2 * m);
    Eigen::VectorXd gradient = Eigen::VectorXd::Zero(2 * m);
    for (int k = 0; k < m; ++k) {
      const size_t j = first_free + k;
      const Eigen::Vector3d t = (c[std::min(j + 1, n - 1)] - c[j - 1]).normalized();
      for (const ViewProbe& probe : probes_) {
        const std::optional<ViewProbe::Observation> o =
            probe.Observe(c[j], t, u[k], w[k], options_.refit_search_px);
        if (!o) continue;
        normal_matrix.block<2, 2>(2 * k, 2 * k) += o->jacobian * o->jacobian.transpose();
        gradient.segment<2>(2 * k) += o->jacobian * o->residual_px;
      }
    }
    if (smooth > 0) {
      // Bend at j: c[j] off the chord of c[j-1] and c[j+1], in mm, times `smooth`.
      for (size_t j = std::max<size_t>(1, first_free - 1); j + 1 < n; ++j) {
        const double a = h[j + 1] / (h[j] + h[j + 1]), b = h[j] / (h[j] + h[j + 1]);
        const Eigen::Vector3d bend = 1000.0 * (c[j] - a * c[j - 1] - b * c[j + 1]) * smooth;
        // d(bend)/d(offset in mm) of the three points, 3x2 each, for those that are free.
        Eigen::Matrix<double, 3, Eigen::Dynamic> jac =
            Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, 2 * m);
        const size_t idx[3] = {j - 1, j, j + 1};
        const double coef[3] = {-a, 1.0, -b};
        for (int r = 0; r < 3; ++r) {
          if (idx[r] < first_free) continue;
          const int k = static_cast<int>(idx[r] - first_free);
          jac.col(2 * k) += coef[r] * smooth * u[k];
          jac.col(2 * k + 1) += coef[r] * smooth * w[k];
        }
        normal_matrix += jac.transpose() * jac;
        gradient += jac.transpose() * bend;
      }
    }
    const Eigen::VectorXd delta = normal_matrix.ldlt().solve(-gradient);
    if (!delta.allFinite()) return;
    for (int k = 0; k < m; ++k)
      c[first_free + k] += (delta[2 * k] * u[k] + delta[2 * k + 1] * w[k]) / 1000.0;
    if (delta.cwiseAbs().maxCoeff() < 0.01) break;
  }
}

}  // namespace vb::reconstruct::grow_internal
