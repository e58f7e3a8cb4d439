// SPDX-License-Identifier: Apache-2.0
// Cost matrices for tests and benchmarks of the cut order (cut_order.h).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "Eigen/Core"
#include "workers/plan/time_parameterization.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// Move times (MoveTimeS, default limits) between n + 1 random arm configurations (joints in
// [-2, 2] rad, drawn from `seed`), as the planner uses them; node 0 is the start.
inline Eigen::MatrixXd MoveTimeCosts(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<Joints> q(n + 1);
  for (Joints& x : q) {
    for (int i = 0; i < 6; ++i) x[i] = u(rng);
  }
  Eigen::MatrixXd c(n + 1, n + 1);
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) c(i, j) = MoveTimeS(q[i], q[j], JointLimits());
  }
  return c;
}

}  // namespace vb::plan
