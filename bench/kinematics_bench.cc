// SPDX-License-Identifier: Apache-2.0
// UR5 forward kinematics and closed-form inverse kinematics (all solutions), per call (issue 5:
// <= 2 us for all IK solutions). Poses come from 1024 random configurations (fixed seed) cycled
// through, so branch prediction does not learn one pose. Run:
//   build/bench/vb_kinematics_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
#include <random>
#include <vector>

#include "benchmark/benchmark.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {
namespace {

std::vector<Joints> RandomConfigurations(int n) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::vector<Joints> qs(n);
  for (Joints& q : qs) {
    for (int i = 0; i < 6; ++i) q[i] = angle(rng);
  }
  return qs;
}

void BM_ForwardKinematics(benchmark::State& state) {
  const std::vector<Joints> qs = RandomConfigurations(1024);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ForwardKinematics(qs[i++ & 1023]));
  }
}
BENCHMARK(BM_ForwardKinematics);

void BM_InverseKinematicsAllSolutions(benchmark::State& state) {
  std::vector<Eigen::Isometry3d> poses;
  for (const Joints& q : RandomConfigurations(1024)) poses.push_back(ForwardKinematics(q));
  const JointLimits limits;
  size_t i = 0;
  int64_t solutions = 0;
  for (auto _ : state) {
    const IkSolutions ik = InverseKinematics(poses[i++ & 1023], limits);
    solutions += ik.count;
    benchmark::DoNotOptimize(ik);
  }
  state.counters["solutions_per_call"] =
      benchmark::Counter(static_cast<double>(solutions), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_InverseKinematicsAllSolutions);

}  // namespace
}  // namespace vb::plan

BENCHMARK_MAIN();
