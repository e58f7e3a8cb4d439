// SPDX-License-Identifier: Apache-2.0
// What the arm must not touch at one stop, as primitives in the arm's base frame: canes (one
// capsule per polyline segment), head spheres, wires, posts, and the platform (planes and fixed
// spheres). Each obstacle carries a safety margin that the adaptive-margin step raises.
// Plain value types; thread-compatible.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "core/ids.h"
#include "core/vine_model.h"
#include "Eigen/Core"
#include "workers/plan/robot_model.h"

namespace vb::plan {

enum class ObstacleKind { kCane, kHead, kWire, kPost, kPlatform };

// A capsule (a sphere when a == b) in the arm base frame.
struct Obstacle {
  ObstacleKind kind = ObstacleKind::kCane;
  int64_t owner_id = 0;        // cane / wire / post id; 0 for head and platform
  Capsule capsule;             // radius is the true radius
  double margin_m = 0.0;       // inflation used by collision checks (>= 0)
};

// The free side of a plane: n . x <= offset (n unit, arm base frame).
struct HalfSpace {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
  double margin_m = 0.0;
};

struct SceneOptions {
  double cane_segment_m = 0.03;     // canes become chords this long from the base (tip shorter)
  double default_margin_m = 0.0;    // initial margin on every obstacle
  // INVALID_ARGUMENT naming the field.
  absl::Status Validate() const;
};

struct CollisionScene {
  std::vector<Obstacle> obstacles;
  std::vector<HalfSpace> planes;

  // The scene of `model` (validated first) and `platform`, transformed into the arm base frame
  // of `robot`. INVALID_ARGUMENT naming the model element or option on bad input.
  static absl::StatusOr<CollisionScene> Build(const VineModel& model,
                                              const PlatformGeometry& platform,
                                              const RobotModel& robot,
                                              const SceneOptions& options = {});

  // A copy without the capsules of cane `cane_id` that come within `radius_m` of `point_in_base`
  // (the cane the tool is cutting may touch the tool there).
  CollisionScene WithoutCaneNear(CaneId cane_id, const Eigen::Vector3d& point_in_base,
                                 double radius_m) const;
};

}  // namespace vb::plan
