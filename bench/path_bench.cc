// SPDX-License-Identifier: Apache-2.0
// Paths between cuts, their timing and the order of the cuts (issue 5: median planning per path
// <= 1 ms; whole vine <= 50 ms).
//  - BM_HeldKarp/n, BM_Heuristic/n: ordering n cuts on move-time costs between random
//    configurations (what the planner feeds OrderCuts).
//  - BM_PlanPathFake: PathPlanner (one context reused) on a joint-space fake checker of random
//    balls, 200 random free start/goal pairs per iteration; counters give the median and p95 per
//    path (and over the paths that needed RRT-Connect), that fraction and the success rate. The fake's checks are
//    nearly free, so this measures the planner's own cost (OMPL included), not collision checking.
//  - BM_PlanPathScene: the primitive checker on simulated vine scenes (sim::GenerateScene, tuning
//    seeds 1100-1104, mill-end tool, no margin), 40 pairs of random collision-free configurations
//    per vine (within +-1.2 rad of a working pose, or anywhere in [-pi, pi]; the UR5's limits,
//    elbow +-pi); same counters, plus dense_failures: returned
//    segments that fail a re-check at 2 mm (the planner checks at 10 mm).
//  - BM_RepeatedHopelessQueries/0, /1: 20 queries from nearby starts to one walled-in goal on the
//    fake checker, without and with PathOptions::remember_failures (refused_fraction).
//  - BM_WalledInGoal/0, /100: one query to a walled-in goal on the fake checker, without and with
//    PathOptions::walled_in_after_states (walled_in_fraction).
//  - BM_PlanPathOneShot / BM_PlanPathReused: one query needing RRT-Connect, with and without the
//    OMPL setup (PlanPath vs PathPlanner::Plan).
// Run (JSON: the console printer of Debian's Google Benchmark garbles counters below 1):
//   build/bench/vb_path_bench --benchmark_format=json
#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "benchmark/benchmark.h"
#include "sim/vine_generator.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/cut_order.h"
#include "workers/plan/cut_order_test_util.h"
#include "workers/plan/fake_checker_test_util.h"
#include "workers/plan/path_planner.h"
#include "workers/plan/simple_tool_test_util.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

using Clock = std::chrono::steady_clock;

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

// The path queries of one benchmark: times, outcomes and checks, and their counters.
struct PathTally {
  std::vector<double> times, rrt_times;
  int solved = 0, rrt = 0, total = 0;
  int64_t checks = 0;

  void Add(const PathResult& r) {
    times.push_back(r.planning_s);
    solved += r.outcome == PathOutcome::kSolved;
    rrt += !r.direct;
    if (!r.direct) rrt_times.push_back(r.planning_s);
    checks += r.checks;
    ++total;
  }

  void Report(benchmark::State& state) {
    std::sort(times.begin(), times.end());
    std::sort(rrt_times.begin(), rrt_times.end());
    state.counters["median_us"] = 1e6 * times[times.size() / 2];
    state.counters["p95_us"] = 1e6 * times[times.size() * 95 / 100];
    if (!rrt_times.empty()) state.counters["rrt_median_us"] = 1e6 * rrt_times[rrt_times.size() / 2];
    state.counters["rrt_fraction"] = double(rrt) / total;
    state.counters["success_rate"] = double(solved) / total;
    state.counters["checks_per_path"] = double(checks) / total;
  }
};

void BM_PlanPathFake(benchmark::State& state) {
  FakeWorld world = MakeFakeWorld(1200);
  PathOptions options;
  PathPlanner planner(world.checker, JointLimits(), options);
  PathTally tally;
  for (auto _ : state) {
    for (const auto& [a, b] : world.queries) tally.Add(planner.Plan(a, b, Deadline::In(1.0)));
  }
  tally.Report(state);
}
BENCHMARK(BM_PlanPathFake)->Unit(benchmark::kMillisecond);

struct SceneWorld {
  std::unique_ptr<CollisionChecker> checker;
  std::vector<std::pair<Joints, Joints>> queries;
};

