// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/rig_refine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"
#include "ceres/rotation.h"
#include "core/status_macros.h"
#include "Eigen/Eigenvalues"
#include "workers/reconstruct/ceres_camera.h"

namespace vb::reconstruct {
namespace {

// The bicubic interpolator reads a 4x4 neighbourhood; keep clear of the border.
constexpr double kMarginPx = 2.0;

// CentrelineCost for a camera whose rotation is corrected by the angle-axis `w` (applied in the
// camera frame: x_cam' = R(w) (R x + t), which keeps the camera centre where it is) and whose
// focal length is scaled by 1 + s.
struct CorrectedCentrelineCost {
  CorrectedCentrelineCost(const Projector& projector, const Interpolator* interpolator,
                        double inv_sd)
      : projector(projector), interpolator(interpolator), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* w, const T* s, const T* p, T* residual) const {
    T pc[3];
    for (int i = 0; i < 3; ++i) {
      pc[i] = projector.r[3 * i] * p[0] + projector.r[3 * i + 1] * p[1] +
              projector.r[3 * i + 2] * p[2] + projector.t[i];
    }
    T rotated[3];
    ceres::AngleAxisRotatePoint(w, pc, rotated);
    T u, v;
    if (!projector.FromCameraScaled(rotated, T(1.0) + s[0], &u, &v)) return false;
    T d2;
    interpolator->Evaluate(v, u, &d2);
    residual[0] = sqrt(fmax(d2, T(0.0)) + T(1e-6)) * inv_sd;
    return true;
  }
  Projector projector;
  const Interpolator* interpolator;
  double inv_sd;
};

// Holds a correction near zero: residual = the pixels it moves the image by / prior_px, for the
// rotation (angle x focal length) and the focal scale (s x half the image width).
struct CorrectionPrior {
  CorrectionPrior(double rotation_scale, double focal_scale)
      : rotation_scale(rotation_scale), focal_scale(focal_scale) {}
  template <typename T>
  bool operator()(const T* w, const T* s, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = w[i] * rotation_scale;
    residual[3] = s[0] * focal_scale;
    return true;
  }
  double rotation_scale, focal_scale;
};

bool InsideMargin(const CameraCalibration& camera, const Eigen::Vector2d& uv) {
  return uv.x() >= kMarginPx && uv.y() >= kMarginPx &&
         uv.x() <= camera.image_width - 1 - kMarginPx &&
         uv.y() <= camera.image_height - 1 - kMarginPx;
}

double DistanceAt(const View2D& view, const Eigen::Vector2d& uv) {
  const int x = std::clamp(static_cast<int>(std::lround(uv.x())), 0, view.width - 1);
  const int y = std::clamp(static_cast<int>(std::lround(uv.y())), 0, view.height - 1);
  return view.centreline_distance_px[static_cast<size_t>(y) * view.width + x];
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

CameraCalibration Corrected(const CameraCalibration& camera, const double w[3], double s) {
  const Eigen::Vector3d axis_angle(w[0], w[1], w[2]);
  const double angle = axis_angle.norm();
  const Eigen::Matrix3d correction =
      angle > 0 ? Eigen::AngleAxisd(angle, axis_angle / angle).toRotationMatrix()
                : Eigen::Matrix3d::Identity();
  CameraCalibration out = camera;
  out.rotation_camera_from_platform = correction * camera.rotation_camera_from_platform;
  out.translation_camera_from_platform = correction * camera.translation_camera_from_platform;
  out.camera_matrix(0, 0) *= 1.0 + s;
  out.camera_matrix(0, 1) *= 1.0 + s;
  out.camera_matrix(1, 1) *= 1.0 + s;
  return out;
}

// Median distance to the skeleton over every observation of `points` in `rig`.
double MedianDistance(const std::vector<View2D>& views, const RigCalibration& rig,
                      const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> d;
  for (const Eigen::Vector3d& p : points) {
    for (size_t v = 0; v < views.size(); ++v) {
      const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(p);
      if (uv && InsideMargin(rig.cameras[v], *uv)) d.push_back(DistanceAt(views[v], *uv));
    }
  }
  return Median(std::move(d));
}

}  // namespace

absl::Status RigRefineOptions::Validate() const {
  auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  if (reference_camera < -1) return absl::InvalidArgumentError("rig_refine.reference_camera < -1");
  if (!(min_probability >= 0 && min_probability <= 1))
    return absl::InvalidArgumentError("rig_refine.min_probability must be in [0, 1]");
  if (!(min_support >= 0 && min_support <= 1))
    return absl::InvalidArgumentError("rig_refine.min_support must be in [0, 1]");
  if (!positive(sample_step_m)) return absl::InvalidArgumentError("rig_refine.sample_step_m must be > 0");
  if (max_points < 1 || min_points < 1 || min_points > max_points)
    return absl::InvalidArgumentError("rig_refine: need 1 <= min_points <= max_points");
  if (!positive(reprojection_sd_px) || !positive(loss_scale_sd) || !positive(correction_prior_px) ||
      !positive(max_correction_px)) {
    return absl::InvalidArgumentError(
        "rig_refine: reprojection_sd_px, loss_scale_sd, correction_prior_px and max_correction_px "
        "must be > 0");
  }
  if (max_iterations < 1) return absl::InvalidArgumentError("rig_refine.max_iterations must be >= 1");
  return absl::OkStatus();
}

absl::StatusOr<RigCalibration> RefineRig(const std::vector<View2D>& views,
                                         const RigCalibration& rig,
                                         const std::vector<Piece3D>& pieces,
                                         const RigRefineOptions& options, const Deadline& deadline,
                                         RigRefineSummary* summary) {
  RigRefineSummary local;
  RigRefineSummary& out = summary != nullptr ? *summary : local;
  out = RigRefineSummary{};
  out.correction_px.assign(rig.cameras.size(), 0.0);
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("views: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  for (size_t v = 0; v < views.size(); ++v) {
    const size_t pixels = static_cast<size_t>(views[v].width) * views[v].height;
    if (views[v].width != rig.cameras[v].image_width ||
        views[v].height != rig.cameras[v].image_height ||
        views[v].centreline_distance_px.size() != pixels) {
      return absl::InvalidArgumentError(
          absl::StrCat("views[", v, "]: size or centreline distance map differs from camera '",
                       rig.cameras[v].name, "'"));
    }
  }
  if (options.reference_camera >= static_cast<int>(rig.cameras.size())) {
    return absl::InvalidArgumentError(absl::StrCat("rig_refine.reference_camera ",
                                                   options.reference_camera, ": the rig has ",
                                                   rig.cameras.size(), " cameras"));
  }
  if (!options.enabled || rig.cameras.size() < 2) {
    out.reason = options.enabled ? "one camera: nothing to refine against" : "disabled";
    return rig;
  }

  // Points along the confident pieces, seen inside (the margin of) at least two views.
  std::vector<Eigen::Vector3d> points;
  for (const Piece3D& piece : pieces) {
    if (piece.probability < options.min_probability || piece.support < options.min_support) continue;
    for (const Eigen::Vector3d& p : piece.polyline.Sample(options.sample_step_m)) {
      int seen = 0;
      for (const CameraCalibration& camera : rig.cameras) {
        const std::optional<Eigen::Vector2d> uv = camera.Project(p);
        seen += uv.has_value() && InsideMargin(camera, *uv);
      }
      if (seen >= 2) points.push_back(p);
    }
  }
  if (static_cast<int>(points.size()) > options.max_points) {
    std::vector<Eigen::Vector3d> thinned;
    const double stride = static_cast<double>(points.size()) / options.max_points;
    for (int k = 0; k < options.max_points; ++k) thinned.push_back(points[static_cast<size_t>(k * stride)]);
    points = std::move(thinned);
  }
  out.points = static_cast<int>(points.size());
  if (out.points < options.min_points) {
    out.reason = absl::StrCat("only ", out.points, " confident points seen by two views (need ",
                              options.min_points, ")");
    return rig;
  }
  out.median_before_px = MedianDistance(views, rig, points);

  std::vector<std::unique_ptr<SquaredDistanceField>> fields;
  std::vector<Projector> projectors;
  for (size_t v = 0; v < views.size(); ++v) {
    fields.push_back(std::make_unique<SquaredDistanceField>(views[v]));
    projectors.emplace_back(rig.cameras[v]);
  }
  std::vector<std::array<double, 3>> rotations(rig.cameras.size(), {0.0, 0.0, 0.0});
  std::vector<double> focal_scales(rig.cameras.size(), 0.0);
  std::vector<std::array<double, 3>> blocks(points.size());
  for (size_t i = 0; i < points.size(); ++i) blocks[i] = {points[i].x(), points[i].y(), points[i].z()};

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::CauchyLoss loss(options.loss_scale_sd);
  const double inv_sd = 1.0 / options.reprojection_sd_px;
  const size_t reference = options.reference_camera < 0
                               ? rig.cameras.size()  // none held fixed
                               : static_cast<size_t>(options.reference_camera);
  for (size_t i = 0; i < points.size(); ++i) {
    for (size_t v = 0; v < views.size(); ++v) {
      const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(points[i]);
      if (!uv || !InsideMargin(rig.cameras[v], *uv)) continue;
      if (v == reference) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CentrelineCost, 1, 3>(
                                     new CentrelineCost(projectors[v], fields[v]->interpolator(),
                                                        inv_sd)),
                                 &loss, blocks[i].data());
      } else {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<CorrectedCentrelineCost, 1, 3, 1, 3>(
                new CorrectedCentrelineCost(projectors[v], fields[v]->interpolator(), inv_sd)),
            &loss, rotations[v].data(), &focal_scales[v], blocks[i].data());
      }
      ++out.residuals;
    }
  }
  for (size_t v = 0; v < views.size(); ++v) {
    if (v == reference) continue;
    if (!problem.HasParameterBlock(rotations[v].data())) continue;  // the camera saw no point
    const double focal = rig.cameras[v].camera_matrix(0, 0);
    const double half_width = 0.5 * rig.cameras[v].image_width;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CorrectionPrior, 4, 3, 1>(
                                 new CorrectionPrior(focal / options.correction_prior_px,
                                                     half_width / options.correction_prior_px)),
                             nullptr, rotations[v].data(), &focal_scales[v]);
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;  // points eliminated, cameras dense
  solver_options.num_threads = 1;
  solver_options.max_num_iterations = options.max_iterations;
  VB_ASSIGN_OR_RETURN(const DeadlineSolve solve,
                      SolveWithDeadline(solver_options, &problem, deadline, "RefineRig"));
  if (solve.expired) return absl::DeadlineExceededError("RefineRig: deadline exceeded");
  const ceres::Solver::Summary& ceres_summary = solve.summary;
  if (!ceres_summary.IsSolutionUsable()) {
    out.reason = absl::StrCat("solve failed: ", ceres_summary.message);
    return rig;
  }

  RigCalibration refined = rig;
  for (size_t v = 0; v < rig.cameras.size(); ++v) {
    const Eigen::Vector3d w(rotations[v][0], rotations[v][1], rotations[v][2]);
    out.correction_px[v] = std::max(w.norm() * rig.cameras[v].camera_matrix(0, 0),
                                    std::abs(focal_scales[v]) * 0.5 * rig.cameras[v].image_width);
    if (out.correction_px[v] > options.max_correction_px) {
      out.reason = absl::StrCat("camera '", rig.cameras[v].name, "' would turn by ",
                                out.correction_px[v], " px; not trusted");
      return rig;
    }
    if (v != reference) {
      refined.cameras[v] = Corrected(rig.cameras[v], rotations[v].data(), focal_scales[v]);
    }
  }
  std::vector<Eigen::Vector3d> adjusted(points.size());
  for (size_t i = 0; i < points.size(); ++i) adjusted[i] = {blocks[i][0], blocks[i][1], blocks[i][2]};
  out.median_after_px = MedianDistance(views, refined, adjusted);
  out.applied = true;
  return refined;
}


