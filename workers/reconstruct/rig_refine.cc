// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/rig_refine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/statistics.h"
#include "core/status_macros.h"
#include "Eigen/Eigenvalues"
#include "workers/reconstruct/ceres_camera.h"
#include "workers/reconstruct/rig_refine_costs.h"
#include "workers/reconstruct/rig_refine_terms.h"

namespace vb::reconstruct {
namespace {

using rig_refine_internal::CorrectedCentrelineCost;
using rig_refine_internal::FiducialTerms;
using rig_refine_internal::InsideMargin;
using rig_refine_internal::RigUnknowns;
using rig_refine_internal::TrellisTerms;

double DistanceAt(const View2D& view, const Eigen::Vector2d& uv) {
  const int x = std::clamp(static_cast<int>(std::lround(uv.x())), 0, view.width - 1);
  const int y = std::clamp(static_cast<int>(std::lround(uv.y())), 0, view.height - 1);
  return view.centreline_distance_px[static_cast<size_t>(y) * view.width + x];
}

CameraCalibration Corrected(const CameraCalibration& camera, const double w[3],
                            const std::array<double, 3>& intrinsics) {
  const double s = intrinsics[0];
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
  out.camera_matrix(0, 2) += intrinsics[1];
  out.camera_matrix(1, 2) += intrinsics[2];
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

// INVALID_ARGUMENT naming the view, trellis match or fiducial that does not fit the rig.
absl::Status ValidateInputs(const std::vector<View2D>& views, const RigCalibration& rig,
                            const std::vector<TrellisLineMatch>& trellis,
                            const RigRefineOptions& options) {
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
  for (size_t m = 0; m < trellis.size(); ++m) {
    if (trellis[m].lines.size() != views.size()) {
      return absl::InvalidArgumentError(absl::StrCat("trellis[", m, "]: ", trellis[m].lines.size(),
                                                     " line indices for ", views.size(), " views"));
    }
    for (size_t v = 0; v < views.size(); ++v) {
      const int count = static_cast<int>(trellis[m].post ? views[v].posts.size() : views[v].wires.size());
      if (trellis[m].lines[v] < -1 || trellis[m].lines[v] >= count) {
        return absl::InvalidArgumentError(absl::StrCat("trellis[", m, "].lines[", v, "] = ",
                                                       trellis[m].lines[v], ": the view has ",
                                                       count, " such lines"));
      }
    }
  }
  for (size_t v = 0; v < views.size(); ++v) {
    for (size_t k = 0; k < views[v].fiducials.size(); ++k) {
      const FiducialObservation& f = views[v].fiducials[k];
      if (f.fiducial < 0 || f.fiducial >= static_cast<int>(rig.fiducials.size()) ||
          !f.uv_px.allFinite()) {
        return absl::InvalidArgumentError(
            absl::StrCat("views[", v, "].fiducials[", k, "]: fiducial ", f.fiducial,
                         " (the rig has ", rig.fiducials.size(), ") or its pixel is invalid"));
      }
    }
  }
  if (options.reference_camera >= static_cast<int>(rig.cameras.size())) {
    return absl::InvalidArgumentError(absl::StrCat("rig_refine.reference_camera ",
                                                   options.reference_camera, ": the rig has ",
                                                   rig.cameras.size(), " cameras"));
  }
  return absl::OkStatus();
}

// Points along the confident pieces, seen inside (the margin of) at least two views, evenly
// thinned to options.max_points.
std::vector<Eigen::Vector3d> ConfidentPoints(const std::vector<Piece3D>& pieces,
                                             const RigCalibration& rig,
                                             const RigRefineOptions& options) {
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
  return points;
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
  if (!positive(trellis_sd_px) || !positive(trellis_match_residual_px) ||
      !positive(trellis_max_rms_px) || !(trellis_direction_sd >= 0))
    return absl::InvalidArgumentError(
        "rig_refine: trellis_sd_px, trellis_match_residual_px and trellis_max_rms_px must be > 0, "
        "trellis_direction_sd >= 0");
  if (trellis_samples < 2) return absl::InvalidArgumentError("rig_refine.trellis_samples must be >= 2");
  if (!positive(fiducial_sd_px)) return absl::InvalidArgumentError("rig_refine.fiducial_sd_px must be > 0");
  if (!positive(fiducial_max_residual_px))
    return absl::InvalidArgumentError("rig_refine.fiducial_max_residual_px must be > 0");
  if (min_fiducials_per_camera < 3)
    return absl::InvalidArgumentError("rig_refine.min_fiducials_per_camera must be >= 3");
  return absl::OkStatus();
}

absl::StatusOr<RigCalibration> RefineRig(const std::vector<View2D>& views,
                                         const RigCalibration& rig,
                                         const std::vector<Piece3D>& pieces,
                                         const RigRefineOptions& options, const Deadline& deadline,
                                         RigRefineSummary* summary) {
  return RefineRig(views, rig, pieces, {}, options, deadline, summary);
}

absl::StatusOr<RigCalibration> RefineRig(const std::vector<View2D>& views,
                                         const RigCalibration& rig,
                                         const std::vector<Piece3D>& pieces,
                                         const std::vector<TrellisLineMatch>& trellis,
                                         const RigRefineOptions& options, const Deadline& deadline,
                                         RigRefineSummary* summary) {
  RigRefineSummary local;
  RigRefineSummary& out = summary != nullptr ? *summary : local;
  out = RigRefineSummary{};
  out.correction_px.assign(rig.cameras.size(), 0.0);
  if (absl::Status s = ValidateInputs(views, rig, trellis, options); !s.ok()) return s;
  if (!options.enabled || rig.cameras.size() < 2) {
    out.reason = options.enabled ? "one camera: nothing to refine against" : "disabled";
    return rig;
  }

  const std::vector<Eigen::Vector3d> points = ConfidentPoints(pieces, rig, options);
  out.points = static_cast<int>(points.size());
  const size_t reference = options.reference_camera < 0
                               ? rig.cameras.size()  // none held fixed
                               : static_cast<size_t>(options.reference_camera);
  // Fiducial detections (of cameras that are corrected).
  FiducialTerms fiducials(views, rig, reference, options);
  if (out.points < options.min_points && !fiducials.suffice()) {
    out.reason = absl::StrCat("only ", out.points, " confident points seen by two views (need ",
                              options.min_points, ") and too few fiducials");
    return rig;
  }
  out.median_before_px = MedianDistance(views, rig, points);

  std::vector<std::unique_ptr<SquaredDistanceField>> fields;
  for (const View2D& view : views) fields.push_back(std::make_unique<SquaredDistanceField>(view));
  RigUnknowns unknowns(rig, reference);
  std::vector<std::array<double, 3>> blocks(points.size());
  for (size_t i = 0; i < points.size(); ++i) blocks[i] = {points[i].x(), points[i].y(), points[i].z()};

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::CauchyLoss loss(options.loss_scale_sd);
  const double inv_sd = 1.0 / options.reprojection_sd_px;
  for (size_t i = 0; i < points.size(); ++i) {
    for (size_t v = 0; v < views.size(); ++v) {
      const std::optional<Eigen::Vector2d> uv = rig.cameras[v].Project(points[i]);
      if (!uv || !InsideMargin(rig.cameras[v], *uv)) continue;
      if (v == reference) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CentrelineCost, 1, 3>(
                                     new CentrelineCost(unknowns.projectors[v],
                                                        fields[v]->interpolator(), inv_sd)),
                                 &loss, blocks[i].data());
      } else {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<CorrectedCentrelineCost, 1, 3, 3, 3>(
                new CorrectedCentrelineCost(unknowns.projectors[v], fields[v]->interpolator(),
                                            inv_sd)),
            &loss, unknowns.rotations[v].data(), unknowns.intrinsics[v].data(),
            blocks[i].data());
      }
      ++out.residuals;
    }
  }
  // Fiducials and the trellis: the same robust scale in pixels as the canes'.
  ceres::CauchyLoss fiducial_loss(options.loss_scale_sd * options.reprojection_sd_px /
                                  options.fiducial_sd_px);
  fiducials.AddTo(&unknowns, &fiducial_loss, 1.0 / options.fiducial_sd_px, &problem);
  unknowns.AddPriors(rig, options, &problem);

