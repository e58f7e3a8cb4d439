// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/lines2d.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>

#include "Eigen/Eigenvalues"

namespace vb::reconstruct {

Eigen::Vector3d FitLineLeastSquares(const std::vector<Eigen::Vector2d>& points,
                                    const std::vector<int>& indices) {
  if (indices.size() < 2) return Eigen::Vector3d::Zero();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : indices) mean += points[i];
  mean /= static_cast<double>(indices.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (int i : indices) {
    const Eigen::Vector2d d = points[i] - mean;
    scatter += d * d.transpose();
  }
  if (scatter.trace() <= 0.0) return Eigen::Vector3d::Zero();
  // The normal is the eigenvector of the smallest eigenvalue (ascending order).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
  const Eigen::Vector2d normal = solver.eigenvectors().col(0).normalized();
  return Eigen::Vector3d(normal.x(), normal.y(), -normal.dot(mean));
}

void UpdateExtent(const std::vector<Eigen::Vector2d>& points, LinePiece* piece) {
  const Eigen::Vector2d direction = piece->Direction();
  const Eigen::Vector2d foot = -piece->line.z() * piece->line.head<2>();  // closest to origin
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (int i : piece->inliers) {
    const double t = direction.dot(points[i] - foot);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  if (piece->inliers.empty()) lo = hi = 0.0;
  piece->begin = foot + lo * direction;
  piece->end = foot + hi * direction;
}

std::vector<LinePiece> FitLinesRansac(const std::vector<Eigen::Vector2d>& points,
                                      const std::vector<int>& indices,
                                      const RansacOptions& options) {
  std::vector<LinePiece> lines;
  std::vector<int> remaining = indices;
  std::sort(remaining.begin(), remaining.end());
  std::mt19937_64 random(options.seed);
  const auto inliers_of = [&](const Eigen::Vector3d& line, const std::vector<int>& set) {
    std::vector<int> in;
    for (int i : set) {
      if (std::abs(line.dot(points[i].homogeneous())) <= options.inlier_distance) in.push_back(i);
    }
    return in;
  };
  while (static_cast<int>(lines.size()) < options.max_lines &&
         static_cast<int>(remaining.size()) >= std::max(2, options.min_support)) {
    const size_t n = remaining.size();
    Eigen::Vector3d best = Eigen::Vector3d::Zero();
    int best_count = 0;
    for (int it = 0; it < options.iterations; ++it) {
      const Eigen::Vector2d& a = points[remaining[random() % n]];
      const Eigen::Vector2d& b = points[remaining[random() % n]];
      Eigen::Vector3d line = a.homogeneous().cross(b.homogeneous());
      const double norm = line.head<2>().norm();
      if (!(norm > 0.0)) continue;
      line /= norm;
      int count = 0;
      for (int i : remaining) {
        count += std::abs(line.dot(points[i].homogeneous())) <= options.inlier_distance;
      }
      if (count > best_count) {
        best_count = count;
        best = line;
      }
    }
    if (best_count < options.min_support) break;
    LinePiece piece;
    piece.line = best;
    for (int refit = 0; refit < 2; ++refit) {
      piece.inliers = inliers_of(piece.line, remaining);
      const Eigen::Vector3d fitted = FitLineLeastSquares(points, piece.inliers);
      if (fitted.head<2>().norm() > 0.0) piece.line = fitted;
    }
    piece.inliers = inliers_of(piece.line, remaining);
    if (static_cast<int>(piece.inliers.size()) < options.min_support) break;
    std::vector<int> rest;
    rest.reserve(remaining.size() - piece.inliers.size());
    std::set_difference(remaining.begin(), remaining.end(), piece.inliers.begin(),
                        piece.inliers.end(), std::back_inserter(rest));
    if (rest.size() == remaining.size()) break;
    remaining = std::move(rest);
    UpdateExtent(points, &piece);
    lines.push_back(std::move(piece));
  }
  return lines;
}

std::vector<LinePiece> MergeCollinear(const std::vector<Eigen::Vector2d>& points,
                                      std::vector<LinePiece> pieces, double distance_px,
                                      double max_angle_rad) {
  const auto length = [](const LinePiece& p) { return (p.end - p.begin).norm(); };
  std::sort(pieces.begin(), pieces.end(),
            [&](const LinePiece& a, const LinePiece& b) { return length(a) > length(b); });
  std::vector<LinePiece> merged;
  const double cos_max = std::cos(max_angle_rad);
  for (LinePiece& piece : pieces) {
    bool joined = false;
    for (LinePiece& line : merged) {
      const double tolerance = distance_px * std::max(line.scale, piece.scale);
      if (std::abs(line.Direction().dot(piece.Direction())) < cos_max) continue;
      if (line.Distance(piece.begin) > tolerance || line.Distance(piece.end) > tolerance) continue;
      line.inliers.insert(line.inliers.end(), piece.inliers.begin(), piece.inliers.end());
      std::sort(line.inliers.begin(), line.inliers.end());
      const Eigen::Vector3d fitted = FitLineLeastSquares(points, line.inliers);
      if (fitted.head<2>().norm() > 0.0) line.line = fitted;
      UpdateExtent(points, &line);
      line.scale = std::max(line.scale, piece.scale);
      joined = true;
      break;
    }
    if (!joined) merged.push_back(std::move(piece));
  }
  std::sort(merged.begin(), merged.end(), [](const LinePiece& a, const LinePiece& b) {
    return a.inliers.size() > b.inliers.size();
  });
  return merged;
}

}  // namespace vb::reconstruct
