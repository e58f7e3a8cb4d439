// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/left_out_wood.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {

absl::Status LeftOutWoodOptions::Validate() const {
  if (!std::isfinite(covered_within_m) || covered_within_m < 0) {
    return absl::InvalidArgumentError("left_out_wood.covered_within_m must be finite and >= 0");
  }
  if (!std::isfinite(min_length_m) || min_length_m < 0) {
    return absl::InvalidArgumentError("left_out_wood.min_length_m must be finite and >= 0");
  }
  if (!std::isfinite(sample_step_m) || sample_step_m < 0.001 || sample_step_m > 0.1) {
    return absl::InvalidArgumentError("left_out_wood.sample_step_m must be in [0.001, 0.1] m");
  }
  return absl::OkStatus();
}

namespace {

// A part of the model as a capsule with its bounding box grown by the coverage distance.
struct Solid {
  Eigen::Vector3d a, b, lo, hi;
  double radius;
};

std::vector<Solid> ModelSolids(const VineModel& model, double within) {
  std::vector<Solid> out;
  auto add = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
    const double grow = radius + within;
    out.push_back({a, b, a.cwiseMin(b).array() - grow, a.cwiseMax(b).array() + grow, radius});
  };
  for (const Cane& cane : model.canes) {
    const Polyline3& line = cane.polyline;
    for (size_t k = 0; k + 1 < line.points.size(); ++k) {
      add(line.points[k], line.points[k + 1], std::max(line.radii[k], line.radii[k + 1]));
    }
  }
  for (const Sphere& s : model.head.spheres) add(s.center, s.center, s.radius);
  for (const Wire& w : model.wires) {
    for (size_t k = 0; k + 1 < w.points.size(); ++k) add(w.points[k], w.points[k + 1], w.radius);
  }
  for (const Post& p : model.posts) add(p.base, p.top, p.radius);
  return out;
}

bool Covered(const Eigen::Vector3d& p, const std::vector<Solid>& solids, double within) {
  for (const Solid& s : solids) {
    if ((p.array() < s.lo.array()).any() || (p.array() > s.hi.array()).any()) continue;
    if (PointSegmentDistance(p, s.a, s.b) - s.radius <= within) return true;
  }
  return false;
}

// The piece of `line` between arc lengths s0 < s1 (`arc` its ArcLengths()).
Polyline3 Piece(const Polyline3& line, const std::vector<double>& arc, double s0, double s1) {
  Polyline3 piece;
  piece.points.push_back(line.PointAt(s0, arc));
  piece.radii.push_back(line.RadiusAt(s0, arc));
  for (size_t k = 0; k < arc.size(); ++k) {
    if (arc[k] > s0 && arc[k] < s1) {
      piece.points.push_back(line.points[k]);
      piece.radii.push_back(line.radii[k]);
    }
  }
  piece.points.push_back(line.PointAt(s1, arc));
  piece.radii.push_back(line.RadiusAt(s1, arc));
  return piece;
}

}  // namespace

absl::StatusOr<std::vector<WoodObstacle>> LeftOutWood(const std::vector<Polyline3>& seen,
                                                      const VineModel& model,
                                                      const LeftOutWoodOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  const std::vector<Solid> solids = ModelSolids(model, options.covered_within_m);
  std::vector<WoodObstacle> out;
  for (size_t c = 0; c < seen.size(); ++c) {
    const Polyline3& line = seen[c];
    if (!line.Validate(absl::StrCat("seen[", c, "]")).ok()) continue;
    const std::vector<double> arc = line.ArcLengths();
    const double length = arc.back();
    std::vector<double> at;
    for (int k = 0; k * options.sample_step_m < length; ++k) at.push_back(k * options.sample_step_m);
    at.push_back(length);
    // Maximal runs of samples outside the model.
    size_t k = 0;
    while (k < at.size()) {
      if (Covered(line.PointAt(at[k], arc), solids, options.covered_within_m)) {
        ++k;
        continue;
      }
      const size_t first = k;
      while (k + 1 < at.size() &&
             !Covered(line.PointAt(at[k + 1], arc), solids, options.covered_within_m)) {
        ++k;
      }
      const double s0 = at[first], s1 = at[k];
      ++k;
      if (s1 - s0 < options.min_length_m || s1 <= s0) continue;
      out.push_back(WoodObstacle{Piece(line, arc, s0, s1)});
    }
  }
  return out;
}

}  // namespace vb::reconstruct
