// SPDX-License-Identifier: Apache-2.0
// The simulated world at one stop, mutable by cuts: a cut severs a cane at a point, and the part
// beyond it (with every cane growing from that part) falls away, so a re-capture shows the cut.
// Not thread-safe; callers serialise access (one arm, one rig).
#pragma once

#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/ids.h"
#include "Eigen/Core"
#include "sim/scene.h"

namespace vb::sim {

struct CutResult {
  CaneId cane_id;
  double arc_length_m = 0.0;        // where along the cane it was severed
  double distance_m = 0.0;          // distance from the requested point to the cane axis
  std::vector<CaneId> removed;      // canes that fell entirely (descendants beyond the cut)
};

class SimWorld {
 public:
  explicit SimWorld(Scene scene) : scene_(std::move(scene)) {}

  const Scene& scene() const { return scene_; }

  // A cut leaving less than this much of a cane removes the whole cane.
  static constexpr double kMinStubM = kMinCaneStubM;

  // Severs cane `cane_id` at the point of its axis nearest `point_in_platform`.
  // NOT_FOUND if the cane does not exist (or already fell); INVALID_ARGUMENT if the point is
  // non-finite or farther than `tolerance_m` from the cane's surface (or tolerance_m is negative or
  // non-finite). On error the world is unchanged.
  // The cane keeps [0, arc_length_m] (Polyline3::TruncateAt). Every cane whose base lies beyond the
  // cut (its base projects onto this cane's axis past arc_length_m) falls, with all its
  // descendants; canes whose base is on the head (off the trunk axis) hang on the trunk top, and
  // cutting the trunk below its top drops the head too. A cut within kMinStubM of the base drops the
  // whole cane, which is then listed first in CutResult::removed. Only the scene's own vine is
  // cuttable (not the neighbours). The model still passes VineModel::Validate() afterwards.
  absl::StatusOr<CutResult> ApplyCut(CaneId cane_id, const Eigen::Vector3d& point_in_platform,
                                     double tolerance_m = 0.01);

 private:
  Scene scene_;
};

}  // namespace vb::sim
