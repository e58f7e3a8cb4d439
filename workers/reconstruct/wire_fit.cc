// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/wire_fit.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "Eigen/Cholesky"

namespace vb::reconstruct {
namespace {

// An observed wire centre: the view, the normalised image point, and where along x its ray passes
// the wire.
struct Observation {
  int view;
  Eigen::Vector2d m;
  double x;
};

// Knots at fixed x; y and z per knot. Linear interpolation, extended linearly past the ends.
struct KnotWire {
  double x0 = 0.0, step = 1.0;
  Eigen::VectorXd y, z;

  int Size() const { return static_cast<int>(y.size()); }
  // The interval [k, k+1] used at x, and the weight of knot k + 1.
  void Locate(double x, int* k, double* t) const {
    *k = std::clamp(static_cast<int>(std::floor((x - x0) / step)), 0, Size() - 2);
    *t = (x - (x0 + *k * step)) / step;
  }
  Eigen::Vector3d At(double x) const {
    int k;
    double t;
    Locate(x, &k, &t);
    return {x, (1 - t) * y[k] + t * y[k + 1], (1 - t) * z[k] + t * z[k + 1]};
  }
  Eigen::Vector3d Tangent(double x) const {
    int k;
    double t;
    Locate(x, &k, &t);
    return Eigen::Vector3d(step, y[k + 1] - y[k], z[k + 1] - z[k]).normalized();
  }
};

// The pixels standing for a 2D wire line: its centre trace, or its straight extent every ~8 px.
std::vector<Eigen::Vector2d> LinePixels(const CameraCalibration& camera, const Line2D& line) {
  if (!line.centre_px.empty()) return line.centre_px;
  const double length_px = (line.end - line.begin).norm() * camera.camera_matrix(0, 0);
  const int n = std::max(2, static_cast<int>(length_px / 8.0) + 1);
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < n; ++i)
    out.push_back(camera.NormalisedToPixel(line.begin + (line.end - line.begin) * i / (n - 1.0)));
  return out;
}

// One linearised observation: residual (px) = j_y . y + j_z . z + r0 over the knots k, k + 1.
struct Row {
  int k;
  double t;
  double cy, cz, r0;  // coefficients of y(x), z(x), and the constant

  double Residual(const KnotWire& w) const {
    return cy * ((1 - t) * w.y[k] + t * w.y[k + 1]) + cz * ((1 - t) * w.z[k] + t * w.z[k + 1]) + r0;
  }
};

// The observation's image distance from the wire, linearised about `w`: the plane through the
// camera centre and the line through the observed point along the wire's local image direction.
bool Linearise(const CameraCalibration& camera, const Observation& o, const KnotWire& w, Row* row) {
  const Eigen::Matrix3d& r = camera.rotation_camera_from_platform;
  const Eigen::Vector3d& t = camera.translation_camera_from_platform;
  const Eigen::Vector3d p = w.At(o.x);
  const Eigen::Vector3d pc = r * p + t;
  const Eigen::Vector3d qc = r * (p + 0.01 * w.Tangent(o.x)) + t;
  if (pc.z() <= 1e-3 || qc.z() <= 1e-3) return false;
  const Eigen::Vector2d dir = (qc.hnormalized() - pc.hnormalized()).normalized();
  const Eigen::Vector2d n(-dir.y(), dir.x());
  const Eigen::Vector3d l(n.x(), n.y(), -n.dot(o.m));
  const double s = camera.camera_matrix(0, 0) / pc.z();
  w.Locate(o.x, &row->k, &row->t);
  row->cy = s * l.dot(r.col(1));
  row->cz = s * l.dot(r.col(2));
  row->r0 = s * (l.dot(r.col(0)) * o.x + l.dot(t));
  return std::isfinite(row->cy) && std::isfinite(row->cz) && std::isfinite(row->r0);
}

}  // namespace

absl::Status WireFitOptions::Validate() const {
  for (auto [v, name] : {std::pair{knot_spacing_m, "knot_spacing_m"}, {gate_px, "gate_px"},
                         {inlier_px, "inlier_px"}, {smoothness_px, "smoothness_px"},
                         {prior_px, "prior_px"}}) {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("wire fit options: ", name, " must be > 0"));
  }
  if (passes < 1) return absl::InvalidArgumentError("wire fit options: passes must be >= 1");
  if (min_observations < 1)
    return absl::InvalidArgumentError("wire fit options: min_observations must be >= 1");
  return absl::OkStatus();
}

