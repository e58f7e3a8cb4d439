// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/polyline_fit.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Cholesky"

namespace vb::reconstruct {
namespace {

// Piecewise-linear curve with K control points at uniform parameters in [0, 1]: the point at t
// is (1 - w) P_k + w P_{k+1}.
void Basis(double t, int k_count, int* k, double* w) {
  const double u = std::clamp(t, 0.0, 1.0) * (k_count - 1);
  *k = std::min(static_cast<int>(u), k_count - 2);
  *w = u - *k;
}

// A 1D residual in a view outside the match: the point of hit j, projected into `camera`, should
// lie on the line through `x` (normalised) with unit normal `normal`.
struct OtherViewResidual {
  int j = 0;
  const CameraCalibration* camera = nullptr;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
};

struct Problem {
  const MatchCandidate& candidate;
  const CameraCalibration& a;
  const CameraCalibration& b;
  std::vector<double> t;  // curve parameter of each hit
  std::vector<int> used;  // hits in the fit: all, or an even subset of long candidates
  int k_count = 2;
  double smooth_scale = 0.0;  // smoothness weight in pixels per metre
  std::vector<OtherViewResidual> others;  // RefineInOtherViews only

  // Cost (sum of squares); if h/g are given also the Gauss-Newton normal equations.
  double Evaluate(const Eigen::MatrixXd& p, Eigen::MatrixXd* h, Eigen::VectorXd* g) const {
    const int dim = 3 * k_count;
    if (h) {
      h->setZero(dim, dim);
      g->setZero(dim);
    }
    double cost = 0.0;
    auto add = [&](const auto& jx, const auto& r, int k, double w) {
      cost += r.squaredNorm();
      if (!h) return;
      const Eigen::Matrix3d jtj = jx.transpose() * jx;
      const Eigen::Vector3d jtr = jx.transpose() * r;
      const double wk[2] = {1.0 - w, w};
      for (int u = 0; u < 2; ++u) {
        g->segment<3>(3 * (k + u)) += wk[u] * jtr;
        for (int v = 0; v < 2; ++v) h->block<3, 3>(3 * (k + u), 3 * (k + v)) += wk[u] * wk[v] * jtj;
      }
    };
    const auto& hits = candidate.hits;
    for (const int j : used) {
      int k;
      double w;
      Basis(t[j], k_count, &k, &w);
      const Eigen::Vector3d x = (1.0 - w) * p.row(k).transpose() + w * p.row(k + 1).transpose();
      for (int view = 0; view < 2; ++view) {
        const CameraCalibration& cam = view == 0 ? a : b;
        const Eigen::Matrix3d& r = cam.rotation_camera_from_platform;
        const Eigen::Vector3d y = r * x + cam.translation_camera_from_platform;
        if (y.z() <= 1e-6) return std::numeric_limits<double>::infinity();
        const double f = cam.camera_matrix(0, 0);
        const Eigen::Vector2d pi = y.head<2>() / y.z();
        Eigen::Matrix<double, 2, 3> dpi;
        dpi << 1.0 / y.z(), 0.0, -y.x() / (y.z() * y.z()), 0.0, 1.0 / y.z(),
            -y.y() / (y.z() * y.z());
        const Eigen::Matrix<double, 2, 3> jx = f * dpi * r;
        if (view == 0) {
          const Eigen::Vector2d res = f * (pi - hits[j].xa);
          add(jx, res, k, w);
        } else {
          const Eigen::Vector2d& n = hits[j].normal_b;
          const Eigen::Matrix<double, 1, 1> res(f * n.dot(pi - hits[j].xb));
          const Eigen::Matrix<double, 1, 3> jn = n.transpose() * jx;
          add(jn, res, k, w);
        }
      }
    }
    for (const OtherViewResidual& o : others) {
      int k;
      double w;
      Basis(t[o.j], k_count, &k, &w);
      const Eigen::Vector3d x = (1.0 - w) * p.row(k).transpose() + w * p.row(k + 1).transpose();
      const Eigen::Matrix3d& r = o.camera->rotation_camera_from_platform;
      const Eigen::Vector3d y = r * x + o.camera->translation_camera_from_platform;
      if (y.z() <= 1e-6) return std::numeric_limits<double>::infinity();
      const double f = o.camera->camera_matrix(0, 0);
      Eigen::Matrix<double, 2, 3> dpi;
      dpi << 1.0 / y.z(), 0.0, -y.x() / (y.z() * y.z()), 0.0, 1.0 / y.z(),
          -y.y() / (y.z() * y.z());
      const Eigen::Matrix<double, 1, 1> res(f * o.normal.dot(y.head<2>() / y.z() - o.x));
      const Eigen::Matrix<double, 1, 3> jn = o.normal.transpose() * (f * dpi * r);
      add(jn, res, k, w);
    }
    for (int k = 1; k + 1 < k_count; ++k) {
      const Eigen::Vector3d second = p.row(k - 1) - 2.0 * p.row(k) + p.row(k + 1);
      cost += smooth_scale * smooth_scale * second.squaredNorm();
      if (!h) continue;
      const double c[3] = {1.0, -2.0, 1.0};
      for (int u = 0; u < 3; ++u) {
        g->segment<3>(3 * (k - 1 + u)) += smooth_scale * smooth_scale * c[u] * second;
        for (int v = 0; v < 3; ++v) {
          h->block<3, 3>(3 * (k - 1 + u), 3 * (k - 1 + v)) +=
              smooth_scale * smooth_scale * c[u] * c[v] * Eigen::Matrix3d::Identity();
        }
      }
    }
    return cost;
  }
};

// Levenberg-Marquardt from *p; returns the final cost (infinite if the start is not finite).
double Minimise(const Problem& problem, int max_iterations, Eigen::MatrixXd* p_io) {
  Eigen::MatrixXd& p = *p_io;
  const int k_count = problem.k_count;
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  double cost = problem.Evaluate(p, &h, &g);
  if (!std::isfinite(cost)) return cost;
  double mu = 1e-4 * std::max(1e-12, h.diagonal().maxCoeff());
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::MatrixXd damped = h;
    damped.diagonal() += mu * (Eigen::VectorXd::Ones(h.rows()) + h.diagonal());
    const Eigen::VectorXd step = damped.ldlt().solve(-g);
    if (!step.allFinite()) break;
    Eigen::MatrixXd trial = p;
    for (int k = 0; k < k_count; ++k) trial.row(k) += step.segment<3>(3 * k).transpose();
    const double trial_cost = problem.Evaluate(trial, nullptr, nullptr);
    if (trial_cost < cost) {
      const double gain = cost - trial_cost;
      p = trial;
      cost = problem.Evaluate(p, &h, &g);
      mu = std::max(mu / 3.0, 1e-12);
      if (gain < 1e-6 * cost + 1e-10) break;
    } else {
      mu *= 4.0;
      if (mu > 1e12) break;
    }
  }
  return cost;
}

// The curve parameter of each hit (arc length along segment_a), the hits used (an even subset
// of long candidates: the curve has at most max_control_points points, so ~4 hits per span are
// plenty; residuals are reported on all) and the smoothness scale. False for a degenerate
// candidate.
bool SetUp(const PolylineFitOptions& options, Problem* problem) {
  const auto& hits = problem->candidate.hits;
  const int n = static_cast<int>(hits.size());
  if (n < 2) return false;
  const double span = hits.back().arc_a_px - hits.front().arc_a_px;
  if (!(span > 0.0)) return false;
  for (const EpipolarHit& hit : hits) {
    if (!hit.point.allFinite()) return false;
  }
  problem->t.resize(n);
  for (int j = 0; j < n; ++j) problem->t[j] = (hits[j].arc_a_px - hits.front().arc_a_px) / span;
  const int stride = std::max(1, n / (4 * options.max_control_points));
  for (int j = 0; j < n; j += stride) problem->used.push_back(j);
  if (problem->used.back() != n - 1) problem->used.push_back(n - 1);
  double depth_sum = 0.0;
  for (const EpipolarHit& hit : hits) depth_sum += hit.depth_a;
  problem->smooth_scale =
      options.smoothness_weight * problem->a.camera_matrix(0, 0) / std::max(0.05, depth_sum / n);
  return true;
}

// The point of the control polygon `p` at curve parameter t.
Eigen::Vector3d CurvePoint(const Eigen::MatrixXd& p, double t) {
  int k;
  double w;
  Basis(t, static_cast<int>(p.rows()), &k, &w);
  return (1.0 - w) * p.row(k).transpose() + w * p.row(k + 1).transpose();
}

// Half-width of the window around log(bundle_width_ratio), in units of that log.
constexpr double kBundleWindow = 0.35;

}  // namespace

