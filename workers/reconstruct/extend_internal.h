// SPDX-License-Identifier: Apache-2.0
// The parts of the single-view extension (extend.h) shared by its sources: following a view's
// skeleton in 2D (extend_paths.cc) and the which-tips rules and anchors (extend_tips.cc); the
// depths and the stage itself are in extend.cc. Not part of extend.h's contract. The classes
// hold no shared state; the functions are pure.
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/extend.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::extend_internal {

// Per view: which model cane (index into the model's canes) each pixel is near, -1 for none. The
// extension stops where its 2D path runs onto another cane: that wood is reconstructed already
// (or the path has switched to a cane it crosses).
class CaneLabels {
 public:
  CaneLabels(int width, int height);
  // Labels the pixels within the projected radius (radius_m, ProjectedRadiusPx) plus margin_px
  // of the polyline `points`, sampled every 1 mm, with `label` (later drawings overwrite).
  void Draw(const CameraCalibration& camera, const std::vector<Eigen::Vector3d>& points,
            double radius_m, double margin_px, int label);
  // The label at uv's nearest pixel; -1 outside the image.
  int At(const Eigen::Vector2d& uv) const;

 private:
  int width_, height_;
  std::vector<int> label_;
};

// Skeleton points of a view in 8 px cells, for finding the path under a projected tip. Refers to
// `view`, which must outlive it.
class SkeletonIndex {
 public:
  explicit SkeletonIndex(const View2D& view);
  // The skeleton point nearest to uv within r px: (segment, index), or nullopt.
  std::optional<std::pair<int, int>> Nearest(const Eigen::Vector2d& uv, double r) const;

 private:
  static constexpr int kCell = 8;
  const View2D& view_;
  int cols_ = 0, rows_ = 0;
  std::vector<std::vector<std::pair<int, int>>> cells_;
};

// Unit direction of a 2D path over its first (from_front) or last ~`span` px; zero for a path
// of fewer than two points or no extent.
Eigen::Vector2d PathDirection(const std::vector<Eigen::Vector2d>& pts, bool from_front,
                              double span = 6.0);

// The skeleton path from point k of segment s, walking toward increasing indices (forward) or
// decreasing, through junctions where a path continues within max_turn; at most max_px long.
std::vector<Eigen::Vector2d> FollowSkeleton(const View2D& view, int s, int k, bool forward,
                                            double max_turn, double max_px);

// Points of `path` every `step` px of arc length, starting `step` past its first point.
std::vector<Eigen::Vector2d> Resample(const std::vector<Eigen::Vector2d>& path, double step);

// The anchors of a cane's tip (extend.h): options.anchor_points points step_m apart ending at
// the tip, oldest first; with anchor_span_m > 0 on the line fitted to the cane's last
// anchor_span_m, anchored at its last point. `line` is at least 2 points and > 0 long.
std::vector<Eigen::Vector3d> TipAnchors(const Polyline3& line, const ExtendOptions& options);

// Whether the which-tips rules skip a tip at `tip` with unit tangent `tangent`: farther than
// max_tip_row_distance_m along the row from the trunk's top x (`trunk_x`, none: no such rule),
// or pointing across the row beyond max_tip_out_of_plane. (The support rule is TipSupportOf.)
bool FarOrAcross(const Eigen::Vector3d& tip, const Eigen::Vector3d& tangent,
                 const std::optional<double>& trunk_x, const ExtendOptions& options);

}  // namespace vb::reconstruct::extend_internal
