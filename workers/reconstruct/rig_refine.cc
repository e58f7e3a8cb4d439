// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/rig_refine.h"

#include <algorithm>
#include <cmath>
#include <deque>
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

// Projects platform point p through `projector` with the corrections of a camera: rotation by the
// angle-axis `w` in the camera frame (x_cam' = R(w) (R x + t), the centre stays), focal length
// scaled by 1 + s[0], principal point moved by (s[1], s[2]) pixels. False behind the camera.
template <typename T>
bool ProjectCorrected(const Projector& projector, const T* w, const T* s, const T* p, T* u, T* v) {
  T pc[3];
  for (int i = 0; i < 3; ++i) {
    pc[i] = projector.r[3 * i] * p[0] + projector.r[3 * i + 1] * p[1] +
            projector.r[3 * i + 2] * p[2] + projector.t[i];
  }
  T rotated[3];
  ceres::AngleAxisRotatePoint(w, pc, rotated);
  if (!projector.FromCameraScaled(rotated, T(1.0) + s[0], u, v)) return false;
  *u += s[1];
  *v += s[2];
  return true;
}

// CentrelineCost for a camera whose rotation is corrected by the angle-axis `w` (applied in the
// camera frame: x_cam' = R(w) (R x + t), which keeps the camera centre where it is), whose
// focal length is scaled by 1 + s[0] and whose principal point moves by (s[1], s[2]) pixels.
struct CorrectedCentrelineCost {
  CorrectedCentrelineCost(const Projector& projector, const Interpolator* interpolator,
                        double inv_sd)
      : projector(projector), interpolator(interpolator), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* w, const T* s, const T* p, T* residual) const {
    T u, v;
    if (!ProjectCorrected(projector, w, s, p, &u, &v)) return false;
    T d2;
    interpolator->Evaluate(v, u, &d2);
    residual[0] = sqrt(fmax(d2, T(0.0)) + T(1e-6)) * inv_sd;
    return true;
  }
  Projector projector;
  const Interpolator* interpolator;
  double inv_sd;
};

// A fiducial of known platform position p seen at pixel uv by a camera with corrections (w, s).
struct FiducialCost {
  FiducialCost(const Projector& projector, const Eigen::Vector3d& p, const Eigen::Vector2d& uv,
               double inv_sd)
      : projector(projector), p(p), uv(uv), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* w, const T* s, T* residual) const {
    const T point[3] = {T(p.x()), T(p.y()), T(p.z())};
    T u, v;
    if (!ProjectCorrected(projector, w, s, point, &u, &v)) return false;
    residual[0] = (u - T(uv.x())) * T(inv_sd);
    residual[1] = (v - T(uv.y())) * T(inv_sd);
    return true;
  }
  Projector projector;
  Eigen::Vector3d p;
  Eigen::Vector2d uv;
  double inv_sd;
};

// Holds a correction near zero: residual = the pixels it moves the image by / prior_px, for the
// rotation (angle x focal length), the focal scale (s x half the image width) and the principal
// point.
struct CorrectionPrior {
  CorrectionPrior(double rotation_scale, double focal_scale, double principal_scale)
      : rotation_scale(rotation_scale), focal_scale(focal_scale),
        principal_scale(principal_scale) {}
  template <typename T>
  bool operator()(const T* w, const T* s, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = w[i] * rotation_scale;
    residual[3] = s[0] * focal_scale;
    residual[4] = s[1] * principal_scale;
    residual[5] = s[2] * principal_scale;
    return true;
  }
  double rotation_scale, focal_scale, principal_scale;
};

double ValueOf(double x) { return x; }
template <int N>
double ValueOf(const ceres::Jet<double, N>& x) {
  return x.a;
}

