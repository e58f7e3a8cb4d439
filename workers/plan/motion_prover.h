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
//
// Paths already sampled with margins (SetSampledScene, IsSampledPathFree): a path planner checks
// its segments with IsMotionFree at s = 10 mm in a scene with safety margins. If an obstacle's
// margin there exceeds its own by s/2 or more, every configuration on such a segment is within
// s/2 of a sample free of it inflated by that much, so the segment is free of that obstacle
// with its own margin: the planner's check has proven it. The prover then proves the segment
// only against the other obstacles and planes (those the margins leave within s/2 of the arm's
// way: near the cuts, where transits start and end), with the levels above, in a scene of those
// alone. The same proof, on fewer obstacles.
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

  // The scene the caller samples paths in before proving them (e.g. the path planner's, with
  // safety margins). An obstacle (plane) of the prover's scene is left to that sampling when the
  // one at the same index in `sampled` has the same kind, owner and capsule (normal and offset)
  // and a margin at least its own + kCoarseStepM / 2 + kSampledSlackM; the others are proven by
  // IsSampledPathFree. A `sampled` scene with other counts of obstacles or planes leaves nothing
  // to the sampling. Replaces an earlier sampled scene.
  void SetSampledScene(const CollisionScene& sampled);
  // As IsPathFree, for a path each of whose segments the caller has checked free in the sampled
  // scene with CollisionChecker::IsMotionFree at a step <= kCoarseStepM (either direction; the
  // segment's ends may differ from the checked ones by rounding, which kSampledSlackM absorbs):
  // proves it free of the prover's scene, sampling in it only the obstacles the sampled scene
  // does not cover. Without SetSampledScene, IsPathFree.
  bool IsSampledPathFree(std::span<const Joints> path);
  // Obstacles and planes SetSampledScene left to the prover (all of them before it is called).
  int unsampled_obstacles() const;
  int unsampled_planes() const;

  // Configuration checks spent, over every level.
  int64_t checks() const;

  static constexpr double kCoarseStepM = 0.01;
  static constexpr int kLevels = 3;            // 10 mm, 1 mm, 0.1 mm
  static constexpr double kFinalStepM = 2e-5;  // the plain check of what the last level leaves
  // Margin a sampled scene must have beyond own + kCoarseStepM / 2 to cover an obstacle: covers
  // rounding in the samples and path ends (a few nanometres).
  static constexpr double kSampledSlackM = 1e-6;

 private:
  // A scene to prove motions in, and its checkers per level (built at their first use).
  struct Levels {
    CollisionScene scene;
    std::vector<std::unique_ptr<CollisionChecker>> checkers;  // kLevels + 1
  };
  bool PieceFree(Levels& levels, const Joints& a, const Joints& b, int level);
  bool PathFree(Levels& levels, std::span<const Joints> path);
  CollisionChecker& Level(Levels& levels, int level);  // level kLevels: the scene as given

  Factory make_;
  Levels full_;
  // The obstacles and planes a sampled scene does not cover; empty when none was set or it
  // covers none (then IsSampledPathFree uses full_).
  std::unique_ptr<Levels> unsampled_;
  int64_t retired_checks_ = 0;  // checks of replaced unsampled_ levels
};

}  // namespace vb::plan