PolylineFit FitPolyline(const MatchCandidate& candidate, const CameraCalibration& camera_a,
                        const CameraCalibration& camera_b, const PolylineFitOptions& options) {
  PolylineFit fit;
  const auto& hits = candidate.hits;
  const int n = static_cast<int>(hits.size());
  if (n < 2) return fit;
  Problem problem{candidate, camera_a, camera_b, {}, {}, 2, 0.0, {}};
  if (!SetUp(options, &problem)) return fit;

  // Length through every third triangulated point (less inflated by depth noise).
  double length = 0.0;
  for (int j = 3; j < n; j += 3) length += (hits[j].point - hits[j - 3].point).norm();
  length += (hits.back().point - hits[(n - 1) / 3 * 3].point).norm();
  const int k_count = std::clamp(static_cast<int>(std::lround(length / options.control_spacing_m)) + 1,
                                 2, std::max(2, std::min(options.max_control_points, n / 3 + 1)));
  problem.k_count = k_count;

  // Linear least squares initialisation from the triangulated points.
  Eigen::MatrixXd ata = Eigen::MatrixXd::Identity(k_count, k_count) * 1e-9;
  Eigen::MatrixXd atb = Eigen::MatrixXd::Zero(k_count, 3);
  for (int j = 0; j < n; ++j) {
    int k;
    double w;
    Basis(problem.t[j], k_count, &k, &w);
    ata(k, k) += (1 - w) * (1 - w);
    ata(k, k + 1) += (1 - w) * w;
    ata(k + 1, k) += (1 - w) * w;
    ata(k + 1, k + 1) += w * w;
    atb.row(k) += (1 - w) * hits[j].point.transpose();
    atb.row(k + 1) += w * hits[j].point.transpose();
  }
  for (int k = 1; k + 1 < k_count; ++k) {  // a little smoothness keeps sparse spans defined
    const double c[3] = {1.0, -2.0, 1.0};
    for (int u = 0; u < 3; ++u) {
      for (int v = 0; v < 3; ++v) ata(k - 1 + u, k - 1 + v) += 1e-3 * c[u] * c[v];
    }
  }
  Eigen::MatrixXd p = ata.ldlt().solve(atb);
  if (!p.allFinite()) return fit;

  const double cost = Minimise(problem, options.max_iterations, &p);
  if (!std::isfinite(cost)) return fit;

  // Attributes of the fit.
  fit.control_points.resize(k_count);
  for (int k = 0; k < k_count; ++k) fit.control_points[k] = p.row(k).transpose();
  fit.points.resize(n);
  fit.hit_radii.resize(n);
  std::vector<double> radius_sum(k_count, 0.0), weight_sum(k_count, 0.0);
  double sum_a = 0.0, sum_b = 0.0, log_ratio = 0.0;
  int ratio_count = 0;
  for (int j = 0; j < n; ++j) {
    int k;
    double w;
    Basis(problem.t[j], k_count, &k, &w);
    const Eigen::Vector3d x = (1.0 - w) * fit.control_points[k] + w * fit.control_points[k + 1];
    fit.points[j] = x;
    const Eigen::Vector3d ya = camera_a.camera_from_platform() * x;
    const Eigen::Vector3d yb = camera_b.camera_from_platform() * x;
    const double ra = (ya.head<2>() / ya.z() - hits[j].xa).norm() * camera_a.camera_matrix(0, 0);
    const double rb = std::abs(hits[j].normal_b.dot(yb.head<2>() / yb.z() - hits[j].xb)) *
                      camera_b.camera_matrix(0, 0);
    sum_a += ra * ra;
    sum_b += rb * rb;
    fit.max_residual_px = std::max({fit.max_residual_px, ra, rb});
    const double radius_a = 0.5 * hits[j].width_a * ya.z();
    const double radius_b = 0.5 * hits[j].width_b * yb.z();
    double radius = 0.5 * (radius_a + radius_b);
    if (radius_a > 0.0 && radius_b > 0.0) {
      double disagreement = std::abs(std::log(radius_a / radius_b));
      if (options.bundle_width_ratio > 1.0) {
        const double bundle = std::log(options.bundle_width_ratio);
        const double off = std::abs(disagreement - bundle);
        if (off < kBundleWindow * bundle) {
          // Read as two canes along each other, overlapping in the narrower view: no
          // disagreement at the factor itself, back to the plain one at the window's edges.
          disagreement *= off / (kBundleWindow * bundle);
        }
      }
      log_ratio += disagreement;
      ++ratio_count;
    } else {
      radius = std::max(radius_a, radius_b);
    }
    fit.hit_radii[j] = radius;
    radius_sum[k] += (1.0 - w) * radius;
    weight_sum[k] += 1.0 - w;
    radius_sum[k + 1] += w * radius;
    weight_sum[k + 1] += w;
  }
  fit.rms_a_px = std::sqrt(sum_a / n);
  fit.rms_b_px = std::sqrt(sum_b / n);
  fit.width_log_ratio = ratio_count > 0 ? log_ratio / ratio_count : 1.0;
  fit.radii.resize(k_count);
  for (int k = 0; k < k_count; ++k) {
    fit.radii[k] = weight_sum[k] > 1e-9 ? radius_sum[k] / weight_sum[k] : 0.0;
  }
  // Control points without nearby hits take their neighbour's radius.
  for (int k = 0; k < k_count; ++k) {
    if (fit.radii[k] > 0.0) continue;
    for (int d = 1; d < k_count; ++d) {
      if (k - d >= 0 && fit.radii[k - d] > 0.0) { fit.radii[k] = fit.radii[k - d]; break; }
      if (k + d < k_count && fit.radii[k + d] > 0.0) { fit.radii[k] = fit.radii[k + d]; break; }
    }
    if (!(fit.radii[k] > 0.0)) fit.radii[k] = 1e-3;
  }
  for (int k = 0; k + 1 < k_count; ++k) {
    fit.length_m += (fit.control_points[k + 1] - fit.control_points[k]).norm();
  }
  for (int k = 1; k + 1 < k_count; ++k) {
    const Eigen::Vector3d u = fit.control_points[k] - fit.control_points[k - 1];
    const Eigen::Vector3d v = fit.control_points[k + 1] - fit.control_points[k];
    if (u.norm() > 0 && v.norm() > 0) {
      fit.turning_rad += std::acos(std::clamp(u.normalized().dot(v.normalized()), -1.0, 1.0));
    }
  }
  fit.ok = std::isfinite(cost) && std::isfinite(fit.length_m) && fit.length_m > 0.0;
  for (const Eigen::Vector3d& x : fit.control_points) fit.ok = fit.ok && x.allFinite();
  return fit;
}

