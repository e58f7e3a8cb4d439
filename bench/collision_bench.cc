// SPDX-License-Identifier: Apache-2.0
// Collision checks per configuration (issue 5: <= 200 ns amortised on a typical vine scene) for
// the primitive checker and the FCL baselines (FCL primitives, FCL meshes), on the scenes of 8
// simulated vines (sim::GenerateScene, seeds 1100-1107, ground truth, no neighbours) with the
// default UR5 mount and a mill-end tool. Configurations are drawn uniformly within the joint
// limits (fixed seed); `free` variants use only configurations that are free (no early exit: the
// worst case for a checker), `motion` variants check straight joint-space motions at 1 cm
// resolution (IsMotionFree; what a planner asks): between consecutive free configurations (mostly
// colliding, early exit) or along free motions (every sample checked: a direct path; each from a
// free configuration a quarter of the way to the next one, kept if free). BM_AreFree checks the
// configurations in batches of 64 (AreFree; the primitive checker works 8 lanes at a time with
// AVX2, 4 otherwise).
// `baseline_simd:1` variants run the primitive checker's baseline SIMD code (SSE2) instead of the
// AVX2 code it picks on a CPU that has AVX2.
// Counters: ns_per_check, free_fraction, checks_per_motion (and, on free motions,
// checks_per_motion_reach_1_2m: the samples of the former single-reach MotionSteps). Run:
//   build/bench/vb_collision_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <memory>
#include <random>
#include <vector>

#include "benchmark/benchmark.h"
#include "sim/vine_generator.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/primitive_checker.h"
#include "workers/plan/simple_tool_test_util.h"

namespace vb::plan {
namespace {

constexpr int kVines = 8;
constexpr int kConfigurations = 4096;

struct Fixture {
  RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::vector<CollisionScene> scenes;
  std::vector<Joints> random;                  // uniform within the limits
  std::vector<std::vector<Joints>> free;       // per scene: free configurations only
  std::vector<std::vector<std::pair<Joints, Joints>>> free_motions;  // per scene