// spread_rad > 0: joints uniform within +-spread_rad of a working pose in front of the vine
// (closer to the travel between cuts); 0: uniform in [-pi, pi] (adversarial: many pairs lie in
// different components of the free space and are unsolvable).
std::vector<SceneWorld> MakeSceneWorlds(double spread_rad) {
  std::vector<SceneWorld> worlds;
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  for (uint64_t seed = 1100; seed < 1105; ++seed) {
    sim::VineGeneratorOptions options;
    options.neighbours = false;
    auto sim_scene = sim::GenerateScene(seed, 0, options);
    if (!sim_scene.ok()) continue;
    auto scene = CollisionScene::Build(sim_scene->vine, DefaultPlatform(), robot);
    if (!scene.ok()) continue;
    SceneWorld w;
    w.checker = MakePrimitiveChecker(robot, *scene);
    std::mt19937 rng(static_cast<uint32_t>(seed));
    const double spread = spread_rad > 0 ? spread_rad : M_PI;
    std::uniform_real_distribution<double> u(-spread, spread);
    Joints centre = Joints::Zero();
    if (spread_rad > 0) centre << 0.0, -1.57, 1.2, -1.2, -1.57, 0.0;
    auto random_free = [&] {
      for (;;) {
        Joints q = centre;
        for (int i = 0; i < 6; ++i) q[i] += u(rng);
        if (robot.limits.Contains(q) && w.checker->IsFree(q)) return q;
      }
    };
    while (w.queries.size() < 40) {
      const Joints a = random_free();
      w.queries.push_back({a, random_free()});
    }
    worlds.push_back(std::move(w));
  }
  return worlds;
}

void BM_PlanPathScene(benchmark::State& state) {
  std::vector<SceneWorld> worlds = MakeSceneWorlds(0.1 * static_cast<double>(state.range(1)));
  const JointLimits limits = DefaultUr5(SimpleMillEnd()).limits;
  PathOptions options;
  options.range_rad = 0.1 * static_cast<double>(state.range(0));
  PathTally tally;
  int dense_failures = 0;
  for (auto _ : state) {
    for (SceneWorld& w : worlds) {
      PathPlanner planner(*w.checker, limits, options);
      for (const auto& [a, b] : w.queries) {
        const PathResult r = planner.Plan(a, b, Deadline::In(2.0));
        tally.Add(r);
        state.PauseTiming();
        for (size_t k = 1; k < r.waypoints.size(); ++k) {
          dense_failures += !w.checker->IsMotionFree(r.waypoints[k - 1], r.waypoints[k], 0.002);
        }
        state.ResumeTiming();
      }
    }
  }
  tally.Report(state);
  state.counters["dense_failures"] = dense_failures;
}
// Arguments: RRT-Connect range in tenths of a radian (0: OMPL's default, 0.2 x the extent of the
// joint box, ~5 rad here); query spread in tenths of a radian (0: whole joint box).
BENCHMARK(BM_PlanPathScene)
    ->Args({0, 12})->Args({10, 12})->Args({20, 12})->Args({0, 0})->Args({10, 0})
    ->Unit(benchmark::kMillisecond)->Iterations(1);

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
// Hopeless queries asked again (remember_failures = state.range(0)): a goal walled in by a
// joint-space shell and 20 starts around one region outside it, one planner for all (a pass's
// queries); a fresh planner per iteration, so every iteration fails the first query in full.
void BM_RepeatedHopelessQueries(benchmark::State& state) {
  testing::JointBallChecker checker;
  checker.AddShell(testing::J(2), 0.5, 0.8);
  PathOptions options;
  options.max_tree_states = 500;
  options.tree_max_step_m = 0.03;
  options.remember_failures = state.range(0) != 0;
  std::vector<Joints> starts;
  for (int k = 0; k < 20; ++k) starts.push_back(testing::J(-2, 0.05 * k, -0.05 * k));
  PathTally tally;
  int refused = 0;
  for (auto _ : state) {
    PathPlanner planner(checker, JointLimits(), options);
    for (const Joints& start : starts) {
      const PathResult r = planner.Plan(start, testing::J(2), Deadline::In(10.0));
      refused += r.repeated_failure;
      tally.Add(r);
    }
  }
  tally.Report(state);
  state.counters["refused_fraction"] = double(refused) / tally.total;
}
BENCHMARK(BM_RepeatedHopelessQueries)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// One query to a goal walled in by a joint-space shell, as PlanVine asks it, without and with
// PathOptions::walled_in_after_states (state.range(0): 0 or PlanVine's 100, with a tenth).
void BM_WalledInGoal(benchmark::State& state) {
  testing::JointBallChecker checker;
  checker.AddShell(testing::J(2), 0.5, 0.8);
  PathOptions options;
  options.max_tree_states = 500;
  options.tree_max_step_m = 0.03;
  options.walled_in_after_states = static_cast<int>(state.range(0));
  options.walled_in_goal_fraction = 0.1;
  PathTally tally;
  int walled_in = 0;
  PathPlanner planner(checker, JointLimits(), options);
  for (auto _ : state) {
    const PathResult r = planner.Plan(testing::J(-2), testing::J(2), Deadline::In(10.0));
    walled_in += r.walled_in;
    tally.Add(r);
  }
  tally.Report(state);
  state.counters["walled_in_fraction"] = double(walled_in) / tally.total;
}
BENCHMARK(BM_WalledInGoal)->Arg(0)->Arg(100)->Unit(benchmark::kMillisecond);

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
