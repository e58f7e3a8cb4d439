// SPDX-License-Identifier: Apache-2.0
// Straight lines through 2D point sets, for the wires and posts of the 2D structure stage
// (structure2d.h): RANSAC (Fischler & Bolles, CACM 1981) for the support of each line, total
// least squares on the inliers, and greedy merging of collinear pieces (a wire split by the canes
// in front of it). Coordinates are whatever the caller uses (structure2d uses normalised,
// undistorted image coordinates, where straight 3D lines stay straight).
// Thread-safe (pure functions).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "Eigen/Core"
#include "Eigen/Geometry"

namespace vb::reconstruct {

// A line with the points supporting it.
struct LinePiece {
  Eigen::Vector3d line = Eigen::Vector3d::Zero();  // l . (x, y, 1) = 0, |(l0, l1)| = 1
  std::vector<int> inliers;                        // indices into the fitted point set
  Eigen::Vector2d begin = Eigen::Vector2d::Zero();  // extreme inliers projected onto the line
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
  double scale = 1.0;  // caller's local units per pixel (to express tolerances in pixels)

  Eigen::Vector2d Direction() const { return Eigen::Vector2d(line.y(), -line.x()); }
  double Distance(const Eigen::Vector2d& p) const { return std::abs(line.dot(p.homogeneous())); }
};

// Total least squares line through points[indices] (the principal axis); zero if < 2 points
// or all coincide.
Eigen::Vector3d FitLineLeastSquares(const std::vector<Eigen::Vector2d>& points,
                                    const std::vector<int>& indices);

// Sets piece->begin/end to the extreme projections of its inliers onto its line.
void UpdateExtent(const std::vector<Eigen::Vector2d>& points, LinePiece* piece);

struct RansacOptions {
  double inlier_distance = 1.0;  // in the points' units
  int min_support = 10;          // lines with fewer inliers are not returned
  int iterations = 64;           // hypotheses per line
  int max_lines = 4;             // lines extracted in turn from one point set
  uint64_t seed = 1;
};

// Sequential RANSAC over points[indices]: the best-supported line, refitted by least squares
// on its inliers (twice), its inliers removed, repeated while a line has min_support inliers.
// Deterministic in options.seed.
std::vector<LinePiece> FitLinesRansac(const std::vector<Eigen::Vector2d>& points,
                                      const std::vector<int>& indices,
                                      const RansacOptions& options);

// Merges pieces that lie on one line: a piece joins a longer one if its ends lie within
// `distance_px` * scale of that line and the directions differ by less than `max_angle_rad`;
// the union is refitted. Longest pieces first; the result is sorted by support, largest first.
std::vector<LinePiece> MergeCollinear(const std::vector<Eigen::Vector2d>& points,
                                      std::vector<LinePiece> pieces, double distance_px,
                                      double max_angle_rad);

}  // namespace vb::reconstruct