// A wire or post seen by one view: where a point at fraction `f` along the 3D line [a, b]
// projects, against the view's trace of its centre in pixels (Line2D::centre_px). The 3D line
// keeps its main-axis coordinate (x for wires, z for posts) at each end fixed; the other two of
// each end are the unknowns, so the line has its 4 degrees of freedom and no sliding along itself.
// A wire also sags: its points drop by sag x 4 f (1 - f), a parabola through its ends (the
// simulator's wires sag up to 3.5 cm between posts 6 m apart, a few millimetres over the view).
// The residual is the signed distance to the nearest chord of the curve: smooth across the
// curve, and its choice of chord only changes where two chords meet.
struct TrellisLineCost {
  TrellisLineCost(const Projector& projector, const std::vector<Eigen::Vector2d>* curve, int axis,
                  double a_axis, double b_axis, double f, double inv_sd)
      : projector(projector), curve(curve), axis(axis), a_axis(a_axis), b_axis(b_axis), f(f),
        inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* w, const T* s, const T* a, const T* b, const T* sag,
                  T* residual) const {
    T p[3];
    for (int k = 0, j = 0; k < 3; ++k) {
      if (k == axis) {
        p[k] = T(a_axis + f * (b_axis - a_axis));
      } else {
        p[k] = a[j] + T(f) * (b[j] - a[j]);
        ++j;
      }
    }
    p[2] -= sag[0] * T(4.0 * f * (1.0 - f));
    T u, v;
    if (!ProjectCorrected(projector, w, s, p, &u, &v)) return false;
    const Eigen::Vector2d at(ValueOf(u), ValueOf(v));
    size_t best = 0;
    double best_d2 = 1e300;
    for (size_t k = 0; k + 1 < curve->size(); ++k) {
      const Eigen::Vector2d c = (*curve)[k];
      const Eigen::Vector2d d = (*curve)[k + 1] - c;
      const double t = std::clamp((at - c).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const double d2 = (at - c - t * d).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = k;
      }
    }
    const Eigen::Vector2d c = (*curve)[best];
    const Eigen::Vector2d d = ((*curve)[best + 1] - c).normalized();
    residual[0] = ((u - T(c.x())) * T(d.y()) - (v - T(c.y())) * T(d.x())) * T(inv_sd);
    return true;
  }
  Projector projector;
  const std::vector<Eigen::Vector2d>* curve;
  int axis;
  double a_axis, b_axis, f, inv_sd;
};

// Holds a wire along the row (x) and a post upright (z): the difference of its ends' free
// coordinates per metre of the main axis, over sd.
struct TrellisDirectionPrior {
  explicit TrellisDirectionPrior(double scale) : scale(scale) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    residual[0] = (b[0] - a[0]) * scale;
    residual[1] = (b[1] - a[1]) * scale;
    return true;
  }
  double scale;  // 1 / (length x sd)
};

// The pixels of a straight 2D line (normalised coordinates of `camera`) every ~3 px along it, in
// order, where the camera sees it: inside the image and inside the fold of the distortion.
std::vector<Eigen::Vector2d> PixelCurve(const CameraCalibration& camera, const Line2D& line) {
  const Eigen::Vector2d normal = line.line.head<2>();
  const Eigen::Vector2d origin = -line.line.z() * normal;  // the line's point nearest (0, 0)
  const Eigen::Vector2d direction(normal.y(), -normal.x());
  const double step = 3.0 / camera.camera_matrix(0, 0);
  std::vector<Eigen::Vector2d> curve;
  for (double t = -3.0; t <= 3.0; t += step) {
    const Eigen::Vector2d xy = origin + t * direction;
    const Eigen::Vector2d uv = camera.NormalisedToPixel(xy);
    if (!camera.InImage(uv) || (camera.PixelToNormalised(uv) - xy).norm() > 1e-6) continue;
    curve.push_back(uv);
  }
  return curve;
}