  Fixture() {
    sim::VineGeneratorOptions options;
    options.neighbours = false;
    for (int v = 0; v < kVines; ++v) {
      auto sim_scene = sim::GenerateScene(1100 + v, 0, options);
      auto scene = CollisionScene::Build(sim_scene->vine, DefaultPlatform(), robot);
      scenes.push_back(*scene);
    }
    std::mt19937 rng(1100);
    for (int k = 0; k < kConfigurations; ++k) {
      Joints q;
      for (int i = 0; i < 6; ++i) {
        q[i] = std::uniform_real_distribution<double>(robot.limits.lower[i],
                                                      robot.limits.upper[i])(rng);
      }
      random.push_back(q);
    }
    for (const CollisionScene& scene : scenes) {
      PrimitiveChecker checker(robot, scene);
      free.emplace_back();
      for (const Joints& q : random) {
        if (checker.IsFree(q)) free.back().push_back(q);
      }
      free_motions.emplace_back();
      const std::vector<Joints>& qs = free.back();
      for (size_t i = 0; i + 1 < qs.size() && free_motions.back().size() < 256; ++i) {
        const Joints b = qs[i] + 0.25 * (qs[i + 1] - qs[i]);
        if (checker.CollisionChecker::IsMotionFree(qs[i], b, 0.01)) {
          free_motions.back().emplace_back(qs[i], b);
        }
      }
    }
  }
};

const Fixture& GetFixture() {
  static const Fixture* fixture = new Fixture();
  return *fixture;
}

enum Kind { kPrimitive = 0, kFclPrimitives = 1, kFclMesh = 2 };

// kind: checker kind; baseline_simd: the primitive checker's baseline SIMD code even where the
// CPU has AVX2.
std::unique_ptr<CollisionChecker> Make(int kind, const RobotModel& robot,
                                       const CollisionScene& scene, bool baseline_simd = false) {
  if (kind == kPrimitive) {
    auto checker = std::make_unique<PrimitiveChecker>(robot, scene);
    if (baseline_simd) checker->UseBaselineSimd();
    return checker;
  }
  return MakeFclChecker(robot, scene, kind == kFclMesh ? FclMode::kMesh : FclMode::kPrimitives);
}

// state.range(0): checker kind; state.range(1): 0 random configurations, 1 free ones only.
void BM_Check(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<std::unique_ptr<CollisionChecker>> checkers;
  for (const CollisionScene& scene : f.scenes) checkers.push_back(Make(state.range(0), f.robot, scene));
  const bool free_only = state.range(1) == 1;
  int64_t checks = 0, free = 0;
  size_t k = 0;
  for (auto _ : state) {
    const int v = static_cast<int>(k % kVines);
    const std::vector<Joints>& qs = free_only ? f.free[v] : f.random;
    const bool ok = checkers[v]->IsFree(qs[(k / kVines) % qs.size()]);
    benchmark::DoNotOptimize(ok);
    free += ok;
    ++checks;
    ++k;
  }
  state.counters["ns_per_check"] = benchmark::Counter(
      static_cast<double>(checks) * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["free_fraction"] = static_cast<double>(free) / std::max<int64_t>(1, checks);
}

// state.range(0): checker kind, range(1): 0 random configurations, 1 free ones only; range(2):
// 1 for the baseline SIMD code.
void BM_AreFree(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<std::unique_ptr<CollisionChecker>> checkers;
  for (const CollisionScene& scene : f.scenes) {
    checkers.push_back(Make(state.range(0), f.robot, scene, state.range(2) == 1));
  }
  const bool free_only = state.range(1) == 1;
  constexpr size_t kBatch = 64;
  bool out[kBatch];
  int64_t checks = 0, free = 0;
  size_t k = 0;
  for (auto _ : state) {
    const int v = static_cast<int>(k % kVines);
    const std::vector<Joints>& qs = free_only ? f.free[v] : f.random;
    const size_t first = ((k / kVines) * kBatch) % (qs.size() - kBatch);
    checkers[v]->AreFree(std::span<const Joints>(&qs[first], kBatch), out);
    benchmark::DoNotOptimize(out);
    for (bool b : out) free += b;
    checks += kBatch;
    ++k;
  }
  state.counters["ns_per_check"] = benchmark::Counter(
      static_cast<double>(checks) * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["free_fraction"] = static_cast<double>(free) / std::max<int64_t>(1, checks);
}

// state.range(0): checker kind; range(1): 0 motions between consecutive free configurations of
// a scene, 1 free motions only, 2 free motions with IsFree at each sample (unbatched, the same
// samples). 1 cm resolution. range(2): 1 for the baseline SIMD code.
bool MotionByIsFree(CollisionChecker& checker, const Joints& a, const Joints& b) {
  const int n = MotionSteps(a, b, 0.01, checker.lever_m());
  for (int k = 0; k <= n; ++k) {
    if (!checker.IsFree(a + (b - a) * (double(k) / n))) return false;
  }
  return true;
}

void BM_Motion(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<std::unique_ptr<CollisionChecker>> checkers;
  for (const CollisionScene& scene : f.scenes) {
    checkers.push_back(Make(state.range(0), f.robot, scene, state.range(2) == 1));
  }
  const bool free_only = state.range(1) >= 1, by_is_free = state.range(1) == 2;
  int64_t motions = 0, free = 0, uniform_checks = 0;
  size_t k = 0;
  for (auto _ : state) {
    const int v = static_cast<int>(k % kVines);
    const std::vector<Joints>& qs = f.free[v];
    const auto& fm = f.free_motions[v];
    if (free_only) {
      const size_t i = (k / kVines) % fm.size();
      uniform_checks += MotionSteps(fm[i].first, fm[i].second, 0.01, kDefaultReachM) + 1;
    }
    const size_t i = (k / kVines) % (free_only ? fm.size() : qs.size() - 1);
    const bool ok = by_is_free ? MotionByIsFree(*checkers[v], fm[i].first, fm[i].second)
                    : free_only ? checkers[v]->IsMotionFree(fm[i].first, fm[i].second, 0.01)
                                : checkers[v]->IsMotionFree(qs[i], qs[i + 1], 0.01);
    benchmark::DoNotOptimize(ok);
    free += ok;
    ++motions;
    ++k;
  }
  int64_t checks = 0;
  for (const auto& c : checkers) checks += c->checks();
  state.counters["ns_per_check"] = benchmark::Counter(
      static_cast<double>(checks) * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["checks_per_motion"] = static_cast<double>(checks) / std::max<int64_t>(1, motions);
  // What the former single 1.2 m reach would sample on the same free motions (all samples).
  if (free_only) {
    state.counters["checks_per_motion_reach_1_2m"] =
        static_cast<double>(uniform_checks) / std::max<int64_t>(1, motions);
  }
  state.counters["free_fraction"] = static_cast<double>(free) / std::max<int64_t>(1, motions);
}

BENCHMARK(BM_Check)
    ->ArgNames({"checker", "free_only"})
    ->Args({kPrimitive, 0})
    ->Args({kPrimitive, 1})
    ->Args({kFclPrimitives, 0})
    ->Args({kFclPrimitives, 1})
    ->Args({kFclMesh, 0})
    ->Args({kFclMesh, 1});
BENCHMARK(BM_AreFree)
    ->ArgNames({"checker", "free_only", "baseline_simd"})
    ->Args({kPrimitive, 0, 0})
    ->Args({kPrimitive, 1, 0})
    ->Args({kPrimitive, 0, 1})
    ->Args({kPrimitive, 1, 1});
BENCHMARK(BM_Motion)
    ->ArgNames({"checker", "free_only", "baseline_simd"})
    ->Args({kPrimitive, 0, 0})
    ->Args({kPrimitive, 1, 0})
    ->Args({kPrimitive, 2, 0})
    ->Args({kPrimitive, 0, 1})
    ->Args({kPrimitive, 1, 1})
    ->Args({kFclPrimitives, 0, 0})
    ->Args({kFclPrimitives, 1, 0})
    ->Args({kFclMesh, 0, 0});

}  // namespace
}  // namespace vb::plan

BENCHMARK_MAIN();