  ceres::Solver::Options solver_options;
  // Points eliminated, cameras dense; with fiducials alone there is nothing to eliminate.
  solver_options.linear_solver_type = points.empty() ? ceres::DENSE_QR : ceres::DENSE_SCHUR;
  solver_options.num_threads = 1;
  solver_options.max_num_iterations = options.max_iterations;
  // One solve; false (with out.reason set) when its solution is unusable.
  auto solve = [&]() -> absl::StatusOr<bool> {
    VB_ASSIGN_OR_RETURN(const DeadlineSolve result,
                        SolveWithDeadline(solver_options, &problem, deadline, "RefineRig"));
    if (result.expired) return absl::DeadlineExceededError("RefineRig: deadline exceeded");
    if (!result.summary.IsSolutionUsable()) {
      out.reason = absl::StrCat("solve failed: ", result.summary.message);
      return false;
    }
    return true;
  };

  // With the trellis, the canes refine the rig first; each wire or post is then fitted to that
  // rig alone, and one that misses its traces by more than trellis_max_rms_px is a mismatch and
  // is left out before everything is solved together.
  TrellisTerms trellis_terms(trellis, options);
  ceres::CauchyLoss trellis_loss(options.loss_scale_sd * options.reprojection_sd_px /
                                 options.trellis_sd_px);
  if (options.use_trellis) {
    if (!trellis.empty()) {
      VB_ASSIGN_OR_RETURN(const bool usable, solve());
      if (!usable) return rig;
    }
    out.trellis_lines = trellis_terms.AddTo(views, rig, &unknowns, &trellis_loss, &problem);
    if (trellis_terms.residuals() > 0) {
      unknowns.AddPriors(rig, options, &problem);
      unknowns.SetCamerasConstant(true, &problem);
      VB_ASSIGN_OR_RETURN(const bool usable, solve());
      if (!usable) return rig;
      out.trellis_rejected =
          trellis_terms.RejectMismatches(unknowns, options.trellis_max_rms_px, &problem);
      out.trellis_lines -= out.trellis_rejected;
      unknowns.SetCamerasConstant(false, &problem);
    }
    out.trellis_residuals = trellis_terms.residuals();
  }
  out.trellis_rms_before_px = trellis_terms.Rms(unknowns);

