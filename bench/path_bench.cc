// SPDX-License-Identifier: Apache-2.0
// Paths between cuts, their timing and the order of the cuts (issue 5: median planning per path
// <= 1 ms; whole vine <= 50 ms).
//  - BM_HeldKarp/n, BM_Heuristic/n: ordering n cuts on move-time costs between random
//    configurations (what the planner feeds OrderCuts).
//  - BM_PlanPathFake: PathPlanner (one context reused) on a joint-space fake checker of random
//    balls, 200 random free start/goal pairs per iteration; counters give the median and p95 per
//    path (and over the paths that needed RRT-Connect), that fraction and the success rate. The fake's checks are
//    nearly free, so this measures the planner's own cost (OMPL included), not collision checking.
//  - BM_PlanPathOneShot / BM_PlanPathReused: one query needing RRT-Connect, with and without the
//    OMPL setup (PlanPath vs PathPlanner::Plan).
// Run (JSON: the console printer of Debian's Google Benchmark garbles counters below 1):
//   build/bench/vb_path_bench --benchmark_format=json
#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "benchmark/benchmark.h"
#include "workers/plan/cut_order.h"
#include "workers/plan/fake_checker_test_util.h"
#include "workers/plan/path_planner.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

using Clock = std::chrono::steady_clock;

Eigen::MatrixXd MoveTimeCosts(int n, uint32_t seed) {
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

void BM_HeldKarp(benchmark::State& state) {
  const Eigen::MatrixXd c = MoveTimeCosts(static_cast<int>(state.range(0)), 1100);
  for (auto _ : state) benchmark::DoNotOptimize(HeldKarpOrder(c).cost);
}
BENCHMARK(BM_HeldKarp)->Arg(8)->Arg(12)->Arg(15)->Unit(benchmark::kMicrosecond);

void BM_Heuristic(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd c = MoveTimeCosts(n, 1101);
  for (auto _ : state) benchmark::DoNotOptimize(HeuristicOrder(c).cost);
  const double heuristic = HeuristicOrder(c).cost;
  if (n <= kMaxExactCuts) state.counters["gap_to_exact"] = heuristic / HeldKarpOrder(c).cost - 1.0;
  state.counters["nn_excess"] = NearestNeighbourOrder(c).cost / heuristic - 1.0;
}
BENCHMARK(BM_Heuristic)->Arg(8)->Arg(15)->Arg(30)->Unit(benchmark::kMicrosecond);

struct FakeWorld {
  testing::JointBallChecker checker;
  std::vector<std::pair<Joints, Joints>> queries;
};

// 60 balls of radius 1.5 rad in [-pi, pi]^6 and 200 free pairs in the same box (about 40% of
// the straight segments between them are blocked).
FakeWorld MakeFakeWorld(uint32_t seed) {
  FakeWorld w;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  auto random_q = [&] {
    Joints q;
    for (int i = 0; i < 6; ++i) q[i] = u(rng);
    return q;
  };
  for (int k = 0; k < 200; ++k) w.checker.AddBall(random_q(), 1.6);
  while (w.queries.size() < 200) {
    const Joints a = random_q(), b = random_q();
    if (w.checker.IsFree(a) && w.checker.IsFree(b)) w.queries.push_back({a, b});
  }
  return w;
}

void BM_PlanPathFake(benchmark::State& state) {
  FakeWorld world = MakeFakeWorld(1200);
  PathOptions options;
  PathPlanner planner(world.checker, JointLimits(), options);
  std::vector<double> times, rrt_times;
  int solved = 0, rrt = 0, total = 0;
  int64_t checks = 0;
  for (auto _ : state) {
    for (const auto& [a, b] : world.queries) {
      const PathResult r = planner.Plan(a, b, Deadline::In(1.0));
      times.push_back(r.planning_s);
      solved += r.outcome == PathOutcome::kSolved;
      rrt += !r.direct;
      if (!r.direct) rrt_times.push_back(r.planning_s);
      checks += r.checks;
      ++total;
    }
  }
  std::sort(times.begin(), times.end());
  state.counters["median_us"] = 1e6 * times[times.size() / 2];
  state.counters["p95_us"] = 1e6 * times[times.size() * 95 / 100];
  std::sort(rrt_times.begin(), rrt_times.end());
  if (!rrt_times.empty()) state.counters["rrt_median_us"] = 1e6 * rrt_times[rrt_times.size() / 2];
  state.counters["rrt_fraction"] = double(rrt) / total;
  state.counters["success_rate"] = double(solved) / total;
  state.counters["checks_per_path"] = double(checks) / total;
}
BENCHMARK(BM_PlanPathFake)->Unit(benchmark::kMillisecond);

// A query that needs RRT-Connect: through a ball at the origin.
void BM_PlanPathOneShot(benchmark::State& state) {
  testing::JointBallChecker checker;
  checker.AddBall(Joints::Zero(), 1.0);
  Joints a = Joints::Zero(), b = Joints::Zero();
  a[0] = -2, b[0] = 2;
  for (auto _ : state) {
    benchmark::DoNotOptimize(PlanPath(checker, JointLimits(), a, b, PathOptions(), Deadline::In(1.0)));
  }
}
BENCHMARK(BM_PlanPathOneShot)->Unit(benchmark::kMicrosecond);

void BM_PlanPathReused(benchmark::State& state) {
  testing::JointBallChecker checker;
  checker.AddBall(Joints::Zero(), 1.0);
  Joints a = Joints::Zero(), b = Joints::Zero();
  a[0] = -2, b[0] = 2;
  PathPlanner planner(checker, JointLimits(), PathOptions());
  for (auto _ : state) benchmark::DoNotOptimize(planner.Plan(a, b, Deadline::In(1.0)));
}
BENCHMARK(BM_PlanPathReused)->Unit(benchmark::kMicrosecond);

// OMPL setup alone (a PathPlanner built and destroyed, no query).
void BM_PlannerSetup(benchmark::State& state) {
  testing::JointBallChecker checker;
  for (auto _ : state) {
    PathPlanner planner(checker, JointLimits(), PathOptions());
    benchmark::DoNotOptimize(&planner);
  }
}
BENCHMARK(BM_PlannerSetup)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace vb::plan

BENCHMARK_MAIN();
