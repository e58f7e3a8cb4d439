// SPDX-License-Identifier: Apache-2.0
// Test support: small hand-made vine models. Header-only; tests only.
#pragma once

#include <optional>
#include <utility>

#include "Eigen/Core"
#include "core/vine_model.h"

namespace vb {

// A cane of the given id, parent (none: a root), kind and polyline.
inline Cane CaneOf(int id, std::optional<int> parent, CaneKind kind, Polyline3 line) {
  Cane c;
  c.id = CaneId(id);
  if (parent) c.parent_id = CaneId(*parent);
  c.kind = kind;
  c.polyline = std::move(line);
  return c;
}

// A straight cane from `a` to `b` (platform frame, m) of constant `radius_m`.
inline Cane StraightCane(int id, std::optional<int> parent, CaneKind kind, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b, double radius_m = 0.005) {
  Cane c;
  c.id = CaneId(id);
  if (parent) c.parent_id = CaneId(*parent);
  c.kind = kind;
  c.polyline.points = {a, b};
  c.polyline.radii = {radius_m, radius_m};
  return c;
}

// One straight trunk, 8 mm thick, across the middle of the default rig's view (sim/rig.h).
inline VineModel OneCaneAcrossTheView() {
  VineModel model;
  model.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {-0.1, 0.8, 0.9},
                                     {0.2, 0.8, 1.0}, 0.004));
  return model;
}

}  // namespace vb