  {
    VB_ASSIGN_OR_RETURN(const bool usable, solve());
    if (!usable) return rig;
  }
  // A detection the solved rig misses by more than fiducial_max_residual_px is not its fiducial
  // (a bright thing nearby, a disc partly hidden): leave it out and solve again.
  if (!fiducials.empty()) {
    out.fiducials_rejected = fiducials.RejectOutliers(unknowns, options.fiducial_max_residual_px,
                                                      &problem, &out.fiducial_log);
    if (out.fiducials_rejected > 0) {
      VB_ASSIGN_OR_RETURN(const bool usable, solve());
      if (!usable) return rig;
    }
    out.fiducial_observations = fiducials.size();
    out.fiducial_rms_after_px = fiducials.RmsCorrected(unknowns);
    out.fiducial_rms_before_px = fiducials.RmsCalibrated();
  }

  RigCalibration refined = rig;
  for (size_t v = 0; v < rig.cameras.size(); ++v) {
    const std::array<double, 3>& w = unknowns.rotations[v];
    const std::array<double, 3>& intrinsics = unknowns.intrinsics[v];
    out.correction_px[v] = std::max(Eigen::Vector3d(w[0], w[1], w[2]).norm() *
                                        rig.cameras[v].camera_matrix(0, 0),
                                    std::max(std::abs(intrinsics[0]) * 0.5 * rig.cameras[v].image_width,
                                             std::hypot(intrinsics[1], intrinsics[2])));
    if (out.correction_px[v] > options.max_correction_px) {
      out.reason = absl::StrCat("camera '", rig.cameras[v].name, "' would turn by ",
                                out.correction_px[v], " px; not trusted");
      return rig;
    }
    if (v != reference) refined.cameras[v] = Corrected(rig.cameras[v], w.data(), intrinsics);
  }
  std::vector<Eigen::Vector3d> adjusted(points.size());
  for (size_t i = 0; i < points.size(); ++i) adjusted[i] = {blocks[i][0], blocks[i][1], blocks[i][2]};
  out.median_after_px = MedianDistance(views, refined, adjusted);
  out.trellis_rms_after_px = trellis_terms.Rms(unknowns);
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
