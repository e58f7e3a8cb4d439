// SPDX-License-Identifier: Apache-2.0
// Ceres building blocks shared by the stages that fit to the images (cane_fit.cc, rig_refine.cc):
// the camera model templated for automatic differentiation, the distance-to-skeleton cost and a
// deadline callback. Internal to workers/reconstruct: include from .cc files only (Ceres is a
// private dependency of the library).
#pragma once

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "absl/status/statusor.h"
#include "ceres/ceres.h"
#include "ceres/cubic_interpolation.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

using Grid = ceres::Grid2D<float, 1>;
using Interpolator = ceres::BiCubicInterpolator<Grid>;

// The camera model of core/calibration.h, templated for automatic differentiation.
struct Projector {
  double r[9];
  double t[3];
  double fx, fy, skew, cx, cy;
  double k1, k2, p1, p2, k3;

  explicit Projector(const CameraCalibration& c) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r[3 * i + j] = c.rotation_camera_from_platform(i, j);
      t[i] = c.translation_camera_from_platform[i];
    }
    fx = c.camera_matrix(0, 0);
    fy = c.camera_matrix(1, 1);
    skew = c.camera_matrix(0, 1);
    cx = c.camera_matrix(0, 2);
    cy = c.camera_matrix(1, 2);
    std::tie(k1, k2, p1, p2, k3) =
        std::tuple(c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3],
                   c.distortion[4]);
  }

  // False if the point is (nearly) on or behind the image plane.
  template <typename T>
  bool operator()(const T* p, T* u, T* v) const {
    T pc[3];
    for (int i = 0; i < 3; ++i) pc[i] = r[3 * i] * p[0] + r[3 * i + 1] * p[1] + r[3 * i + 2] * p[2] + t[i];
    return FromCamera(pc, u, v);
  }

  // The pixel of a point in camera coordinates; false if it is (nearly) on or behind the image
  // plane.
  template <typename T>
  bool FromCamera(const T* pc, T* u, T* v) const {
    return FromCameraScaled(pc, T(1.0), u, v);
  }

  // As FromCamera with the focal length (fx, fy and skew) multiplied by `focal_scale`.
  template <typename T>
  bool FromCameraScaled(const T* pc, const T& focal_scale, T* u, T* v) const {
    if (!(pc[2] > T(1e-3))) return false;
    const T x = pc[0] / pc[2];
    const T y = pc[1] / pc[2];
    const T r2 = x * x + y * y;
    const T radial = T(1.0) + r2 * (k1 + r2 * (k2 + r2 * k3));
    const T xd = x * radial + T(2.0 * p1) * x * y + p2 * (r2 + T(2.0) * x * x);
    const T yd = y * radial + p1 * (r2 + T(2.0) * y * y) + T(2.0 * p2) * x * y;
    *u = focal_scale * (fx * xd + skew * yd) + cx;
    *v = focal_scale * (fy * yd) + cy;
    return true;
  }
};

// Distance in pixels from the projection of a point to the view's nearest skeleton point.
struct CentrelineCost {
  CentrelineCost(const Projector& projector, const Interpolator* interpolator, double inv_sd)
      : projector(projector), interpolator(interpolator), inv_sd(inv_sd) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    T u, v;
    if (!projector(p, &u, &v)) return false;
    T d2;
    interpolator->Evaluate(v, u, &d2);  // (row, column)
    // d2 can dip a hair below 0 between samples; the epsilon keeps the derivative finite at 0.
    residual[0] = sqrt(fmax(d2, T(0.0)) + T(1e-6)) * inv_sd;
    return true;
  }
  Projector projector;
  const Interpolator* interpolator;
  double inv_sd;
};

// A view's squared distance-to-skeleton map, ready for CentrelineCost. The cost reads the
// *squared* distance: Keys' cubic convolution reproduces quadratics, so interpolating d^2 and
// taking the root gives the sub-pixel distance to the skeleton, where interpolating d itself
// gives a flat-bottomed bowl (d ~ 2 x^2 within a pixel of the centreline) in which regularisers,
// not the images, would place the points. Not copyable (the interpolator points into it).
class SquaredDistanceField {
 public:
  // Precondition: view.centreline_distance_px has width * height values.
  explicit SquaredDistanceField(const View2D& view)
      : squared_(view.centreline_distance_px.size()) {
    std::transform(view.centreline_distance_px.begin(), view.centreline_distance_px.end(),
                   squared_.begin(), [](float d) { return d * d; });
    grid_ = std::make_unique<Grid>(squared_.data(), 0, view.height, 0, view.width);
    interpolator_ = std::make_unique<Interpolator>(*grid_);
  }
  SquaredDistanceField(const SquaredDistanceField&) = delete;
  SquaredDistanceField& operator=(const SquaredDistanceField&) = delete;

  const Interpolator* interpolator() const { return interpolator_.get(); }

 private:
  std::vector<float> squared_;
  std::unique_ptr<Grid> grid_;
  std::unique_ptr<Interpolator> interpolator_;
};

// Stops a solve when the deadline expires (keeping the best iterate) or aborts it on
// cancellation.
class DeadlineCallback : public ceres::IterationCallback {
 public:
  explicit DeadlineCallback(const Deadline& deadline) : deadline_(deadline) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (deadline_.Cancelled()) {
      cancelled_ = true;
      return ceres::SOLVER_ABORT;
    }
    if (deadline_.Expired()) {
      expired_ = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;  // keeps the current (best) iterate
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool cancelled() const { return cancelled_; }
  bool expired() const { return expired_; }

 private:
  const Deadline& deadline_;
  bool cancelled_ = false;
  bool expired_ = false;
};

struct DeadlineSolve {
  ceres::Solver::Summary summary;
  bool expired = false;  // the deadline stopped the solve (the iterate is the best so far)
};

// Solves `problem` with `options` made quiet (no logging) and bounded by `deadline` (time limit
// and a DeadlineCallback). `caller` names the stage in errors: INTERNAL if Ceres throws,
// CANCELLED on cancellation. An unusable solution is left for the caller to judge.
inline absl::StatusOr<DeadlineSolve> SolveWithDeadline(ceres::Solver::Options options,
                                                       ceres::Problem* problem,
                                                       const Deadline& deadline,
                                                       const std::string& caller) {
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.max_solver_time_in_seconds = std::min(deadline.RemainingS(), 1e6);
  DeadlineCallback callback(deadline);
  options.callbacks.push_back(&callback);
  DeadlineSolve out;
  try {
    ceres::Solve(options, problem, &out.summary);
  } catch (const std::exception& e) {
    return absl::InternalError(caller + ": Ceres threw: " + e.what());
  }
  if (callback.cancelled()) return absl::CancelledError(caller + ": cancelled");
  out.expired = callback.expired();
  return out;
}

}  // namespace vb::reconstruct
