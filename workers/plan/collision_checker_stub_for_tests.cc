// SPDX-License-Identifier: Apache-2.0
// TEMPORARY (branch plan-path only): the base-class defaults of CollisionChecker, so that fake
// checkers in tests and benchmarks link before collision_checker.cc lands from branch plan-coll.
// Delete this file (and its mentions in CMakeLists.txt) when merging plan-coll.
#include "workers/plan/collision_checker.h"

#include <cmath>

namespace vb::plan {

void CollisionChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  for (size_t i = 0; i < qs.size(); ++i) out[i] = IsFree(qs[i]);
}

bool CollisionChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  const int steps = MotionSteps(a, b, max_step_m);
  for (int k = 0; k <= steps; ++k) {
    if (!IsFree(a + (b - a) * (static_cast<double>(k) / steps))) return false;
  }
  return true;
}

int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m) {
  const double travel = (b - a).cwiseAbs().maxCoeff() * reach_m * 6.0;
  const int steps = static_cast<int>(std::ceil(travel / max_step_m));
  return steps < 1 ? 1 : steps;
}

}  // namespace vb::plan
