// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/motion_prover.h"

#include <cmath>
#include <utility>
#include <vector>

namespace vb::plan {

namespace {

double StepAt(int level) { return MotionProver::kCoarseStepM * std::pow(0.1, level); }

}  // namespace

MotionProver::MotionProver(CollisionScene scene, Factory make)
    : scene_(std::move(scene)), make_(std::move(make)), levels_(kLevels + 1) {}

CollisionChecker& MotionProver::Level(int level) {
  std::unique_ptr<CollisionChecker>& checker = levels_[level];
  if (!checker) {
    CollisionScene inflated = scene_;
    const double margin = level < kLevels ? 0.5 * StepAt(level) : 0.0;
    for (Obstacle& o : inflated.obstacles) o.margin_m += margin;
    for (HalfSpace& h : inflated.planes) h.margin_m += margin;
    checker = make_(inflated);
  }
  return *checker;
}

int64_t MotionProver::checks() const {
  int64_t n = 0;
  for (const auto& checker : levels_)
    if (checker) n += checker->checks();
  return n;
}

bool MotionProver::PieceFree(const Joints& a, const Joints& b, int level) {
  if (level == kLevels) return Level(kLevels).IsMotionFree(a, b, kFinalStepM);
  CollisionChecker& checker = Level(level);
  // Samples step apart, free of the scene inflated by step / 2: proven. Otherwise the halves, to
  // find the pieces between two samples that fail, which go to the next level. (A failing check
  // usually stops at its ends, which it checks first: the halving costs about twice one pass.)
  if (checker.IsMotionFree(a, b, StepAt(level))) return true;
  if (MotionSteps(a, b, StepAt(level), checker.lever_m()) <= 1)
    return PieceFree(a, b, level + 1);
  const Joints mid = 0.5 * (a + b);
  return PieceFree(a, mid, level) && PieceFree(mid, b, level);
}

bool MotionProver::IsMotionFree(const Joints& a, const Joints& b) {
  if (!a.allFinite() || !b.allFinite()) return false;
  return PieceFree(a, b, 0);
}

bool MotionProver::IsPathFree(std::span<const Joints> path) {
  if (path.size() == 1) return IsMotionFree(path[0], path[0]);
  for (size_t i = 1; i < path.size(); ++i)
    if (!IsMotionFree(path[i - 1], path[i])) return false;
  return true;
}

}  // namespace vb::plan
