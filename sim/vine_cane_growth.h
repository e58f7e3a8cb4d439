// SPDX-License-Identifier: Apache-2.0
// Grows one cane as a smooth 3D curve: a heading integrated along the arc length with random,
// smoothly varying curvature, a gravity droop that bends long canes over, a sideways arch along the
// row, a pull back toward the vine plane, and draping along trellis wires that the cane meets.
// Structure of dormant canes (lengths, diameters, forking, canes lying along the wires) follows
// Botterill et al., "A Robot System for Pruning Grape Vines", J. Field Robotics 2017, Sec. 3-4.
// Thread-safe (pure functions of their arguments and the given generator).
#pragma once

#include "core/geometry.h"
#include "Eigen/Core"
#include "sim/trellis.h"
#include "sim/vine_generator.h"
#include "sim/vine_random.h"

namespace vb::sim {

struct CaneGrowth {
  Eigen::Vector3d base = Eigen::Vector3d::Zero();  // first point, row coordinates
  // Initial heading: angle from +z toward +x in the x-z plane (0 = up, +pi/2 = along +x), and the
  // elevation out of that plane toward +y.
  double heading_rad = 0.0;
  double elevation_rad = 0.0;
  double length_m = 0.5;
  double base_radius_m = 0.004;
  double tip_ratio = 0.5;          // tip radius / base radius
  double taper_exponent = 1.0;     // r(s) = r0 * (1 - (1 - tip_ratio) * (s/L)^taper_exponent)
  double arch_rad_per_m = 0.0;     // signed constant turn rate (the sideways arch along the row)
  double droop_rad_per_m = 1.0;    // gravity: turn rate toward down, times sin(heading)
  double wander_rad_per_m = 1.5;   // stationary sd of the random curvature
  double drape_probability = 0.4;  // chance of draping along a wire the cane meets
  double step_min_m = 0.02;        // point spacing range
  double step_max_m = 0.03;
};

// Grows the cane described by `growth` among the wires of `row`; the plane pull is toward
// options.vine_plane_y_m. Returns a polyline of length growth.length_m (up to rounding), base
// first, with >= 2 points, a finite radius > 0 at each point, every point above the ground.
Polyline3 GrowCane(const CaneGrowth& growth, const TrellisRow& row,
                   const VineGeneratorOptions& options, VineRng& rng);

}  // namespace vb::sim
