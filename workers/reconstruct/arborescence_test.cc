// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/arborescence.h"

#include <algorithm>
#include <cstddef>
#include <random>
#include <vector>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

double TotalWeight(const std::vector<Arc>& arcs, const std::vector<int>& chosen) {
  double sum = 0.0;
  for (int k : chosen)
    if (k >= 0) sum += arcs[k].weight;
  return sum;
}

// Whether `chosen` is a spanning arborescence rooted at `root`: every other node has one
// incoming arc and its chain of parents reaches the root.
bool IsArborescence(int n, int root, const std::vector<Arc>& arcs, const std::vector<int>& chosen) {
  if (static_cast<int>(chosen.size()) != n || chosen[root] >= 0) return false;
  for (int v = 0; v < n; ++v) {
    if (v == root) continue;
    if (chosen[v] < 0 || arcs[chosen[v]].to != v) return false;
    int at = v;
    for (int hops = 0; at != root; ++hops) {
      if (hops > n) return false;
      at = arcs[chosen[at]].from;
    }
  }
  return true;
}

// The best arborescence by trying every choice of incoming arc (small graphs only).
double BruteForceBest(int n, int root, const std::vector<Arc>& arcs) {
  std::vector<std::vector<int>> incoming(n);
  for (size_t k = 0; k < arcs.size(); ++k)
    if (arcs[k].to != root && arcs[k].from != arcs[k].to) incoming[arcs[k].to].push_back(int(k));
  double best = -1e300;
  std::vector<int> chosen(n, -1);
  auto recurse = [&](auto&& self, int v) -> void {
    if (v == n) {
      if (IsArborescence(n, root, arcs, chosen)) best = std::max(best, TotalWeight(arcs, chosen));
      return;
    }
    if (v == root) return self(self, v + 1);
    for (int k : incoming[v]) {
      chosen[v] = k;
      self(self, v + 1);
    }
    chosen[v] = -1;
  };
  recurse(recurse, 0);
  return best;
}

TEST(MaxArborescence, TakesEachNodesBestArcWithoutACycle) {
  // 0 -> 1 (2), 0 -> 2 (1), 1 -> 2 (5): node 2 takes its arc from 1.
  const std::vector<Arc> arcs = {{0, 1, 2.0}, {0, 2, 1.0}, {1, 2, 5.0}};
  const std::vector<int> chosen = MaxArborescence(3, 0, arcs);
  EXPECT_EQ(chosen, (std::vector<int>{-1, 0, 2}));
}

TEST(MaxArborescence, BreaksACycleWhereItCostsLeast) {
  // 1 and 2 prefer each other (a cycle); entering the cycle at 2 from the root costs 10 - 1,
  // at 1 costs 9 - 0.5: the cheaper break is at 1.
  const std::vector<Arc> arcs = {{2, 1, 9.0}, {1, 2, 10.0}, {0, 1, 0.5}, {0, 2, 1.0}};
  const std::vector<int> chosen = MaxArborescence(3, 0, arcs);
  ASSERT_TRUE(IsArborescence(3, 0, arcs, chosen));
  EXPECT_EQ(chosen[1], 2);
  EXPECT_EQ(chosen[2], 1);
  EXPECT_DOUBLE_EQ(TotalWeight(arcs, chosen), 10.5);
}

TEST(MaxArborescence, MatchesBruteForceOnRandomGraphs) {
  std::mt19937 rng(1100);
  std::uniform_real_distribution<double> weight(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + trial % 5;
    std::vector<Arc> arcs;
    for (int v = 1; v < n; ++v) arcs.push_back({0, v, weight(rng)});  // always spanning
    for (int u = 1; u < n; ++u)
      for (int v = 1; v < n; ++v)
        if (u != v && rng() % 3 != 0) arcs.push_back({u, v, weight(rng)});
    const std::vector<int> chosen = MaxArborescence(n, 0, arcs);
    ASSERT_TRUE(IsArborescence(n, 0, arcs, chosen)) << "trial " << trial;
    EXPECT_NEAR(TotalWeight(arcs, chosen), BruteForceBest(n, 0, arcs), 1e-9) << "trial " << trial;
  }
}

}  // namespace
}  // namespace vb::reconstruct
