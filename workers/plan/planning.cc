// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/planning.h"

#include <algorithm>
#include <utility>

namespace vb::plan {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

void Planning::UsePassScenes(const CollisionScene& plain, const CollisionScene& inflated) {
  planner.reset();
  checker = MakeChecker(options.checker, robot, inflated);
  planner = std::make_unique<PathPlanner>(*checker, robot.limits, options.path);
  fine_planner.reset();
  plain_planner.reset();
  plain_checker.reset();
  prover = std::make_shared<MotionProver>(plain, [this](const CollisionScene& s) {
    return MakeChecker(options.checker, robot, s);
  });
  // The planner samples its paths in the inflated scene: their proof samples only what the
  // margins leave close (MotionProver::SetSampledScene). Not with FCL meshes: their facets lie
  // inside the surface by a tolerance that grows with the inflated radius, so the planner's
  // samples prove less than the covering margin assumes.
  if (options.path.max_step_m <= MotionProver::kCoarseStepM &&
      options.checker != CheckerKind::kFclMesh) {
    prover->SetSampledScene(inflated);
  }
  plain_scene = plain;
}

std::optional<Planning::Reached> Planning::Path(std::vector<Joints> goals, CutId to) {
  if (!plain_checker) plain_checker = MakeChecker(options.checker, robot, *plain_scene);
  const bool home = to.value == 0;  // the only way home: no smaller bound for elbow flips
  ProvenPath path{planner->PlanToAny(At(), goals, deadline, home)};
  Prove(path, /*sampled=*/true);
  Record(path, to, goals, false);
  std::shared_ptr<CollisionChecker> used = checker;
  // Start in collision: a cut of an earlier pass, whose stroke this pass's margins did not
  // protect (the way home after a cut is given up); it is free without margins.
  if ((path.outcome == PathOutcome::kNoPathWithinDeadline ||
       path.outcome == PathOutcome::kStartInCollision) &&
      options.margin_fallback &&
      options.margins.max_margin_m > 0 && !deadline.Expired()) {
    if (!plain_planner)
      plain_planner = std::make_unique<PathPlanner>(*plain_checker, robot.limits, options.path);
    path = ProvenPath{plain_planner->PlanToAny(At(), goals, deadline, home)};
    Prove(path);
    Record(path, to, goals, true);
    used = plain_checker;
  }
  if (path.unproven && !deadline.Expired()) {
    if (!fine_planner) {
      PathOptions fine = options.path;
      fine.max_step_m = std::min(fine.max_step_m, kFineStepM);
      fine.tree_max_step_m = std::min(fine.tree_max_step_m, 3 * kFineStepM);
      fine_planner = std::make_unique<PathPlanner>(*plain_checker, robot.limits, fine);
    }
    path = ProvenPath{fine_planner->PlanToAny(At(), goals, deadline, home)};
    Prove(path);
    Record(path, to, goals, true);
    used = plain_checker;
  }
  if (path.outcome != PathOutcome::kSolved) return std::nullopt;
  return Reached{std::move(path.waypoints), path.goal_index, std::move(used), prover};
}

void Planning::Prove(ProvenPath& path, bool sampled) {
  if (path.outcome != PathOutcome::kSolved) return;
  const auto start = std::chrono::steady_clock::now();
  const int64_t checks = prover->checks();
  const bool proven = sampled ? prover->IsSampledPathFree(path.waypoints)
                              : prover->IsPathFree(path.waypoints);
  path.planning_s += Seconds(start);
  path.checks += prover->checks() - checks;
  if (proven) return;
  path.unproven = true;
  path.outcome = PathOutcome::kNoPathWithinDeadline;
  path.message = "the path found is not proven free of the vine";
  ++result.stats.unproven_paths;
}

void Planning::Record(const ProvenPath& path, CutId to, const std::vector<Joints>& goals, bool plain) {
  PathRecord record{to, path.outcome, path.planning_s, path.checks, path.direct, plain, At(),
                    goals[std::max(path.goal_index, 0)], goals};
  record.unproven = path.unproven;
  record.walled_in = path.walled_in;
  record.repeated_failure = path.repeated_failure;
  record.flip_bound = path.flip_bound;
  result.stats.paths.push_back(std::move(record));
}

}  // namespace vb::plan
