// SPDX-License-Identifier: Apache-2.0
// What correspondence (correspondence.h) hands to 3D assembly (cane_assembly.h): pieces of cane
// reconstructed in 3D from matched 2D segments, and the working volume every reconstructed
// structure must lie in. Plain value types.
#pragma once

#include "Eigen/Core"
#include "Eigen/Geometry"
#include "core/geometry.h"

namespace vb::reconstruct {

// The region of the platform frame (ARCHITECTURE.md) where the vine being pruned can be: the
// arm's working cuboid. Structure reconstructed outside it is rejected. The default is the
// rig's view of one vine stop: 1.1 m either side of the rig centre along the row, 0.45-1.2 m
// across it (the vine plane is ~0.8 m away, the backdrop at 1.25 m), ground to 2.1 m.
struct WorkingVolume {
  Eigen::AlignedBox3d box{Eigen::Vector3d(-1.1, 0.45, -0.05), Eigen::Vector3d(1.1, 1.2, 2.1)};

  bool Contains(const Eigen::Vector3d& p) const { return box.contains(p); }

  // More than half of the line's points lie outside: a reconstructed cane that is rejected.
  bool MostlyOutside(const Polyline3& line) const {
    size_t outside = 0;
    for (const Eigen::Vector3d& p : line.points) outside += !Contains(p);
    return outside * 2 > line.points.size();
  }
};

// A piece of cane (or trunk) in 3D, from one match of 2D segments across two views, checked in
// the others.
struct Piece3D {
  Polyline3 polyline;        // 3D points (ordered along segment_a) with radii from 2D widths
  double probability = 0.0;  // marginal probability that the match is right (Gibbs sampling)
  int view_a = -1;           // the two matched views and segments (indices into the views and
  int segment_a = -1;        // their View2D::segments)
  int view_b = -1;
  int segment_b = -1;
  double support = 0.0;      // fraction of the piece's points that project onto the foreground
                             // of every view in which they are inside the image
};

}  // namespace vb::reconstruct
