// SPDX-License-Identifier: Apache-2.0
// What the arm must not touch at one stop, as primitives in the arm's base frame: canes (one
// capsule per polyline segment), the wood the model left out (VineModel::obstacles, chords like
// canes'), head spheres, wires, posts, and the platform (planes, fixed spheres and fixed capsules
// such as the cameras). Each obstacle carries a safety margin that the
// adaptive-margin step raises.
// Plain value types; thread-compatible.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/geometry.h"
#include "core/ids.h"
#include "core/vine_model.h"
#include "Eigen/Core"
#include "workers/plan/robot_model.h"

namespace vb::plan {

// kLeftOutWood: wood the cameras saw that is in no cane of the model (VineModel::obstacles), as
// chords like a cane's; never the cut cane (IsCaneNear), so no cut motion may touch it.
enum class ObstacleKind { kCane, kHead, kWire, kPost, kPlatform, kLeftOutWood };

// A capsule (a sphere when a == b) in the arm base frame.
struct Obstacle {
  ObstacleKind kind = ObstacleKind::kCane;
  int64_t owner_id = 0;        // cane / wire / post id; 0 for head and platform; for
                               // kLeftOutWood the index into VineModel::obstacles plus 1
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
  // The indices into `obstacles` of the capsules WithoutCaneNear leaves out, ascending.
  std::vector<int> CaneNearIndices(CaneId cane_id, const Eigen::Vector3d& point_in_base,
                                   double radius_m) const;
};

// The rule of WithoutCaneNear and CaneNearIndices, which the safety margins' ignored cane
// (safety_margins.h) shares: `o` is a capsule of cane `cane_id` whose surface comes within
// `radius_m` of `point_in_base` (the distance to its axis, less its true radius).
inline bool IsCaneNear(const Obstacle& o, CaneId cane_id, const Eigen::Vector3d& point_in_base,
                       double radius_m) {
  return o.kind == ObstacleKind::kCane && o.owner_id == cane_id.value &&
         PointSegmentDistance(point_in_base, o.capsule.a, o.capsule.b) - o.capsule.radius <=
             radius_m;
}

// The chords (kCane obstacles, arm base frame, margin options.default_margin_m) of the stub that
// `cut` leaves of its cane when made after the cuts `made` on `model` -- the cane in
// WithoutFallenWood(model, made + {cut}) (fallen_wood.h) -- except those identical to a chord of
// the cane in WithoutFallenWood(model, made): in practice the one chord the cut falls in, whose
// end is now the cut. It may bulge a fraction of a millimetre outside the uncut cane's capsule
// there (the cane may bend away from the uncut chord at the cut, and the stub chord takes its
// thicker end's radius), so a motion free on the uncut vine can touch it. Empty when the cane is
// absent after `made` or falls whole with the cut.
//
// Conservative union: for cuts C, Build(WithoutFallenWood(model, made)) plus StubChords(model,
// made, c) for every c in C contains (identically) every obstacle of
// Build(WithoutFallenWood(model, made + S)) for every subset S of C, made in any order: more cuts
// only make more wood fall, and a cane that stays is cut short at the lowest cut on it -- one of
// `made`, leaving its chords as they were, or some c in S, leaving the chords it leaves alone.
// INVALID_ARGUMENT naming the field for bad options, model or robot, or a non-finite cut point.
absl::StatusOr<std::vector<Obstacle>> StubChords(const VineModel& model, std::span<const Cut> made,
                                                 const Cut& cut, const RobotModel& robot,
                                                 const SceneOptions& options = {});

}  // namespace vb::plan
