// SPDX-License-Identifier: Apache-2.0
// Test support for the correspondence tests (correspondence*_test.cc): straight canes drawn by
// SyntheticViews through the simulator's rig, and the distances their checks use. Header-only;
// tests only.
#pragma once

#include <algorithm>
#include <vector>

#include "core/geometry.h"
#include "core/vine_model.h"
#include "sim/rig.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/synthetic_views.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// A straight cane from a to b of constant radius; id 1 is the trunk, any other id a cane on it.
inline Cane MakeCane(int id, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  Cane cane;
  cane.id = CaneId(id);
  cane.kind = id == 1 ? CaneKind::kTrunk : CaneKind::kCane;
  if (id != 1) cane.parent_id = CaneId(1);
  cane.polyline.points = {a, b};
  cane.polyline.radii = {radius, radius};
  return cane;
}

// The simulator's default rig with `cameras` cameras.
inline RigCalibration Rig(int cameras) {
  sim::RigOptions options;
  options.camera_count = cameras;
  return sim::MakeRig(options).value();
}

// One straight cane (MakeCane id 1, radius 4 mm) from a to b, drawn by SyntheticViews through
// Rig(cameras).
struct OneCaneViews {
  VineModel model;
  RigCalibration rig;
  std::vector<View2D> views;
};
inline OneCaneViews DrawOneCane(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int cameras) {
  OneCaneViews out;
  out.model.canes.push_back(MakeCane(1, a, b, 0.004));
  out.rig = Rig(cameras);
  out.views = SyntheticViews(out.model, out.rig);
  return out;
}

// The farthest a piece's points (PiecePoints, every 2 mm) lie from `truth`.
inline double MaxDistance(const Piece3D& piece, const Polyline3& truth) {
  double worst = 0.0;
  for (const Eigen::Vector3d& p : PiecePoints(piece)) worst = std::max(worst, DistanceToPolyline(p, truth));
  return worst;
}

// The number of segments over all views.
inline size_t SegmentCount(const std::vector<View2D>& views) {
  size_t n = 0;
  for (const View2D& v : views) n += v.segments.size();
  return n;
}

}  // namespace vb::reconstruct
