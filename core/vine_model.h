// SPDX-License-Identifier: Apache-2.0
// The vine model: canes as 3D polylines with thickness, the head, and the trellis, all in the
// platform frame (ARCHITECTURE.md "Frames and units"; JSON format vinebot.vine_model.v1).
// Plain value types; thread-compatible.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "core/ids.h"

namespace vb {

enum class CaneKind { kTrunk, kCane, kSpur };

std::string_view CaneKindName(CaneKind kind);
// INVALID_ARGUMENT for anything but "trunk", "cane", "spur".
absl::StatusOr<CaneKind> ParseCaneKind(std::string_view name);

struct Cane {
  CaneId id;
  std::optional<CaneId> parent_id;  // nullopt for the trunk; canes from the head name the trunk
  CaneKind kind = CaneKind::kCane;
  Polyline3 polyline;               // base (where it grows from its parent) to tip
};

// The head: the gnarled knot at the top of the trunk, as a union of spheres.
struct HeadModel {
  std::vector<Sphere> spheres;
};

struct Wire {
  WireId id;
  std::vector<Eigen::Vector3d> points;  // >= 2, along the wire
  double radius = 0.0015;               // metres
};

struct Post {
  PostId id;
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  Eigen::Vector3d top = Eigen::Vector3d::Zero();
  double radius = 0.04;  // metres
};

// Wood the cameras saw that is in no cane of the model: canes the reconstruction left out (a
// neighbour's canes, canes it could not connect to the vine); also the trunk below the images,
// which no camera saw and the reconstruction guesses (workers/reconstruct/cane_fit.h). Not a
// cane: phenomics, decisions and the accuracy metrics never see it; the planner avoids it as it
// avoids canes, and cuts none.
struct WoodObstacle {
  Polyline3 polyline;  // >= 2 points, one radius per point
};

// A cut closer than this to a cane's base removes the whole cane (the simulator's world and the
// planner's view of the vine after cuts share the rule).
inline constexpr double kMinCaneStubM = 0.001;

struct VineModel {
  std::vector<Cane> canes;
  HeadModel head;
  std::vector<Wire> wires;
  std::vector<Post> posts;
  std::vector<WoodObstacle> obstacles;  // empty in ground truth and in older files

  // Checks the model is well formed: unique ids, every parent exists, no parent cycles, at most
  // one trunk and only the trunk without a parent, finite geometry, one radius per point (canes
  // and obstacles alike).
  // INVALID_ARGUMENT naming the offending element (e.g. "canes[4] (id 9): parent_id 12 unknown").
  absl::Status Validate() const;

  // Index into `canes` of the cane with this id, or nullopt.
  std::optional<size_t> IndexOf(CaneId id) const;
  // Ids of canes whose parent is `id`.
  std::vector<CaneId> ChildrenOf(CaneId id) const;
  // All canes descending from `id` (children, grandchildren, ...), not including `id`.
  std::vector<CaneId> DescendantsOf(CaneId id) const;
};

}  // namespace vb
