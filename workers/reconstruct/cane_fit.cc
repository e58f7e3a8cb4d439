// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/cane_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "ceres/ceres.h"
#include "ceres/cubic_interpolation.h"
#include "workers/reconstruct/cane_fit_internal.h"
#include "workers/reconstruct/ceres_camera.h"

namespace vb::reconstruct {
namespace {

// Passes of the [1 2 1] / 4 kernel that make the rest shape.
constexpr int kRestSmoothingPasses = 3;

// Second difference of three consecutive points about that of the cane's rest shape.
struct KinkCost {
  KinkCost(const Eigen::Vector3d& rest, double inv_sd) : rest(rest), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (a[i] - T(2.0) * b[i] + c[i] - rest[i]) * inv_sd;
    return true;
  }
  Eigen::Vector3d rest;
  double inv_sd;
};

// Keeps a point no view sees near where it started.
struct PriorCost {
  PriorCost(const Eigen::Vector3d& start, double inv_sd) : start(start), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (p[i] - start[i]) * inv_sd;
    return true;
  }
  Eigen::Vector3d start;
  double inv_sd;
};

struct SpacingCost {
  SpacingCost(double spacing, double inv_sd) : spacing(spacing), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    const T dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
    // The epsilon keeps the derivative finite if two points ever coincide.
    residual[0] = (sqrt(dx * dx + dy * dy + dz * dz + T(1e-12)) - spacing) * inv_sd;
    return true;
  }
  double spacing, inv_sd;
};

// Base p of a child at a fixed fraction along parent segment [q0, q1], plus a fixed offset.
struct PinCost {
  PinCost(double fraction, const Eigen::Vector3d& offset, double inv_sd)
      : fraction(fraction), offset(offset), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* p, const T* q0, const T* q1, T* residual) const {
    for (int i = 0; i < 3; ++i) {
      residual[i] = (p[i] - (T(1.0 - fraction) * q0[i] + T(fraction) * q1[i]) - offset[i]) * inv_sd;
    }
    return true;
  }
  double fraction;
  Eigen::Vector3d offset;
  double inv_sd;
};

struct GroundCost {
  explicit GroundCost(double inv_sd) : inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    residual[0] = p[2] * inv_sd;
    return true;
  }
  double inv_sd;
};

// The rest shape of a cane: its points with the noise smoothed away (three [1 2 1] / 4 passes;
// a binomial kernel of sd ~1.2 points), which would otherwise inflate its length and curvature.
std::vector<Eigen::Vector3d> RestShape(const Polyline3& line) {
  std::vector<Eigen::Vector3d> p = line.points;
  for (int pass = 0; pass < kRestSmoothingPasses; ++pass) {
    std::vector<Eigen::Vector3d> q = p;
    for (size_t i = 1; i + 1 < p.size(); ++i) q[i] = 0.25 * (p[i - 1] + 2.0 * p[i] + p[i + 1]);
    p = std::move(q);
  }
  return p;
}

}  // namespace

