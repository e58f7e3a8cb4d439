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

// One view as the growth reads it: where a 3D point projects, how far that is from the
// skeleton, and what the pixels around it are.
class ViewProbe {
 public:
  ViewProbe(const View2D& view, const CameraCalibration& camera, int margin_px);

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

 private:
  const View2D& view_;
  const CameraCalibration& camera_;
  int margin_;
  bool has_thick_;
};

// All views' evidence at a point (views[i] seen by rig.cameras[i]; the caller checks sizes).
class GrowEvidence {
 public:
  GrowEvidence(const std::vector<View2D>& views, const RigCalibration& rig,
               const GrowOptions& options);

  // The point near `predicted`, on the plane normal to the tangent, that best fits the skeletons
  // of all views (truncated squared distances plus prior_px_per_mm of pull per mm of offset): a
  // coarse grid of offsets, then a 4x finer one around the best.
  Eigen::Vector3d Correct(const Eigen::Vector3d& predicted, const Eigen::Vector3d& tangent,
                          double prior_px_per_mm) const;
  // Every view that sees p holds it within support_px of its skeleton, and at least
  // min_support_views do.
  bool EndSupported(const Eigen::Vector3d& p) const;
  // Why p (reached along the unit `step`, on a cane of `radius_m`) is not accepted, if it is
  // not: kThick, kContradicted or kUnsupported.
  std::optional<GrowStop> Check(const Eigen::Vector3d& p, const Eigen::Vector3d& step,
                                double radius_m) const;

 private:
  double Cost(const Eigen::Vector3d& p) const;
  bool AlongSkeleton(const ViewProbe& probe, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& step) const;

  const GrowOptions& options_;
  std::vector<ViewProbe> probes_;
};

}  // namespace vb::reconstruct::grow_internal