void ReexpressLines(const CameraCalibration& from, const CameraCalibration& to,
                    std::vector<Line2D>* lines) {
  constexpr int kSamples = 33;
  for (Line2D& line : *lines) {
    // Points along the line's support that the camera sees (inside the image, and inside the fold
    // of the distortion, where the pixel maps back to the same normalised point: lines drawn
    // from a model may end far outside the image), through their pixels into the new normalised
    // coordinates.
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < kSamples; ++k) {
      const double f = static_cast<double>(k) / (kSamples - 1);
      const Eigen::Vector2d on_line = (1.0 - f) * line.begin + f * line.end;
      const Eigen::Vector2d uv = from.NormalisedToPixel(on_line);
      if (!from.InImage(uv) || (from.PixelToNormalised(uv) - on_line).norm() > 1e-6) continue;
      points.push_back(to.PixelToNormalised(uv));
    }
    if (points.size() < 2) continue;  // not seen: nothing to re-express
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const Eigen::Vector2d& p : points) scatter += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
    const Eigen::Vector2d normal = solver.eigenvectors().col(0);  // smallest eigenvalue
    line.line = Eigen::Vector3d(normal.x(), normal.y(), -normal.dot(mean));
    line.begin = points.front() - normal * normal.dot(points.front() - mean);
    line.end = points.back() - normal * normal.dot(points.back() - mean);
  }
}

}  // namespace vb::reconstruct