absl::Status RefineModel(VineModel* model, const std::vector<View2D>& views,
                         const RigCalibration& rig, const FitOptions& options,
                         const Deadline& deadline, FitSummary* summary) {
  const auto start_time = std::chrono::steady_clock::now();
  FitSummary local_summary;
  FitSummary& out = summary != nullptr ? *summary : local_summary;
  out = FitSummary();
  if (model == nullptr) return absl::InvalidArgumentError("model: null");
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = rig.Validate(); !s.ok()) return s;
  if (absl::Status s = cane_fit_internal::ValidateViews(views, rig); !s.ok()) return s;
  if (absl::Status s = cane_fit_internal::ValidateModel(*model); !s.ok()) return s;
  out.canes_in = out.canes_out = static_cast<int>(model->canes.size());
  if (model->canes.empty()) return absl::OkStatus();
  if (absl::Status s = deadline.Check("RefineModel"); !s.ok()) return s;

  // Parameters: every resampled point is its own block of 3. The trunk's base stretch no
  // trunk_min_views images see is a straight guess (head.h): it goes to the obstacles at the end
  // (the model is untouched until then). Without it the ground pin below no longer applies.
  const size_t cane_count = model->canes.size();
  cane_fit_internal::FitLines fit_lines = cane_fit_internal::LinesForFit(*model, rig, options);
  std::vector<Polyline3>& lines = fit_lines.lines;
  std::vector<WoodObstacle>& unseen = fit_lines.unseen;
  const std::vector<size_t>& unseen_of = fit_lines.unseen_of;
  const std::vector<bool>& split = fit_lines.split;
  std::vector<std::vector<double>> params(cane_count);
  for (size_t c = 0; c < cane_count; ++c) {
    for (const Eigen::Vector3d& p : lines[c].points) params[c].insert(params[c].end(), {p.x(), p.y(), p.z()});
  }
  auto block = [&](size_t c, size_t i) { return params[c].data() + 3 * i; };
  std::unordered_map<int64_t, size_t> index_of_id;
  for (size_t c = 0; c < cane_count; ++c) index_of_id[model->canes[c].id.value] = c;

  // Rejection runs before the fit (a ghost near real structure would otherwise be pulled onto
  // it) and after it. remove: 0 keep, 1 rejected, 2 descendant of a rejected cane.
  std::vector<char> remove(cane_count, 0);
  auto reject = [&]() {
    for (size_t c = 0; c < cane_count; ++c) {
      if (remove[c] || !model->canes[c].parent_id.has_value()) continue;  // trunk carries all
      size_t outside = 0;
      for (const Eigen::Vector3d& p : lines[c].points) {
        outside += !options.working_volume.Contains(p);
      }
      if (outside > options.max_outside_fraction * lines[c].points.size()) {
        remove[c] = 1;
        ++out.rejected_outside;
        continue;
      }
      const auto [fraction, visible] =
          cane_fit_internal::ForegroundFraction(lines[c], views, rig, options.foreground_tolerance_px);
      if (visible >= options.min_visible_points && fraction < options.min_foreground_fraction) {
        remove[c] = 1;
        ++out.rejected_background;
      }
    }
    for (size_t c = 0; c < cane_count; ++c) {
      if (remove[c] != 1) continue;
      for (const CaneId& id : model->DescendantsOf(model->canes[c].id)) {
        const size_t d = index_of_id.at(id.value);
        if (!remove[d]) {
          remove[d] = 2;
          ++out.removed_with_parent;
        }
      }
    }
  };
  reject();

  std::vector<std::unique_ptr<SquaredDistanceField>> fields;
  std::vector<Projector> projectors;
  for (size_t v = 0; v < views.size(); ++v) {
    fields.push_back(std::make_unique<SquaredDistanceField>(views[v]));
    projectors.emplace_back(rig.cameras[v]);
  }

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::SoftLOneLoss loss(options.pseudo_huber_t_sd);
  const double inv_px = 1.0 / options.reprojection_sd_px;
  // The bicubic interpolator reads a 4x4 neighbourhood; keep clear of the border.
  constexpr double kMarginPx = 2.0;
  for (size_t c = 0; c < cane_count; ++c) {
    if (remove[c]) continue;
    const Polyline3& line = lines[c];
    const size_t n = line.points.size();
    for (size_t i = 0; i < n; ++i) problem.AddParameterBlock(block(c, i), 3);
    std::vector<int> seen_by(n, 0);
    for (size_t v = 0; v < views.size(); ++v) {
      const CameraCalibration& camera = rig.cameras[v];
      for (size_t i = 0; i < n; ++i) {
        const std::optional<Eigen::Vector2d> uv = camera.Project(line.points[i]);
        if (!uv || uv->x() < kMarginPx || uv->y() < kMarginPx ||
            uv->x() > camera.image_width - 1 - kMarginPx ||
            uv->y() > camera.image_height - 1 - kMarginPx) {
          continue;
        }
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<CentrelineCost, 1, 3>(
                new CentrelineCost(projectors[v], fields[v]->interpolator(), inv_px)),
            &loss, block(c, i));
        ++seen_by[i];
      }
    }
    for (size_t i = 0; i < n; ++i) {
      if (seen_by[i] > 0) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(
                                   new PriorCost(line.points[i], 1.0 / options.unseen_prior_sd_m)),
                               nullptr, block(c, i));
    }
    const std::vector<Eigen::Vector3d> rest = RestShape(line);
    for (size_t i = 1; i + 1 < n; ++i) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<KinkCost, 3, 3, 3, 3>(new KinkCost(
              rest[i - 1] - 2.0 * rest[i] + rest[i + 1], 1.0 / options.kink_sd_m)),
          nullptr, block(c, i - 1), block(c, i), block(c, i + 1));
    }
    double rest_length = 0.0;
    for (size_t i = 1; i < n; ++i) rest_length += (rest[i] - rest[i - 1]).norm();
    const double spacing = rest_length / static_cast<double>(n - 1);
    for (size_t i = 0; i + 1 < n; ++i) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SpacingCost, 1, 3, 3>(
                                   new SpacingCost(spacing, 1.0 / options.spacing_sd_m)),
                               nullptr, block(c, i), block(c, i + 1));
    }
    const Cane& cane = model->canes[c];
    if (!cane.parent_id.has_value()) {
      if (split[c] || std::abs(line.points[0].z()) > options.ground_snap_m) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<GroundCost, 1, 3>(new GroundCost(1.0 / options.pin_sd_m)),
          nullptr, block(c, 0));
      continue;
    }
    // The nearest point of the parent, as a fixed segment and fraction.
    const size_t parent = index_of_id.at(cane.parent_id->value);
    const Polyline3& parent_line = lines[parent];
    double best = std::numeric_limits<double>::infinity(), fraction = 0.0;
    size_t segment = 0;
    for (size_t k = 0; k + 1 < parent_line.points.size(); ++k) {
      double t = 0.0;
      const double d = PointSegmentDistance(line.points[0], parent_line.points[k],
                                            parent_line.points[k + 1], &t);
      if (d < best) best = d, segment = k, fraction = t;
    }
    const Eigen::Vector3d attach = (1.0 - fraction) * parent_line.points[segment] +
                                   fraction * parent_line.points[segment + 1];
    const bool on_parent = best <= options.attach_distance_m;
    const Eigen::Vector3d offset = on_parent ? Eigen::Vector3d::Zero() : Eigen::Vector3d(line.points[0] - attach);
    const double sd = on_parent ? options.pin_sd_m : options.detached_base_sd_m;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PinCost, 3, 3, 3, 3>(
                                 new PinCost(fraction, offset, 1.0 / sd)),
                             nullptr, block(c, 0), block(parent, segment),
                             block(parent, segment + 1));
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.num_threads = 1;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  VB_ASSIGN_OR_RETURN(const DeadlineSolve solve,
                      SolveWithDeadline(solver_options, &problem, deadline, "RefineModel"));
  const ceres::Solver::Summary& ceres_summary = solve.summary;
  if (!ceres_summary.IsSolutionUsable()) {
    return absl::InternalError(
        absl::StrCat("RefineModel: Ceres failed: ", ceres_summary.message));
  }
  out.iterations = static_cast<int>(ceres_summary.iterations.size()) - 1;
  out.initial_cost = ceres_summary.initial_cost;
  out.final_cost = ceres_summary.final_cost;
  out.message = ceres_summary.BriefReport();
  if (solve.expired || (ceres_summary.termination_type == ceres::NO_CONVERGENCE &&
                             deadline.Expired())) {
    out.termination = FitTermination::kDeadline;
  } else if (ceres_summary.termination_type == ceres::NO_CONVERGENCE) {
    out.termination = FitTermination::kIterationLimit;
  } else {
    out.termination = FitTermination::kConverged;
  }

  // Write back, then reject.
  for (size_t c = 0; c < cane_count; ++c) {
    if (remove[c]) continue;
    for (size_t i = 0; i < lines[c].points.size(); ++i) {
      lines[c].points[i] = Eigen::Vector3d(block(c, i)[0], block(c, i)[1], block(c, i)[2]);
    }
  }
  reject();
  // Each unseen stretch ends where its trunk now starts (the fit may have moved that point).
  for (size_t k = 0; k < unseen.size(); ++k) {
    const size_t c = unseen_of[k];
    if (!remove[c]) unseen[k].polyline.points.back() = lines[c].points.front();
  }
  out.trunk_unseen_m = 0.0;
  for (const WoodObstacle& stretch : unseen) out.trunk_unseen_m += stretch.polyline.Length();
  std::vector<Cane> kept;
  for (size_t c = 0; c < cane_count; ++c) {
    if (remove[c]) continue;
    Cane cane = model->canes[c];
    cane.polyline = std::move(lines[c]);
    kept.push_back(std::move(cane));
  }
  model->canes = std::move(kept);
  model->obstacles.insert(model->obstacles.end(), unseen.begin(), unseen.end());
  out.canes_out = static_cast<int>(model->canes.size());
  out.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
