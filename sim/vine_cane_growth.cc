// SPDX-License-Identifier: Apache-2.0
#include "sim/vine_cane_growth.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace vb::sim {
namespace {

constexpr double kPi = std::numbers::pi;
// Correlation length of the random curvature: canes bend over tens of centimetres, not per point.
constexpr double kCurvatureCorrelationM = 0.15;
// Pull of the heading back toward the vine plane (shoot positioning squeezed the canes between the
// foliage wires last summer): elevation damping per metre and restoring gain per metre of offset.
constexpr double kElevationDamping = 4.0;
constexpr double kPlaneRestoring = 30.0;
constexpr double kElevationNoise = 0.8;
constexpr double kMaxElevationRad = 0.7;
// Canes never touch the ground; below kGroundAvoidZ a downward heading is bent toward horizontal.
constexpr double kGroundAvoidZ = 0.3;
constexpr double kMinZ = 0.03;
// Draping: a cane within kDrapeCatchY of a wire's plane when it passes the wire's height may get
// caught and lie along the wire, bending over it with at most kDrapeMaxCurvature.
constexpr double kDrapeCatchY = 0.12;
constexpr double kDrapeMaxCurvature = 10.0;  // rad/m: a 10 cm bend radius
constexpr double kDrapeHeightGain = 6.0;     // rad per metre above the wire
constexpr int kMaxDrapes = 2;

Eigen::Vector3d Heading(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(phi), std::cos(theta) * std::cos(phi)};
}

double TurnToward(double value, double target, double max_step) {
  return value + std::clamp(target - value, -max_step, max_step);
}

struct Drape {
  bool active = false;
  size_t wire = 0;
  double side = 1.0;         // +1 along +x, -1 along -x
  double remaining_m = 0.0;  // still to lie on the wire
  double budget_m = 0.0;     // still to grow in drape mode at most
};

}  // namespace

namespace {

// Wood does not pass through wire: a cane that would overlap a wire is displaced to rest against
// it, away from the wire's axis (upward when it lies exactly on it). The displacement is spread
// along the cane (triangular falloff over kSpreadM) so the cane bends smoothly around the wire
// instead of kinking, and fades to zero at the base, which sits on its parent. The steering in
// GrowCane only aims at a wire; this enforces contact without penetration.
void RestOnWires(const TrellisRow& row, const VineGeneratorOptions& options, Polyline3* line) {
  constexpr double kClearanceM = 0.0003;
  constexpr double kSpreadM = 0.08;
  constexpr double kBaseFadeM = 0.02;
  const size_t n = line->points.size();
  const std::vector<double> arc = line->ArcLengths();
  for (int pass = 0; pass < 8; ++pass) {
    std::vector<Eigen::Vector2d> need(n, Eigen::Vector2d::Zero());  // (dy, dz) per point
    bool any = false;
    for (size_t i = 1; i < n; ++i) {
      const Eigen::Vector3d& q = line->points[i];
      for (const TrellisWire& wire : row.wires) {
        const double min_distance = line->radii[i] + options.wire_radius_m + kClearanceM;
        const Eigen::Vector2d axis(wire.y_m, WireHeightAt(row, wire, q.x(), options));
        const Eigen::Vector2d offset = Eigen::Vector2d(q.y(), q.z()) - axis;
        const double distance = offset.norm();
        if (distance >= min_distance) continue;
        const Eigen::Vector2d dir =
            distance > 1e-9 ? Eigen::Vector2d(offset / distance) : Eigen::Vector2d(0.0, 1.0);
        const Eigen::Vector2d push = (min_distance - distance) * dir;
        if (push.norm() > need[i].norm()) need[i] = push;
        any = true;
      }
    }
    if (!any) return;
    for (size_t i = 1; i < n; ++i) {
      Eigen::Vector2d best = Eigen::Vector2d::Zero();
      for (size_t j = 1; j < n; ++j) {
        const double w = 1.0 - std::abs(arc[i] - arc[j]) / kSpreadM;
        if (w <= 0.0 || need[j].isZero()) continue;
        if (w * need[j].norm() > best.norm()) best = w * need[j];
      }
      const double fade = std::min(1.0, arc[i] / kBaseFadeM);
      // The point that needs the push gets all of it (w = 1 at j = i), fade permitting.
      line->points[i].y() += fade * best.x();
      line->points[i].z() += fade * best.y();
    }
  }
}

}  // namespace

