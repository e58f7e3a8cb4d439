// SPDX-License-Identifier: Apache-2.0
// The Ceres cost functions of RefineRig (rig_refine.h): a camera's corrections (rotation about its
// centre, focal scale, principal point shift) applied to its projection, and the residuals of cane
// points, fiducials, wires and posts and the priors through them. Internal to rig_refine*.cc:
// include from .cc files only (Ceres is a private dependency of the library).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "ceres/rotation.h"
#include "Eigen/Core"
#include "workers/reconstruct/ceres_camera.h"

namespace vb::reconstruct::rig_refine_internal {

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

inline double ValueOf(double x) { return x; }
template <int N>
inline double ValueOf(const ceres::Jet<double, N>& x) {
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

}  // namespace vb::reconstruct::rig_refine_internal