std::vector<Eigen::Vector3d> FitWirePolyline(const std::vector<View2D>& views,
                                             const RigCalibration& rig, const Eigen::Vector3d& a,
                                             const Eigen::Vector3d& b,
                                             const WireFitOptions& options) {
  const double span = b.x() - a.x();
  if (!(span > 0)) return {};
  const int intervals = std::max(1, static_cast<int>(std::ceil(span / options.knot_spacing_m)));
  KnotWire straight;
  straight.x0 = a.x();
  straight.step = span / intervals;
  straight.y.resize(intervals + 1);
  straight.z.resize(intervals + 1);
  for (int k = 0; k <= intervals; ++k) {
    const double f = static_cast<double>(k) / intervals;
    straight.y[k] = a.y() + f * (b.y() - a.y());
    straight.z[k] = a.z() + f * (b.z() - a.z());
  }

  // Observations: centres whose ray passes near the straight wire, inside its x range.
  const Eigen::Vector3d e = b - a;
  std::vector<Observation> observations;
  for (size_t v = 0; v < views.size(); ++v) {
    const CameraCalibration& camera = rig.cameras[v];
    const Eigen::Vector3d c = camera.CentreInPlatform();
    const Eigen::Matrix3d platform_from_camera = camera.rotation_camera_from_platform.transpose();
    for (const Line2D& line : views[v].wires) {
      for (const Eigen::Vector2d& uv : LinePixels(camera, line)) {
        const Eigen::Vector2d m = camera.PixelToNormalised(uv);
        const Eigen::Vector3d d = platform_from_camera * m.homogeneous();
        // Closest approach of the ray c + s d and the line a + u e.
        const Eigen::Vector3d w0 = c - a;
        const double aa = d.dot(d), bb = d.dot(e), cc = e.dot(e), dd = d.dot(w0), ee = e.dot(w0);
        const double denom = aa * cc - bb * bb;
        if (std::abs(denom) < 1e-12) continue;
        const double u = (aa * ee - bb * dd) / denom;
        const double x = a.x() + u * e.x();
        if (x < a.x() || x > b.x()) continue;
        const auto projected = camera.Project(straight.At(x));
        if (!projected || (*projected - uv).norm() > options.gate_px) continue;
        observations.push_back({static_cast<int>(v), m, x});
      }
    }
  }
  if (static_cast<int>(observations.size()) < options.min_observations) return {};

  const int n = straight.Size();
  KnotWire wire = straight;
  std::vector<bool> inlier(observations.size(), true);
  for (int pass = 0; pass < options.passes; ++pass) {
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(2 * n);
    double scale_sum = 0.0;  // mean px per metre, to express the penalties in pixels
    int used = 0;
    for (size_t i = 0; i < observations.size(); ++i) {
      if (!inlier[i]) continue;
      const Observation& o = observations[i];
      Row row;
      if (!Linearise(rig.cameras[o.view], o, wire, &row)) continue;
      Eigen::Vector4d j(row.cy * (1 - row.t), row.cy * row.t, row.cz * (1 - row.t), row.cz * row.t);
      const int idx[4] = {row.k, row.k + 1, n + row.k, n + row.k + 1};
      for (int p = 0; p < 4; ++p) {
        g[idx[p]] += j[p] * row.r0;
        for (int q = 0; q < 4; ++q) h(idx[p], idx[q]) += j[p] * j[q];
      }
      scale_sum += std::hypot(row.cy, row.cz);
      ++used;
    }
    if (used < options.min_observations) return {};
    const double px_per_m = scale_sum / used;
    const double smooth = options.smoothness_px * px_per_m;
    for (int k = 1; k + 1 < n; ++k)
      for (int base : {0, n}) {
        const int idx[3] = {base + k - 1, base + k, base + k + 1};
        const double c[3] = {smooth, -2 * smooth, smooth};
        for (int p = 0; p < 3; ++p)
          for (int q = 0; q < 3; ++q) h(idx[p], idx[q]) += c[p] * c[q];
      }
    const double prior = options.prior_px * px_per_m;
    for (int k = 0; k < n; ++k) {
      h(k, k) += prior * prior;
      g[k] -= prior * prior * straight.y[k];
      h(n + k, n + k) += prior * prior;
      g[n + k] -= prior * prior * straight.z[k];
    }
    const Eigen::VectorXd theta = h.ldlt().solve(-g);
    if (!theta.allFinite()) return {};
    wire.y = theta.head(n);
    wire.z = theta.tail(n);
    if (pass + 1 == options.passes) break;
    for (size_t i = 0; i < observations.size(); ++i) {
      Row row;
      inlier[i] = Linearise(rig.cameras[observations[i].view], observations[i], wire, &row) &&
                  std::abs(row.Residual(wire)) <= options.inlier_px;
    }
  }
  std::vector<Eigen::Vector3d> knots;
  for (int k = 0; k < n; ++k) knots.emplace_back(wire.x0 + k * wire.step, wire.y[k], wire.z[k]);
  return knots;
}

}  // namespace vb::reconstruct
