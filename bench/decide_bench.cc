// SPDX-License-Identifier: Apache-2.0
// Decision time per vine vs candidate count (issue 4: <= 5 ms per vine for 25+ candidates).
// Candidate sets are cut from simulated vines (sim::GenerateScene, seeds 1100-1199): the canes of
// consecutive vines are pooled, renumbered, and the first N taken, so features and ancestry are
// those of real-looking vines while N goes past what one vine has. Each iteration searches 8
// different sets; times are per set (one vine). BM_FindBestSchemeSynthetic uses synthetic sets
// with signed random weights instead (a harder case). Run:
//   build/bench/vb_decide_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "benchmark/benchmark.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/decide/scheme.h"

namespace vb::decide {
namespace {

constexpr int kSetsPerSize = 8;

// Candidates of the simulated vine of `seed`, ids offset by seed * 1000 so pools stay unique.
std::vector<Candidate> VineCandidates(uint64_t seed) {
  sim::VineGeneratorOptions options;
  options.neighbours = false;
  auto scene = sim::GenerateScene(seed, 0, options);
  if (!scene.ok()) return {};
  auto candidates = FindCandidates(scene->vine, PruningPolicy{});
  if (!candidates.ok()) return {};
  const int64_t offset = static_cast<int64_t>(seed) * 1000;
  for (Candidate& c : *candidates) {
    c.id = CaneId(c.id.value + offset);
    for (CaneId& a : c.ancestors) a = CaneId(a.value + offset);
  }
  return *candidates;
}

// Set k of size n: pooled from vines 1100 + 10 k onward.
std::vector<Candidate> CandidateSet(int n, int k) {
  std::vector<Candidate> pool;
  for (uint64_t seed = 1100 + 10 * k; static_cast<int>(pool.size()) < n; ++seed) {
    for (Candidate& c : VineCandidates(seed)) pool.push_back(std::move(c));
  }
  pool.resize(n);
  // Ancestors that did not make the cut are dropped (the relation stays an ancestry forest).
  std::unordered_map<int64_t, int> present;
  for (const Candidate& c : pool) present[c.id.value] = 1;
  for (Candidate& c : pool) {
    std::erase_if(c.ancestors, [&present](CaneId a) { return !present.contains(a.value); });
  }
  return pool;
}

// Synthetic set k of size n: features uniform over their plausible ranges (no vine structure),
// 30% secondary canes. Harder than real vines: nothing makes a few canes stand out.
std::vector<Candidate> SyntheticSet(int n, int k) {
  std::mt19937 rng(1000 + 37 * n + k);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Candidate> out;
  for (int i = 0; i < n; ++i) {
    Candidate c;
    c.id = CaneId(i + 2);
    if (i > 0 && u(rng) < 0.3) {
      const Candidate& parent = out[std::uniform_int_distribution<int>(0, i - 1)(rng)];
      c.ancestors = parent.ancestors;
      c.ancestors.insert(c.ancestors.begin(), parent.id);
      c.origin = CaneOrigin::kCane;
    } else {
      c.origin = u(rng) < 0.8 ? CaneOrigin::kHead : CaneOrigin::kTrunk;
    }
    c.length_m = 0.1 + 1.4 * u(rng);
    c.base_diameter_m = 0.004 + 0.011 * u(rng);
    c.base = Eigen::Vector3d(0.6 * u(rng) - 0.3, 0.8, 0.6 + 0.5 * u(rng));
    c.base_distance_from_head_m = 0.4 * u(rng);
    c.angle_from_head_rad = 3.14159 * u(rng);
    c.wire_z_m = 0.95;
    c.side = u(rng) < 0.5 ? -1 : 1;
    out.push_back(c);
  }
  return out;
}

SchemeWeights SignedWeights(int k) {
  std::mt19937 rng(77 + k);
  std::normal_distribution<double> g(0.0, 2.0);
  SchemeWeights w;
  for (int f = 0; f < kSchemeFeatureCount; ++f) w.w[f] = g(rng);
  return w;
}

void Search(benchmark::State& state, bool signed_weights, bool synthetic = false) {
  const int n = static_cast<int>(state.range(0));
  PruningPolicy policy;
  policy.canes_to_keep = static_cast<int>(state.range(1));
  policy.spurs = static_cast<int>(state.range(1));
  std::vector<std::vector<Candidate>> sets;
  std::vector<SchemeWeights> weights;
  for (int k = 0; k < kSetsPerSize; ++k) {
    sets.push_back(synthetic ? SyntheticSet(n, k) : CandidateSet(n, k));
    weights.push_back(signed_weights ? SignedWeights(k) : DefaultSchemeWeights());
  }
  long long nodes = 0;
  long long searches = 0;
  for (auto _ : state) {
    for (int k = 0; k < kSetsPerSize; ++k) {
      SearchStats stats;
      auto scheme = FindBestScheme(sets[k], policy, weights[k], Deadline::Infinite(), &stats);
      if (!scheme.ok()) state.SkipWithError(std::string(scheme.status().message()).c_str());
      benchmark::DoNotOptimize(scheme);
      nodes += stats.schemes_visited;
      ++searches;
    }
  }
  // Seconds per vine (one candidate set): 1 / (sets searched per second).
  state.counters["per_vine_s"] = benchmark::Counter(
      kSetsPerSize, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["nodes_per_vine"] = searches > 0 ? static_cast<double>(nodes) / searches : 0.0;
}

void BM_FindBestScheme(benchmark::State& state) { Search(state, false); }
void BM_FindBestSchemeSignedWeights(benchmark::State& state) { Search(state, true); }
void BM_FindBestSchemeSynthetic(benchmark::State& state) { Search(state, true, true); }

void SizesAndKeeps(benchmark::internal::Benchmark* b) {
  for (int keep : {2, 6}) {
    for (int n : {5, 10, 15, 20, 25, 30, 40}) b->Args({n, keep});
  }
  b->ArgNames({"candidates", "keep"})->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_FindBestScheme)->Apply(SizesAndKeeps);
BENCHMARK(BM_FindBestSchemeSignedWeights)->Apply(SizesAndKeeps);
BENCHMARK(BM_FindBestSchemeSynthetic)->Apply(SizesAndKeeps);

// The whole stage (candidates, search, cut points) on whole simulated vines, default policy.
void BM_DecideSimulatedVine(benchmark::State& state) {
  std::vector<VineModel> vines;
  for (uint64_t seed = 1100; seed < 1100 + kSetsPerSize; ++seed) {
    sim::VineGeneratorOptions options;
    options.neighbours = false;
    auto scene = sim::GenerateScene(seed, 0, options);
    if (scene.ok()) vines.push_back(scene->vine);
  }
  for (auto _ : state) {
    for (const VineModel& vine : vines) {
      auto decision = Decide(vine, PruningPolicy{});
      benchmark::DoNotOptimize(decision);
    }
  }
  state.counters["per_vine_s"] = benchmark::Counter(
      static_cast<double>(vines.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_DecideSimulatedVine)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace vb::decide

BENCHMARK_MAIN();
