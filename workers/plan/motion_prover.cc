// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/motion_prover.h"

#include <cmath>
#include <utility>
#include <vector>

namespace vb::plan {

namespace {

double StepAt(int level) { return MotionProver::kCoarseStepM * std::pow(0.1, level); }

}  // namespace

MotionProver::MotionProver(CollisionScene scene, Factory make) : make_(std::move(make)) {
  full_.scene = std::move(scene);
  full_.checkers.resize(kLevels + 1);
}

void MotionProver::SetSampledScene(const CollisionScene& sampled) {
  if (unsampled_) {
    for (const auto& checker : unsampled_->checkers)
      if (checker) retired_checks_ += checker->checks();
  }
  unsampled_.reset();
  const CollisionScene& own = full_.scene;
  if (sampled.obstacles.size() != own.obstacles.size() ||
      sampled.planes.size() != own.planes.size())
    return;
  const double cover_m = 0.5 * kCoarseStepM + kSampledSlackM;
  auto levels = std::make_unique<Levels>();
  levels->checkers.resize(kLevels + 1);
  for (size_t i = 0; i < own.obstacles.size(); ++i) {
    const Obstacle& o = own.obstacles[i];
    const Obstacle& s = sampled.obstacles[i];
    const bool covered = s.kind == o.kind && s.owner_id == o.owner_id &&
                         s.capsule.a == o.capsule.a && s.capsule.b == o.capsule.b &&
                         s.capsule.radius == o.capsule.radius && s.margin_m >= o.margin_m + cover_m;
    if (!covered) levels->scene.obstacles.push_back(o);
  }
  for (size_t i = 0; i < own.planes.size(); ++i) {
    const HalfSpace& h = own.planes[i];
    const HalfSpace& s = sampled.planes[i];
    const bool covered = s.normal == h.normal && s.offset == h.offset &&
                         s.margin_m >= h.margin_m + cover_m;
    if (!covered) levels->scene.planes.push_back(h);
  }
  if (levels->scene.obstacles.size() == own.obstacles.size() &&
      levels->scene.planes.size() == own.planes.size())
    return;  // covers nothing: the full levels serve
  unsampled_ = std::move(levels);
}

int MotionProver::unsampled_obstacles() const {
  return static_cast<int>((unsampled_ ? unsampled_->scene : full_.scene).obstacles.size());
}

int MotionProver::unsampled_planes() const {
  return static_cast<int>((unsampled_ ? unsampled_->scene : full_.scene).planes.size());
}

CollisionChecker& MotionProver::Level(Levels& levels, int level) {
  std::unique_ptr<CollisionChecker>& checker = levels.checkers[level];
  if (!checker) {
    CollisionScene inflated = levels.scene;
    const double margin = level < kLevels ? 0.5 * StepAt(level) : 0.0;
    for (Obstacle& o : inflated.obstacles) o.margin_m += margin;
    for (HalfSpace& h : inflated.planes) h.margin_m += margin;
    checker = make_(inflated);
  }
  return *checker;
}

int64_t MotionProver::checks() const {
  int64_t n = retired_checks_;
  for (const Levels* levels : {static_cast<const Levels*>(&full_), static_cast<const Levels*>(unsampled_.get())}) {
    if (levels == nullptr) continue;
    for (const auto& checker : levels->checkers)
      if (checker) n += checker->checks();
  }
  return n;
}

bool MotionProver::PieceFree(Levels& levels, const Joints& a, const Joints& b, int level) {
  if (level == kLevels) return Level(levels, kLevels).IsMotionFree(a, b, kFinalStepM);
  CollisionChecker& checker = Level(levels, level);
  // Samples step apart, free of the scene inflated by step / 2: proven. Otherwise the halves, to
  // find the pieces between two samples that fail, which go to the next level. (A failing check
  // usually stops at its ends, which it checks first: the halving costs about twice one pass.)
  if (checker.IsMotionFree(a, b, StepAt(level))) return true;
  if (MotionSteps(a, b, StepAt(level), checker.lever_m()) <= 1)
    return PieceFree(levels, a, b, level + 1);
  const Joints mid = 0.5 * (a + b);
  return PieceFree(levels, a, mid, level) && PieceFree(levels, mid, b, level);
}

bool MotionProver::IsMotionFree(const Joints& a, const Joints& b) {
  if (!a.allFinite() || !b.allFinite()) return false;
  return PieceFree(full_, a, b, 0);
}

bool MotionProver::PathFree(Levels& levels, std::span<const Joints> path) {
  for (const Joints& q : path)
    if (!q.allFinite()) return false;
  if (path.size() == 1) return PieceFree(levels, path[0], path[0], 0);
  for (size_t i = 1; i < path.size(); ++i)
    if (!PieceFree(levels, path[i - 1], path[i], 0)) return false;
  return true;
}

bool MotionProver::IsPathFree(std::span<const Joints> path) { return PathFree(full_, path); }

bool MotionProver::IsSampledPathFree(std::span<const Joints> path) {
  return PathFree(unsampled_ ? *unsampled_ : full_, path);
}

}  // namespace vb::plan
