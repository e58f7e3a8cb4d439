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
  if (!std::isfinite(same_wood_max_angle_deg) || same_wood_max_angle_deg < 0 ||
      same_wood_max_angle_deg > 90) {
    return absl::InvalidArgumentError(
        "left_out_wood.same_wood_max_angle_deg must be in [0, 90] degrees");
  }
  if (!std::isfinite(contained_tolerance_m) || contained_tolerance_m < 0) {
    return absl::InvalidArgumentError(
        "left_out_wood.contained_tolerance_m must be finite and >= 0");
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

// A part of the model as a capsule, with its bounding box grown by the most a covered point can
// lie outside it. A cane's capsule covers wood running along it within the coverage distance; the
// others (head spheres, wires, posts) only wood inside them.
struct Solid {
  Eigen::Vector3d a, b, lo, hi;
  double radius;
  bool cane;
};

std::vector<Solid> ModelSolids(const VineModel& model, const LeftOutWoodOptions& options) {
  std::vector<Solid> out;
  auto add = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, bool cane) {
    const double grow = radius + std::max(options.covered_within_m, options.contained_tolerance_m);
    out.push_back({a, b, a.cwiseMin(b).array() - grow, a.cwiseMax(b).array() + grow, radius,
                   cane});
  };
  for (const Cane& cane : model.canes) {
    const Polyline3& line = cane.polyline;
    for (size_t k = 0; k + 1 < line.points.size(); ++k) {
      add(line.points[k], line.points[k + 1], std::max(line.radii[k], line.radii[k + 1]), true);
    }
  }
  for (const Sphere& s : model.head.spheres) add(s.center, s.center, s.radius, false);
  for (const Wire& w : model.wires) {
    for (size_t k = 0; k + 1 < w.points.size(); ++k) {
      add(w.points[k], w.points[k + 1], w.radius, false);
    }
  }
  for (const Post& p : model.posts) add(p.base, p.top, p.radius, false);
  return out;
}

// Whether the seen cane's point `p` (radius `r`, unit direction `t`) is in the model.
bool Covered(const Eigen::Vector3d& p, double r, const Eigen::Vector3d& t,
             const std::vector<Solid>& solids, const LeftOutWoodOptions& options) {
  const double min_cos = std::cos(options.same_wood_max_angle_deg * M_PI / 180.0);
  for (const Solid& s : solids) {
    if ((p.array() < s.lo.array()).any() || (p.array() > s.hi.array()).any()) continue;
    const double d = PointSegmentDistance(p, s.a, s.b);
    if (!s.cane) {
      if (d + r <= s.radius + options.contained_tolerance_m) return true;
      continue;
    }
    if (d - s.radius > options.covered_within_m) continue;
    const Eigen::Vector3d axis = s.b - s.a;
    const double n = axis.norm();
    if (n > 0 && std::abs(t.dot(axis) / n) >= min_cos) return true;
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
  const std::vector<Solid> solids = ModelSolids(model, options);
  std::vector<WoodObstacle> out;
  for (size_t c = 0; c < seen.size(); ++c) {
    const Polyline3& line = seen[c];
    if (!line.Validate(absl::StrCat("seen[", c, "]")).ok()) continue;
    const std::vector<double> arc = line.ArcLengths();
    const double length = arc.back();
    std::vector<double> at;
    for (int k = 0; k * options.sample_step_m < length; ++k) at.push_back(k * options.sample_step_m);
    at.push_back(length);
    const auto covered = [&](double s) {
      return Covered(line.PointAt(s, arc), line.RadiusAt(s, arc), line.TangentAt(s, arc), solids,
                     options);
    };
    // Maximal runs of samples outside the model, grown by one step at each end.
    size_t k = 0;
    while (k < at.size()) {
      if (covered(at[k])) {
        ++k;
        continue;
      }
      const size_t first = k;
      while (k + 1 < at.size() && !covered(at[k + 1])) ++k;
      const double s0 = std::max(0.0, at[first] - options.sample_step_m);
      const double s1 = std::min(length, at[k] + options.sample_step_m);
      ++k;
      if (s1 - s0 < options.min_length_m || s1 <= s0) continue;
      out.push_back(WoodObstacle{Piece(line, arc, s0, s1)});
    }
  }
  return out;
}

}  // namespace vb::reconstruct