// RMS (pixels) of the two views' residuals over the used hits, and of the other views' ones.
void ResidualRms(const Problem& problem, const Eigen::MatrixXd& p, double* two_view_px,
                 double* other_px) {
  double sum = 0.0, other_sum = 0.0;
  int count = 0;
  const auto& hits = problem.candidate.hits;
  auto project = [&](const CameraCalibration& cam, const Eigen::Vector3d& x) {
    const Eigen::Vector3d y = cam.camera_from_platform() * x;
    return Eigen::Vector2d(y.head<2>() / std::max(y.z(), 1e-9));
  };
  for (const int j : problem.used) {
    const Eigen::Vector3d x = CurvePoint(p, problem.t[j]);
    const double fa = problem.a.camera_matrix(0, 0), fb = problem.b.camera_matrix(0, 0);
    sum += (fa * (project(problem.a, x) - hits[j].xa)).squaredNorm();
    const double rb = fb * hits[j].normal_b.dot(project(problem.b, x) - hits[j].xb);
    sum += rb * rb;
    ++count;
  }
  for (const OtherViewResidual& o : problem.others) {
    const double r = o.camera->camera_matrix(0, 0) *
                     o.normal.dot(project(*o.camera, CurvePoint(p, problem.t[o.j])) - o.x);
    other_sum += r * r;
  }
  *two_view_px = count > 0 ? std::sqrt(sum / count) : 0.0;
  *other_px = problem.others.empty() ? 0.0 : std::sqrt(other_sum / problem.others.size());
}