// Whether uv lies beside the curve rather than beyond either of its ends.
bool AlongsideCurve(const std::vector<Eigen::Vector2d>& curve, const Eigen::Vector2d& uv) {
  size_t best = 0;
  double best_d2 = 1e300, best_t = 0.0;
  for (size_t k = 0; k + 1 < curve.size(); ++k) {
    const Eigen::Vector2d d = curve[k + 1] - curve[k];
    const double t = (uv - curve[k]).dot(d) / std::max(d.squaredNorm(), 1e-12);
    const double d2 = (uv - curve[k] - std::clamp(t, 0.0, 1.0) * d).squaredNorm();
    if (d2 < best_d2) best_d2 = d2, best = k, best_t = t;
  }
  return !(best == 0 && best_t < 0.0) && !(best + 2 == curve.size() && best_t > 1.0);
}

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
  const size_t reference = options.reference_camera < 0
                               ? rig.cameras.size()  // none held fixed
                               : static_cast<size_t>(options.reference_camera);
  // Fiducial detections (of cameras that are corrected).
  struct FiducialTerm {
    size_t view;
    const FiducialObservation* observation;
    ceres::ResidualBlockId id = nullptr;
  };
  std::vector<FiducialTerm> fiducial_terms;
  bool fiducials_suffice = false;
  if (options.use_fiducials) {
    fiducials_suffice = true;
    for (size_t v = 0; v < views.size(); ++v) {
      if (v == reference) continue;
      for (const FiducialObservation& f : views[v].fiducials) fiducial_terms.push_back({v, &f});
      fiducials_suffice = fiducials_suffice && static_cast<int>(views[v].fiducials.size()) >=
                                                    options.min_fiducials_per_camera;
    }
  }
  if (out.points < options.min_points && !fiducials_suffice) {
    out.reason = absl::StrCat("only ", out.points, " confident points seen by two views (need ",
                              options.min_points, ") and too few fiducials");
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
  // Per camera: focal scale - 1, and the principal point's shift in x and y, pixels.
  std::vector<std::array<double, 3>> intrinsics(rig.cameras.size(), {0.0, 0.0, 0.0});
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
                                     new CentrelineCost(projectors[v], fields[v]->interpolator(),
                                                        inv_sd)),
                                 &loss, blocks[i].data());
      } else {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<CorrectedCentrelineCost, 1, 3, 3, 3>(
                new CorrectedCentrelineCost(projectors[v], fields[v]->interpolator(), inv_sd)),
            &loss, rotations[v].data(), intrinsics[v].data(), blocks[i].data());
      }
      ++out.residuals;
    }
  }

  // Fiducials: the same robust scale in pixels as the canes'.
  ceres::CauchyLoss fiducial_loss(options.loss_scale_sd * options.reprojection_sd_px /
                                  options.fiducial_sd_px);
  for (FiducialTerm& term : fiducial_terms) {
    term.id = problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<FiducialCost, 2, 3, 3>(new FiducialCost(
            projectors[term.view],
            rig.fiducials[static_cast<size_t>(term.observation->fiducial)].position_in_platform,
            term.observation->uv_px, 1.0 / options.fiducial_sd_px)),
        &fiducial_loss, rotations[term.view].data(), intrinsics[term.view].data());
  }
  // Reprojection error of a fiducial detection, pixels, with the current corrections.
  auto fiducial_error = [&](const FiducialTerm& term) {
    const Eigen::Vector3d& p =
        rig.fiducials[static_cast<size_t>(term.observation->fiducial)].position_in_platform;
    double uv[2];
    if (!ProjectCorrected(projectors[term.view], rotations[term.view].data(),
                          intrinsics[term.view].data(), p.data(), &uv[0], &uv[1])) {
      return 1e6;
    }
    return (Eigen::Vector2d(uv[0], uv[1]) - term.observation->uv_px).norm();
  };
  auto fiducial_rms = [&]() {
    double sum = 0.0;
    for (const FiducialTerm& term : fiducial_terms) sum += std::pow(fiducial_error(term), 2);
    return fiducial_terms.empty() ? 0.0 : std::sqrt(sum / fiducial_terms.size());
  };

  // Priors on the corrections of every camera (but the reference) that has observations; called
  // again when the trellis brings in a camera that no cane point reached.
  std::vector<bool> has_prior(views.size(), false);
  auto add_priors = [&]() {
    for (size_t v = 0; v < views.size(); ++v) {
      if (v == reference || has_prior[v]) continue;
      if (!problem.HasParameterBlock(rotations[v].data())) continue;  // the camera saw nothing
      has_prior[v] = true;
      const double focal = rig.cameras[v].camera_matrix(0, 0);
      const double half_width = 0.5 * rig.cameras[v].image_width;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CorrectionPrior, 6, 3, 3>(
                                   new CorrectionPrior(focal / options.correction_prior_px,
                                                       half_width / options.correction_prior_px,
                                                       1.0 / options.correction_prior_px)),
                               nullptr, rotations[v].data(), intrinsics[v].data());
      if (!options.refine_principal_point) {
        problem.SetManifold(intrinsics[v].data(), new ceres::SubsetManifold(3, {1, 2}));
      }
    }
  };
  add_priors();
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
  auto set_cameras_constant = [&](bool constant) {
    for (size_t v = 0; v < views.size(); ++v) {
      if (!problem.HasParameterBlock(rotations[v].data())) continue;
      if (constant || v == reference) {
        problem.SetParameterBlockConstant(rotations[v].data());
        problem.SetParameterBlockConstant(intrinsics[v].data());
      } else {
        problem.SetParameterBlockVariable(rotations[v].data());
        problem.SetParameterBlockVariable(intrinsics[v].data());
      }
    }
  };
  // With the trellis, the canes refine the rig first; each wire or post is then fitted to that
  // rig alone, and one that misses its traces by more than trellis_max_rms_px is a mismatch and
  // is left out before everything is solved together.
  const bool staged = options.use_trellis && !trellis.empty();
  if (staged) {
    VB_ASSIGN_OR_RETURN(const bool usable, solve());
    if (!usable) return rig;
  }

  // Wires and posts: one 3D line per match, observed at trellis_samples points in every view
  // whose 2D line supports them (inside its extent and the image, with the calibrated rig).
  std::deque<std::vector<Eigen::Vector2d>> curves;  // per (match, view); costs point into it
  // The same robust scale in pixels as the canes'.
  ceres::CauchyLoss trellis_loss(options.loss_scale_sd * options.reprojection_sd_px /
                                 options.trellis_sd_px);
  std::vector<std::array<double, 2>> line_ends(2 * trellis.size());
  std::vector<double> sags(trellis.size(), 0.0);
  struct TrellisTerm {
    std::unique_ptr<TrellisLineCost> cost;  // a copy, for the RMS before and after
    size_t view, match;
  };
  std::vector<TrellisTerm> terms;
  if (options.use_trellis) {
    for (size_t m = 0; m < trellis.size(); ++m) {
      const TrellisLineMatch& match = trellis[m];
      const int axis = match.post ? 2 : 0;
      for (int k = 0, j = 0; k < 3; ++k) {
        if (k == axis) continue;
        line_ends[2 * m][j] = match.a[k];
        line_ends[2 * m + 1][j] = match.b[k];
        ++j;
      }
      int seen_by = 0;
      for (size_t v = 0; v < views.size(); ++v) seen_by += match.lines[v] >= 0;
      if (seen_by < 3) continue;  // two views' planes always meet: nothing to learn
      const size_t first_term = terms.size();
      for (size_t v = 0; v < views.size(); ++v) {
        if (match.lines[v] < 0) continue;
        const CameraCalibration& camera = rig.cameras[v];
        const Line2D& line = match.post ? views[v].posts[static_cast<size_t>(match.lines[v])]
                                        : views[v].wires[static_cast<size_t>(match.lines[v])];
        curves.push_back(line.centre_px.size() >= 2 ? line.centre_px : PixelCurve(camera, line));
        if (curves.back().size() < 2) continue;
        for (int k = 0; k < options.trellis_samples; ++k) {
          const double f = (k + 0.5) / options.trellis_samples;
          const std::optional<Eigen::Vector2d> uv = camera.Project(match.a + f * (match.b - match.a));
          if (!uv || !InsideMargin(camera, *uv) || !AlongsideCurve(curves.back(), *uv)) continue;
          auto cost = std::make_unique<TrellisLineCost>(projectors[v], &curves.back(), axis,
                                                        match.a[axis], match.b[axis], f,
                                                        1.0 / options.trellis_sd_px);
          terms.push_back({std::make_unique<TrellisLineCost>(*cost), v, m});
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<TrellisLineCost, 1, 3, 3, 2, 2, 1>(cost.release()),
              &trellis_loss, rotations[v].data(), intrinsics[v].data(), line_ends[2 * m].data(),
              line_ends[2 * m + 1].data(), &sags[m]);
        }
      }
      if (terms.size() > first_term) {
        ++out.trellis_lines;
        const double length = std::abs(match.b[axis] - match.a[axis]);
        if (options.trellis_direction_sd > 0 && length > 0.1) {
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<TrellisDirectionPrior, 2, 2, 2>(
                  new TrellisDirectionPrior(1.0 / (length * options.trellis_direction_sd))),
              nullptr, line_ends[2 * m].data(), line_ends[2 * m + 1].data());
        }
        if (match.post || !options.trellis_wire_sag) problem.SetParameterBlockConstant(&sags[m]);
      }
    }
    if (!terms.empty()) {
      add_priors();
      set_cameras_constant(true);
      VB_ASSIGN_OR_RETURN(const bool usable, solve());
      if (!usable) return rig;
      std::vector<double> sum(trellis.size(), 0.0);
      std::vector<int> count(trellis.size(), 0);
      for (const TrellisTerm& term : terms) {
        double r = 0.0;
        if ((*term.cost)(rotations[term.view].data(), intrinsics[term.view].data(),
                         line_ends[2 * term.match].data(), line_ends[2 * term.match + 1].data(),
                         &sags[term.match], &r)) {
          sum[term.match] += r * r * options.trellis_sd_px * options.trellis_sd_px;
        } else {
          sum[term.match] += 1e6;  // behind a camera: certainly a mismatch
        }
        ++count[term.match];
      }
      for (size_t m = 0; m < trellis.size(); ++m) {
        if (count[m] == 0 || std::sqrt(sum[m] / count[m]) <= options.trellis_max_rms_px) continue;
        // Removing its parameter blocks removes its residuals (and its direction prior).
        problem.RemoveParameterBlock(line_ends[2 * m].data());
        problem.RemoveParameterBlock(line_ends[2 * m + 1].data());
        problem.RemoveParameterBlock(&sags[m]);
        --out.trellis_lines;
        ++out.trellis_rejected;
      }
      std::erase_if(terms, [&](const TrellisTerm& term) {
        return count[term.match] > 0 &&
               std::sqrt(sum[term.match] / count[term.match]) > options.trellis_max_rms_px;
      });
      set_cameras_constant(false);
    }
    out.trellis_residuals = static_cast<int>(terms.size());
  }
  auto trellis_rms = [&]() {
    double sum = 0.0;
    int n = 0;
    for (const TrellisTerm& term : terms) {
      double r = 0.0;
      if ((*term.cost)(rotations[term.view].data(), intrinsics[term.view].data(),
                       line_ends[2 * term.match].data(), line_ends[2 * term.match + 1].data(),
                       &sags[term.match], &r)) {
        sum += r * r * options.trellis_sd_px * options.trellis_sd_px;
        ++n;
      }
    }
    return n > 0 ? std::sqrt(sum / n) : 0.0;
  };
  out.trellis_rms_before_px = trellis_rms();

  {
    VB_ASSIGN_OR_RETURN(const bool usable, solve());
    if (!usable) return rig;
  }
  // A detection the solved rig misses by more than fiducial_max_residual_px is not its fiducial
  // (a bright thing nearby, a disc partly hidden): leave it out and solve again.
  if (!fiducial_terms.empty()) {
    const size_t before = fiducial_terms.size();
    std::erase_if(fiducial_terms, [&](const FiducialTerm& term) {
      const double error = fiducial_error(term);
      if (error <= options.fiducial_max_residual_px) return false;
      problem.RemoveResidualBlock(term.id);
      out.fiducial_log.push_back(absl::StrCat(
          rig.cameras[term.view].name, " ",
          rig.fiducials[static_cast<size_t>(term.observation->fiducial)].name, ": detected at (",
          term.observation->uv_px.x(), ", ", term.observation->uv_px.y(), "), ", error,
          " px from where the refined rig projects it (limit ", options.fiducial_max_residual_px,
          "): rejected"));
      return true;
    });
    out.fiducials_rejected = static_cast<int>(before - fiducial_terms.size());
    if (out.fiducials_rejected > 0) {
      VB_ASSIGN_OR_RETURN(const bool usable, solve());
      if (!usable) return rig;
    }
    out.fiducial_observations = static_cast<int>(fiducial_terms.size());
    out.fiducial_rms_after_px = fiducial_rms();
    for (const FiducialTerm& term : fiducial_terms) {
      const std::optional<Eigen::Vector2d> uv = rig.cameras[term.view].Project(
          rig.fiducials[static_cast<size_t>(term.observation->fiducial)].position_in_platform);
      out.fiducial_rms_before_px += uv ? (*uv - term.observation->uv_px).squaredNorm() : 1e12;
    }
    out.fiducial_rms_before_px = std::sqrt(out.fiducial_rms_before_px / std::max<size_t>(fiducial_terms.size(), 1));
  }

  RigCalibration refined = rig;
  for (size_t v = 0; v < rig.cameras.size(); ++v) {
    const Eigen::Vector3d w(rotations[v][0], rotations[v][1], rotations[v][2]);
    out.correction_px[v] = std::max(w.norm() * rig.cameras[v].camera_matrix(0, 0),
                                    std::max(std::abs(intrinsics[v][0]) * 0.5 * rig.cameras[v].image_width,
                                             std::hypot(intrinsics[v][1], intrinsics[v][2])));
    if (out.correction_px[v] > options.max_correction_px) {
      out.reason = absl::StrCat("camera '", rig.cameras[v].name, "' would turn by ",
                                out.correction_px[v], " px; not trusted");
      return rig;
    }
    if (v != reference) {
      refined.cameras[v] = Corrected(rig.cameras[v], rotations[v].data(), intrinsics[v]);
    }
  }
  std::vector<Eigen::Vector3d> adjusted(points.size());
  for (size_t i = 0; i < points.size(); ++i) adjusted[i] = {blocks[i][0], blocks[i][1], blocks[i][2]};
  out.median_after_px = MedianDistance(views, refined, adjusted);
  out.trellis_rms_after_px = trellis_rms();
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
