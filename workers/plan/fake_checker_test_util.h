// SPDX-License-Identifier: Apache-2.0
// A CollisionChecker for tests and benchmarks of the planner: obstacles are balls and spherical
// shells in joint space, checked exactly (motions included, analytically, so no resolution
// enters). Counts one check per IsFree and per MotionSteps-like sample of a motion.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "workers/plan/collision_checker.h"

namespace vb::plan::testing {

// A joint vector written inline: J(0.5, -1) is (0.5, -1, 0, 0, 0, 0).
inline Joints J(double a, double b = 0, double c = 0, double d = 0, double e = 0, double f = 0) {
  Joints q;
  q << a, b, c, d, e, f;
  return q;
}

class JointBallChecker : public CollisionChecker {
 public:
  // Blocked: inner_rad < |q - centre| < outer_rad. A solid ball has inner_rad < 0.
  struct Region {
    Joints centre;
    double outer_rad = 0.0;
    double inner_rad = -1.0;
  };

  void AddBall(const Joints& centre, double radius) { regions_.push_back({centre, radius, -1.0}); }
  // A shell that encloses the ball of radius inner_rad about centre.
  void AddShell(const Joints& centre, double inner_rad, double outer_rad) {
    regions_.push_back({centre, outer_rad, inner_rad});
  }

  bool IsFree(const Joints& q) override {
    ++checks_;
    for (const Region& r : regions_) {
      const double d = (q - r.centre).norm();
      if (d > r.inner_rad && d < r.outer_rad) return false;
    }
    return true;
  }

  void AreFree(std::span<const Joints> qs, std::span<bool> out) override {
    for (size_t i = 0; i < qs.size(); ++i) out[i] = IsFree(qs[i]);
  }

  // Exact: the distance to a centre along the segment covers [closest, farther end].
  bool IsMotionFree(const Joints& a, const Joints& b, double max_step_m) override {
    checks_ += 1 + static_cast<int64_t>(std::ceil((b - a).norm() / std::max(max_step_m, 1e-6)));
    ++motions_;
    for (const Region& r : regions_) {
      const Joints ab = b - a;
      const double len2 = ab.squaredNorm();
      const double t = len2 > 0 ? std::clamp((r.centre - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      const double closest = (a + t * ab - r.centre).norm();
      const double farthest = std::max((a - r.centre).norm(), (b - r.centre).norm());
      if (closest < r.outer_rad && farthest > r.inner_rad) return false;
    }
    return true;
  }

  double Clearance(const Joints& q) override {
    ++checks_;
    double best = 1e9;
    for (const Region& r : regions_) {
      const double d = (q - r.centre).norm();
      double c = d - r.outer_rad;
      if (r.inner_rad >= 0) c = d >= r.outer_rad ? d - r.outer_rad : (d <= r.inner_rad ? r.inner_rad - d : -std::min(d - r.inner_rad, r.outer_rad - d));
      else if (d < r.outer_rad) c = d - r.outer_rad;
      best = std::min(best, c);
    }
    return best;
  }

  int64_t motions() const { return motions_; }

 private:
  std::vector<Region> regions_;
  int64_t motions_ = 0;
};

}  // namespace vb::plan::testing