Polyline3 GrowCane(const CaneGrowth& g, const TrellisRow& row,
                   const VineGeneratorOptions& options, VineRng& rng) {
  const double length = std::max(g.length_m, 1e-3);
  const double plane_y = options.vine_plane_y_m;
  const double sigma_curv = g.wander_rad_per_m * std::sqrt(2.0 / kCurvatureCorrelationM);
  // Bark thickness varies a little along the cane (nodes, internodes); zero at both ends so the
  // base and tip radii are exactly as requested.
  const double wobble_amp = rng.Uniform(0.0, 0.04);
  const double wobble_wavelength = rng.Uniform(0.08, 0.25);
  const double wobble_phase = rng.Uniform(0.0, 2.0 * kPi);
  auto radius_at = [&](double s) {
    const double u = std::clamp(s / length, 0.0, 1.0);
    const double taper = 1.0 - (1.0 - g.tip_ratio) * std::pow(u, g.taper_exponent);
    const double wobble =
        1.0 + wobble_amp * std::sin(2.0 * kPi * s / wobble_wavelength + wobble_phase) *
                  std::sin(kPi * u);
    return g.base_radius_m * taper * wobble;
  };

  Polyline3 line;
  Eigen::Vector3d p = g.base;
  double theta = g.heading_rad;
  double phi = g.elevation_rad;
  double curvature = rng.Normal(0.0, g.wander_rad_per_m);
  double s = 0.0;
  line.points.push_back(p);
  line.radii.push_back(radius_at(0.0));

  std::vector<bool> tried(row.wires.size(), false);
  int drapes = 0;
  Drape drape;

  while (s < length - 1e-9) {
    double ds = rng.Uniform(g.step_min_m, g.step_max_m);
    // End exactly at the requested length without a stub or an overlong last step.
    const double left = length - s;
    if (left <= g.step_max_m) {
      ds = left;
    } else if (left - ds < g.step_min_m) {
      ds = 0.5 * left;
    }
    const double r = radius_at(s + ds);

    if (!drape.active) {
      curvature += -curvature / kCurvatureCorrelationM * ds + sigma_curv * std::sqrt(ds) * rng.Normal();
      double rate = curvature + g.arch_rad_per_m + g.droop_rad_per_m * std::sin(theta);
      if (p.z() < kGroundAvoidZ && std::cos(theta) < 0.1) {
        // Bend a falling cane back toward horizontal; the lower, the harder.
        const double side = theta >= 0.0 ? 1.0 : -1.0;
        const double w = (kGroundAvoidZ - p.z()) / kGroundAvoidZ;
        rate += 25.0 * w * (side * 0.4 * kPi - theta);
      }
      theta = std::clamp(theta + rate * ds, -0.92 * kPi, 0.92 * kPi);
      phi += ds * (-kElevationDamping * phi - kPlaneRestoring * (p.y() - plane_y)) +
             kElevationNoise * std::sqrt(ds) * rng.Normal();
      phi = std::clamp(phi, -kMaxElevationRad, kMaxElevationRad);
    } else {
      const TrellisWire& wire = row.wires[drape.wire];
      const double z_target = WireHeightAt(row, wire, p.x(), options) + options.wire_radius_m + r;
      const double tilt = std::clamp(kDrapeHeightGain * (p.z() - z_target), -0.5, 0.8);
      const double theta_target = drape.side * (0.5 * kPi + tilt);
      theta = TurnToward(theta, theta_target, kDrapeMaxCurvature * ds) + 0.02 * rng.Normal();
      const double phi_target = std::clamp(-8.0 * (p.y() - wire.y_m), -0.4, 0.4);
      phi = TurnToward(phi, phi_target, kDrapeMaxCurvature * ds);
      // The drape length counts once the cane has settled onto the wire; the bend onto it comes
      // on top (bounded, in case it never settles).
      if (std::abs(p.z() - z_target) < 0.01) drape.remaining_m -= ds;
      drape.budget_m -= ds;
      if (drape.remaining_m <= 0.0 || drape.budget_m <= 0.0) {
        drape.active = false;
        curvature = 0.0;
      }
    }

    Eigen::Vector3d next = p + ds * Heading(theta, phi);
    next.z() = std::max(next.z(), kMinZ + r);

    if (!drape.active && drapes < kMaxDrapes) {
      for (size_t w = 0; w < row.wires.size(); ++w) {
        if (tried[w]) continue;
        const TrellisWire& wire = row.wires[w];
        const double h = WireHeightAt(row, wire, next.x(), options);
        if ((p.z() - h) * (next.z() - h) > 0.0 || std::abs(next.y() - wire.y_m) > kDrapeCatchY) {
          continue;
        }
        tried[w] = true;
        if (!rng.Bernoulli(g.drape_probability)) continue;
        const double dx = next.x() - p.x();
        drape.active = true;
        drape.wire = w;
        drape.side = std::abs(dx) > 0.2 * ds ? (dx > 0.0 ? 1.0 : -1.0)
                                               : (g.arch_rad_per_m >= 0.0 ? 1.0 : -1.0);
        drape.remaining_m = rng.Uniform(0.15, 0.9);
        drape.budget_m = drape.remaining_m + 0.4;
        ++drapes;
        break;
      }
    }

    p = next;
    s += ds;
    line.points.push_back(p);
    line.radii.push_back(r);
  }
  RestOnWires(row, options, &line);
  // Resting on a wire can stretch a step; subdivide so sampling stays as dense as grown.
  Polyline3 dense;
  for (size_t i = 0; i < line.points.size(); ++i) {
    if (i > 0) {
      const double step = (line.points[i] - line.points[i - 1]).norm();
      const int pieces = static_cast<int>(std::ceil(step / g.step_max_m - 1e-9));
      for (int k = 1; k < pieces; ++k) {
        const double f = static_cast<double>(k) / pieces;
        dense.points.push_back(line.points[i - 1] + f * (line.points[i] - line.points[i - 1]));
        dense.radii.push_back(line.radii[i - 1] + f * (line.radii[i] - line.radii[i - 1]));
      }
    }
    dense.points.push_back(line.points[i]);
    dense.radii.push_back(line.radii[i]);
  }
  // A chord between two pushed points can still cut through the wire; settle once more.
  RestOnWires(row, options, &dense);
  return dense;
}

}  // namespace vb::sim