int RefineInOtherViews(const MatchCandidate& candidate, const CameraCalibration& camera_a,
                       const CameraCalibration& camera_b, const std::vector<OtherView>& others,
                       const PolylineFitOptions& options, const OtherViewFitOptions& other_options,
                       PolylineFit* fit) {
  if (!fit->ok || others.empty() || other_options.rounds <= 0 ||
      fit->control_points.size() < 2) {
    return 0;
  }
  Problem problem{candidate, camera_a, camera_b, {}, {}, 2, 0.0, {}};
  if (!SetUp(options, &problem)) return 0;
  problem.k_count = static_cast<int>(fit->control_points.size());
  Eigen::MatrixXd p(problem.k_count, 3);
  for (int k = 0; k < problem.k_count; ++k) p.row(k) = fit->control_points[k].transpose();
  int associated = 0;
  double before_px = 0.0, unused = 0.0;
  ResidualRms(problem, p, &before_px, &unused);
  for (int round = 0; round < other_options.rounds; ++round) {
    // Associate each used hit's point with the nearest skeleton piece of each other view, if it
    // is near and runs the same way (a different cane crossing there is not taken).
    auto previous_others = std::move(problem.others);
    problem.others.clear();
    for (const int j : problem.used) {
      int k;
      double w;
      Basis(problem.t[j], problem.k_count, &k, &w);
      const Eigen::Vector3d x = CurvePoint(p, problem.t[j]);
      const Eigen::Vector3d along = (p.row(k + 1) - p.row(k)).transpose();
      if (!(along.norm() > 0.0)) continue;
      for (const OtherView& other : others) {
        const Eigen::Isometry3d from_platform = other.camera->camera_from_platform();
        const Eigen::Vector3d y = from_platform * x;
        const Eigen::Vector3d y1 = from_platform * (x + 1e-3 * along.normalized());
        if (y.z() <= 1e-6 || y1.z() <= 1e-6) continue;
        const Eigen::Vector2d direction = y1.hnormalized() - y.hnormalized();
        if (!(direction.norm() > 0.0)) continue;
        const double f = other.camera->camera_matrix(0, 0);
        double distance;
        Eigen::Vector2d piece, closest;
        if (!other.samples->NearestPiece(y.hnormalized(), other_options.gate_px / f, &distance,
                                         &piece, &closest)) {
          continue;
        }
        if (std::abs(piece.dot(direction.normalized())) < other_options.min_cos) continue;
        problem.others.push_back({j, other.camera, closest, Eigen::Vector2d(-piece.y(), piece.x())});
      }
    }
    if (static_cast<int>(problem.others.size()) < other_options.min_associations) {
      if (round == 0) return 0;
      // Keep the previous round's fit, judged below against the views it was fitted to.
      problem.others = std::move(previous_others);
      break;
    }
    associated = static_cast<int>(problem.others.size());
    Eigen::MatrixXd trial = p;
    const double cost = Minimise(problem, options.max_iterations, &trial);
    if (!std::isfinite(cost) || !trial.allFinite()) return 0;
    p = trial;
  }
  // A third view that disagrees with the two (another cane associated, or a skeleton pulled
  // aside at a junction) shows as residuals the refined curve cannot bring down: keep the
  // two-view fit then.
  double after_px = 0.0, other_px = 0.0;
  ResidualRms(problem, p, &after_px, &other_px);
  if (other_options.max_residual_growth_px > 0.0 &&
      (after_px > before_px + other_options.max_residual_growth_px ||
       other_px > other_options.max_residual_growth_px + 1.0)) {
    return 0;
  }
  for (int k = 0; k < problem.k_count; ++k) fit->control_points[k] = p.row(k).transpose();
  for (size_t j = 0; j < fit->points.size() && j < problem.t.size(); ++j) {
    fit->points[j] = CurvePoint(p, problem.t[j]);
  }
  return associated;
}

