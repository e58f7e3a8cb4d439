// SPDX-License-Identifier: Apache-2.0
// The simulated world at one stop, mutable by cuts: a cut severs a cane at a point, and the part
// beyond it (with every cane growing from that part) falls away, so a re-capture shows the cut.
// Not thread-safe; callers serialise access (one arm, one rig).
#pragma once

#include <vector>

#include "absl/status/status.h"
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

  // Severs cane `cane_id` at the point of its axis nearest `point_in_platform`.
  // NOT_FOUND if the cane does not exist (or already fell); INVALID_ARGUMENT if the point is
  // non-finite or farther than `tolerance_m` from the cane's surface.
  absl::StatusOr<CutResult> ApplyCut(CaneId cane_id, const Eigen::Vector3d& point_in_platform,
                                     double tolerance_m = 0.01);

 private:
  Scene scene_;
};

}  // namespace vb::sim
