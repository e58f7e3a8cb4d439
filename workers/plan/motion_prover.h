// SPDX-License-Identifier: Apache-2.0
// A proof that straight joint-space motions are collision-free, not a sampled check.
// CollisionChecker::IsMotionFree checks configurations max_step_m of arm travel apart, so a motion
// it passes may cross an obstacle between two of them (on tuning seed 1129, a transit checked at
// 10 mm went 0.1 mm into a cane, which the bench's 1 mm re-check found, trajectory_check.h).
//
// The proof: if no arm point moves more than s between two configurations (MotionSteps' bound
// from the lever arms), every point on the segment between them is within s/2 of where it is at
// one end; so if both ends are free with every obstacle and plane inflated by s/2, the segment
// touches nothing. Segments are sampled at s = 10 mm against the scene inflated by 5 mm; a piece
// between two samples that fails (found by halving) is sampled again at s / 10 against the scene
// inflated by s / 20, down to 0.1 mm (0.05 mm inflation); a piece that fails there is checked
// plainly at 0.02 mm (a sampled check, only within 0.05 mm of contact). Self-collision is not inflated: it is checked
// as sampled. Thread-compatible (one prover per thread).
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

class MotionProver {
 public:
  using Factory = std::function<std::unique_ptr<CollisionChecker>(const CollisionScene&)>;
  // Proves motions free of `scene` (its margins included). `make` builds a checker of a scene
  // (the inflated copies are built at their first use).
  MotionProver(CollisionScene scene, Factory make);

  // True if every configuration on the straight joint segments between consecutive
  // configurations of `path` is free (true for fewer than 2 when the one there is free).
  bool IsPathFree(std::span<const Joints> path);
  bool IsMotionFree(const Joints& a, const Joints& b);

  // Configuration checks spent, over every level.
  int64_t checks() const;

  static constexpr double kCoarseStepM = 0.01;
  static constexpr int kLevels = 3;            // 10 mm, 1 mm, 0.1 mm
  static constexpr double kFinalStepM = 2e-5;  // the plain check of what the last level leaves

 private:
  bool PieceFree(const Joints& a, const Joints& b, int level);
  CollisionChecker& Level(int level);  // level kLevels: the scene as given

  CollisionScene scene_;
  Factory make_;
  std::vector<std::unique_ptr<CollisionChecker>> levels_;  // kLevels + 1
};

}  // namespace vb::plan
