// SPDX-License-Identifier: Apache-2.0
// The views' evidence for cane growth (grow.h), shared by its sources: where a 3D point projects
// in each view and how near the skeleton, the correction of a predicted point against all views,
// and the support test of a point (grow_probe.cc); the stepping of an end and the stage itself
// are in grow.cc. Not part of grow.h's contract. Both classes refer to the views, cameras and
// options they were built from, which must outlive them; their methods are const and thread-safe.
#pragma once

#include <optional>
#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::grow_internal {

// Per pixel of `view`: the distance in pixels to the nearest background pixel (0 on background;
// wires and posts count as wood, since they may hide it), the radius of the largest disc of wood
// around it. Row-major, width * height; all zero when the view has no class image.
std::vector<float> WoodRadiusMap(const View2D& view);

// One view as the growth reads it: where a 3D point projects, how far that is from the
// skeleton, and what the pixels around it are. `wood_radius` (WoodRadiusMap of the view, or
// null: then no point is inside a band) must outlive the probe.
class ViewProbe {
 public:
  ViewProbe(const View2D& view, const CameraCalibration& camera, int margin_px,
            const std::vector<float>* wood_radius = nullptr);

  // The pixel of p when it lies at least the margin inside the image.
  std::optional<Eigen::Vector2d> Inside(const Eigen::Vector3d& p) const;
  // Distance to the skeleton at uv, bilinear between pixel centres (uv inside the image).
  double Distance(const Eigen::Vector2d& uv) const;
  // uv's nearest pixel is in the view's thick (head or trunk) region.
  bool Thick(const Eigen::Vector2d& uv) const;
  // Only background within the point's projected radius (at least one pixel): this view should
  // see wood there and does not. Wires and posts are in front of canes, so they do not
  // contradict.
  bool Background(const Eigen::Vector2d& uv, const Eigen::Vector3d& p, double radius_m) const;
  Eigen::Vector3d Centre() const { return camera_.CentreInPlatform(); }
  // The radius (px) that a cross-section of radius_m at p projects to.
  double RadiusPx(const Eigen::Vector3d& p, double radius_m) const;
  // The wood radius at uv (WoodRadiusMap), bilinear between pixel centres; 0 without the map.
  double WoodRadius(const Eigen::Vector2d& uv) const;
  // Whether uv lies in a band of wood wider than a cane of radius_px: the band's half-width
  // through uv (its skeleton distance plus its distance to the background) exceeds radius_px by
  // margin_px. If so, how far a cross-section of radius_px at uv reaches out of the wood beyond
  // tolerance_px (0: it lies inside the band); nullopt otherwise and without the map.
  std::optional<double> BandExcess(const Eigen::Vector2d& uv, double radius_px, double margin_px,
                                   double tolerance_px) const;
  // A skeleton observation of a point p on a cane running along the unit `tangent` (refit,
  // grow_refit.cc): the skeleton point nearest p's projection along the normal to the
  // projected tangent, within search_px (where the skeleton crosses that normal: its distance
  // there is at most a pixel). `residual_px` is the projection's signed offset from it along
  // the normal, `jacobian` the residual's change per mm of p's offset along u and along w.
  // nullopt where the view does not see p, the cane runs along the ray, or no skeleton is near.
  struct Observation {
    double residual_px = 0.0;
    Eigen::Vector2d jacobian = Eigen::Vector2d::Zero();
  };
  std::optional<Observation> Observe(const Eigen::Vector3d& p, const Eigen::Vector3d& tangent,
                                     const Eigen::Vector3d& u, const Eigen::Vector3d& w,
                                     double search_px) const;

 private:
  const View2D& view_;
  const CameraCalibration& camera_;
  int margin_;
  bool has_thick_;
  const std::vector<float>* wood_radius_;
};

// All views' evidence at a point (views[i] seen by rig.cameras[i]; the caller checks sizes).
// Computes each view's WoodRadiusMap when options.band_support or band_end_support is on.
class GrowEvidence {
 public:
  GrowEvidence(const std::vector<View2D>& views, const RigCalibration& rig,
               const GrowOptions& options);
  // The probes point into this object's own radius maps: not copyable.
  GrowEvidence(const GrowEvidence&) = delete;
  GrowEvidence& operator=(const GrowEvidence&) = delete;

  // The point near `predicted`, on the plane normal to the tangent, that best fits the skeletons
  // of all views (truncated squared distances plus prior_px_per_mm of pull per mm of offset): a
  // coarse grid of offsets, then a 4x finer one around the best. With band_support a view's
  // distance is, where p lies in a band wider than the cane, the lesser of the skeleton distance
  // and ViewProbe::BandExcess of the point's cross-section (radius_m).
  Eigen::Vector3d Correct(const Eigen::Vector3d& predicted, const Eigen::Vector3d& tangent,
                          double prior_px_per_mm, double radius_m) const;
  // Every view that sees p holds it within support_px of its skeleton (or, with
  // band_end_support, inside a band wider than the cane: InBand), and at least
  // min_support_views do.
  bool EndSupported(const Eigen::Vector3d& p, double radius_m) const;
  // Why p (reached along the unit `step`, on a cane of `radius_m`) is not accepted, if it is
  // not: kThick, kContradicted or kUnsupported. `banded` (may be null) is set to whether some
  // view supported p only by lying inside a band (band_support).
  std::optional<GrowStop> Check(const Eigen::Vector3d& p, const Eigen::Vector3d& step,
                                double radius_m, bool* banded = nullptr) const;
  // Refits curve[first_free..] jointly (refit_span_m; grow_refit.cc): each point moves on the
  // plane normal to the curve there, to minimise the squared pixel offsets of its projections
  // from the skeleton of every view that holds it within refit_search_px (ViewProbe::Observe)
  // plus refit_smooth_px_per_mm of cost per mm that a point lies off the chord of its two
  // neighbours; curve[..first_free) are fixed and anchor the bend. A few Gauss-Newton
  // iterations, the observations found again in each. Needs first_free >= 2; else a no-op.
  void Refit(std::vector<Eigen::Vector3d>* curve, size_t first_free) const;

 private:
  double Cost(const Eigen::Vector3d& p, double radius_m) const;
  // Whether the points half a step before and after p satisfy `near` too.
  template <typename Near>
  bool Along(const ViewProbe& probe, const Eigen::Vector3d& p, const Eigen::Vector3d& step,
             const Near& near) const;
  std::optional<double> BandExcess(const ViewProbe& probe, const Eigen::Vector2d& uv,
                                   const Eigen::Vector3d& p, double radius_m) const;
  // BandExcess is 0: p's cross-section lies inside a band wider than the cane.
  bool InBand(const ViewProbe& probe, const Eigen::Vector2d& uv, const Eigen::Vector3d& p,
              double radius_m) const;

  const GrowOptions& options_;
  std::vector<std::vector<float>> wood_radius_;  // per view, when a band option is on
  std::vector<ViewProbe> probes_;
};

}  // namespace vb::reconstruct::grow_internal