ViewSupport CheckInView(const std::vector<Eigen::Vector3d>& points, const View2D& view,
                        const ViewSamples& samples, const CameraCalibration& camera) {
  ViewSupport support;
  const size_t pixels = static_cast<size_t>(view.width) * view.height;
  if (points.size() < 2 || view.classes.data.size() != pixels || pixels == 0) return support;
  const bool has_distance = view.centreline_distance_px.size() == pixels;
  const double f = camera.camera_matrix(0, 0);
  const Eigen::Isometry3d from_platform = camera.camera_from_platform();
  int inside = 0, foreground = 0;
  double centreline = 0.0, tangent = 0.0;
  int near = 0, aligned = 0;
  const size_t n = points.size();
  for (size_t j = 0; j < n; ++j) {
    const auto uv = camera.Project(points[j]);
    if (!uv || !camera.InImage(*uv) || uv->x() > view.width - 1 || uv->y() > view.height - 1) {
      continue;
    }
    ++inside;
    const int x = static_cast<int>(std::lround(uv->x()));
    const int y = static_cast<int>(std::lround(uv->y()));
    bool on = false;
    for (int dy = -1; dy <= 1 && !on; ++dy) {
      for (int dx = -1; dx <= 1 && !on; ++dx) {
        const int xx = std::clamp(x + dx, 0, view.width - 1);
        const int yy = std::clamp(y + dy, 0, view.height - 1);
        on = view.IsForeground(xx, yy);
      }
    }
    foreground += on ? 1 : 0;
    const double distance_px =
        has_distance ? view.centreline_distance_px[static_cast<size_t>(y) * view.width + x]
                     : kCentrelineDistanceCapPx;
    centreline += distance_px;
    near += distance_px <= 2.5 ? 1 : 0;
    const Eigen::Vector3d y0 = from_platform * points[j == 0 ? 0 : j - 1];
    const Eigen::Vector3d y1 = from_platform * points[j + 1 == n ? n - 1 : j + 1];
    const Eigen::Vector3d yj = from_platform * points[j];
    if (y0.z() <= 0 || y1.z() <= 0 || yj.z() <= 0) continue;
    const Eigen::Vector2d dir = y1.hnormalized() - y0.hnormalized();
    double distance;
    Eigen::Vector2d piece;
    if (dir.norm() > 0 && samples.NearestPiece(yj.hnormalized(), 6.0 / f, &distance, &piece)) {
      const double agreement = std::abs(dir.normalized().dot(piece));
      tangent += agreement;
      aligned += distance * f <= 3.0 && agreement > 0.95 ? 1 : 0;
    }
  }
  support.in_image = static_cast<double>(inside) / n;
  if (inside > 0) {
    support.foreground = static_cast<double>(foreground) / inside;
    support.centreline_px = centreline / inside;
    support.tangent = tangent / inside;
    support.near = static_cast<double>(near) / inside;
    support.aligned = static_cast<double>(aligned) / inside;
  }
  return support;
}

}  // namespace vb::reconstruct
