// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/cut_order.h"
#include "workers/plan/cut_order_test_util.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <set>

#include "gtest/gtest.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

// Asymmetric random costs in [1, 10).
Eigen::MatrixXd RandomCosts(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(1.0, 10.0);
  Eigen::MatrixXd c(n + 1, n + 1);
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) c(i, j) = i == j ? 0.0 : u(rng);
  }
  return c;
}

double BruteForce(const Eigen::MatrixXd& c, bool return_to_start) {
  std::vector<int> order(c.rows() - 1);
  std::iota(order.begin(), order.end(), 1);
  double best = std::numeric_limits<double>::infinity();
  do {
    best = std::min(best, OrderCost(c, order, return_to_start));
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

bool IsPermutation(const std::vector<int>& order, int n) {
  std::set<int> seen(order.begin(), order.end());
  return static_cast<int>(order.size()) == n && static_cast<int>(seen.size()) == n &&
         (n == 0 || (*seen.begin() == 1 && *seen.rbegin() == n));
}

TEST(CutOrder, HeldKarpEqualsBruteForce) {
  for (int n = 2; n <= 8; ++n) {
    for (uint32_t seed = 0; seed < 4; ++seed) {
      for (bool ret : {false, true}) {
        const Eigen::MatrixXd c = RandomCosts(n, 100 * n + seed);
        const OrderResult r = OrderCuts(c, ret);
        ASSERT_TRUE(IsPermutation(r.order, n));
        EXPECT_TRUE(r.exact);
        EXPECT_NEAR(r.cost, BruteForce(c, ret), 1e-9) << "n=" << n << " seed=" << seed;
        EXPECT_NEAR(r.cost, OrderCost(c, r.order, ret), 1e-12);
      }
    }
  }
}

TEST(CutOrder, HeuristicIsNearExactOnMoveTimes) {
  double worst = 0, sum = 0;
  int count = 0;
  for (int n = 12; n <= 15; ++n) {
    for (uint32_t seed = 0; seed < 3; ++seed) {
      for (bool ret : {false, true}) {
        const Eigen::MatrixXd c = MoveTimeCosts(n, 1000 * n + seed);
        const OrderResult exact = HeldKarpOrder(c, ret);
        const OrderResult heuristic = HeuristicOrder(c, ret);
        ASSERT_TRUE(IsPermutation(heuristic.order, n));
        EXPECT_FALSE(heuristic.exact);
        EXPECT_GE(heuristic.cost, exact.cost - 1e-9);
        const double gap = heuristic.cost / exact.cost - 1.0;
        worst = std::max(worst, gap);
        sum += gap;
        ++count;
        // Nearest neighbour alone is never better than exact either.
        EXPECT_GE(NearestNeighbourOrder(c, ret).cost, exact.cost - 1e-9);
      }
    }
  }
  EXPECT_LT(worst, 0.05);
  EXPECT_LT(sum / count, 0.02);
}

TEST(CutOrder, HeuristicIsNearExactOnAsymmetricCosts) {
  double worst = 0;
  for (int n = 12; n <= 14; ++n) {
    for (uint32_t seed = 0; seed < 2; ++seed) {
      const Eigen::MatrixXd c = RandomCosts(n, 5000 * n + seed);
      const double exact = HeldKarpOrder(c).cost;
      worst = std::max(worst, HeuristicOrder(c).cost / exact - 1.0);
    }
  }
  EXPECT_LT(worst, 0.10);
}

TEST(CutOrder, LargeInstancesUseTheHeuristic) {
  const Eigen::MatrixXd c = MoveTimeCosts(40, 7);
  const OrderResult r = OrderCuts(c);
  EXPECT_FALSE(r.exact);
  ASSERT_TRUE(IsPermutation(r.order, 40));
  EXPECT_LE(r.cost, NearestNeighbourOrder(c).cost + 1e-9);
}

TEST(CutOrder, ZeroAndOneCut) {
  Eigen::MatrixXd c0 = Eigen::MatrixXd::Zero(1, 1);
  OrderResult r = OrderCuts(c0, true);
  EXPECT_TRUE(r.order.empty());
  EXPECT_EQ(r.cost, 0.0);
  EXPECT_TRUE(r.exact);
  Eigen::MatrixXd c1(2, 2);
  c1 << 0, 2, 3, 0;
  r = OrderCuts(c1);
  EXPECT_EQ(r.order, std::vector<int>{1});
  EXPECT_EQ(r.cost, 2.0);
  EXPECT_EQ(OrderCuts(c1, true).cost, 5.0);
  EXPECT_EQ(NearestNeighbourOrder(c1).order, std::vector<int>{1});
  EXPECT_EQ(HeuristicOrder(c1, true).cost, 5.0);
}

TEST(CutOrder, AsymmetryIsRespected) {
  // Going 1 -> 2 is cheap, 2 -> 1 dear; from the start both are equally far.
  Eigen::MatrixXd c(3, 3);
  c << 0, 5, 5,
       5, 0, 1,
       5, 9, 0;
  const OrderResult r = OrderCuts(c);
  EXPECT_EQ(r.order, (std::vector<int>{1, 2}));
  EXPECT_EQ(r.cost, 6.0);
}

TEST(CutOrder, UnusableMovesAreAvoided) {
  Eigen::MatrixXd c = RandomCosts(6, 3);
  const double inf = std::numeric_limits<double>::infinity();
  c(0, 1) = inf;
  c(0, 2) = std::numeric_limits<double>::quiet_NaN();
  c(3, 4) = inf;
  for (const OrderResult& r : {OrderCuts(c), HeuristicOrder(c), NearestNeighbourOrder(c)}) {
    ASSERT_TRUE(IsPermutation(r.order, 6));
    EXPECT_TRUE(std::isfinite(r.cost));
    EXPECT_NE(r.order.front(), 1);
    EXPECT_NE(r.order.front(), 2);
  }
  // When every order must use one, the cost says so.
  Eigen::MatrixXd all = Eigen::MatrixXd::Constant(3, 3, inf);
  const OrderResult r = OrderCuts(all);
  EXPECT_TRUE(IsPermutation(r.order, 2));
  EXPECT_EQ(r.cost, inf);
}

TEST(CutOrder, MalformedMatrixRejects) {
  const OrderResult r = OrderCuts(Eigen::MatrixXd::Zero(3, 4));
  EXPECT_TRUE(r.order.empty());
  EXPECT_TRUE(std::isnan(r.cost));
  EXPECT_TRUE(std::isnan(OrderCuts(Eigen::MatrixXd()).cost));
  EXPECT_TRUE(std::isnan(OrderCost(Eigen::MatrixXd::Zero(3, 3), {1, 3})));
  EXPECT_TRUE(std::isnan(OrderCost(Eigen::MatrixXd::Zero(3, 3), {0})));
}

TEST(CutOrder, OrderCostSumsMoves) {
  Eigen::MatrixXd c(3, 3);
  c << 0, 1, 2,
       3, 0, 4,
       5, 6, 0;
  EXPECT_EQ(OrderCost(c, {2, 1}), 2.0 + 6.0);
  EXPECT_EQ(OrderCost(c, {2, 1}, true), 2.0 + 6.0 + 3.0);
  EXPECT_EQ(OrderCost(c, {}, true), 0.0);
}

// Along a fixed order: option A of the first cut is the nearer (1 vs 2) but leads to a far
// second cut (10 vs 1); nearest-first picks A (11), the dynamic programme B (3).
TEST(ChooseAlongOrder, BeatsTheNearestChoiceWhenItLeadsFar) {
  Eigen::MatrixXd first(1, 2), second(2, 1);
  first << 1.0, 2.0;
  second << 10.0, 1.0;
  const ChoiceResult r = ChooseAlongOrder({first, second});
  EXPECT_EQ(r.choice, (std::vector<int>{0, 1, 0}));
  EXPECT_DOUBLE_EQ(r.cost, 3.0);
  ASSERT_EQ(r.first_costs.size(), 2u);
  EXPECT_DOUBLE_EQ(r.first_costs[0], 11.0);
  EXPECT_DOUBLE_EQ(r.first_costs[1], 3.0);
}

TEST(ChooseAlongOrder, MatchesBruteForceAndAvoidsUnusableMoves) {
  std::mt19937 rng(1101);
  std::uniform_real_distribution<double> u(1.0, 10.0);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<int> sizes = {1, 3, 2, 4, 3};
    std::vector<Eigen::MatrixXd> t;
    for (size_t l = 0; l + 1 < sizes.size(); ++l) {
      Eigen::MatrixXd m(sizes[l], sizes[l + 1]);
      for (int a = 0; a < m.rows(); ++a)
        for (int b = 0; b < m.cols(); ++b) m(a, b) = u(rng);
      t.push_back(m);
    }
    t[1](0, 0) = std::numeric_limits<double>::infinity();
    t[2](1, 2) = std::numeric_limits<double>::quiet_NaN();
    double best = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 2; ++b)
        for (int c = 0; c < 4; ++c)
          for (int d = 0; d < 3; ++d) {
            const double v = t[0](0, a) + t[1](a, b) + t[2](b, c) + t[3](c, d);
            if (!std::isnan(v)) best = std::min(best, v);
          }
    const ChoiceResult r = ChooseAlongOrder(t);
    ASSERT_EQ(r.choice.size(), 5u);
    EXPECT_NEAR(r.cost, best, 1e-9);
    double sum = 0.0;
    for (size_t l = 0; l < t.size(); ++l) sum += t[l](r.choice[l], r.choice[l + 1]);
    EXPECT_NEAR(sum, r.cost, 1e-9);
  }
}

TEST(ChooseAlongOrder, RejectsMatricesThatDoNotChain) {
  EXPECT_TRUE(std::isnan(ChooseAlongOrder({Eigen::MatrixXd::Ones(1, 2),
                                           Eigen::MatrixXd::Ones(3, 1)}).cost));
  EXPECT_TRUE(std::isnan(ChooseAlongOrder({Eigen::MatrixXd(1, 0)}).cost));
  const ChoiceResult empty = ChooseAlongOrder({});
  EXPECT_EQ(empty.choice, std::vector<int>{0});
  EXPECT_EQ(empty.cost, 0.0);
}

// Options as points on a line: cost = distance; node 0 at 0.
struct LineCase {
  std::vector<std::vector<double>> at;  // per cut node 1..n, its options' positions
  double Cost(int i, int a, int j, int b) const {
    const double from = i == 0 ? 0.0 : at[i - 1][a];
    const double to = j == 0 ? 0.0 : at[j - 1][b];
    return std::abs(to - from) + 0.1;
  }
};

double BruteForceWithOptions(const LineCase& c, bool return_to_start) {
  const int n = static_cast<int>(c.at.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 1);
  double best = std::numeric_limits<double>::infinity();
  do {
    std::vector<Eigen::MatrixXd> t;
    int prev = 0;
    for (int node : order) {
      const int rows = prev == 0 ? 1 : static_cast<int>(c.at[prev - 1].size());
      Eigen::MatrixXd m(rows, c.at[node - 1].size());
      for (int a = 0; a < m.rows(); ++a)
        for (int b = 0; b < m.cols(); ++b) m(a, b) = c.Cost(prev, a, node, b);
      t.push_back(m);
      prev = node;
    }
    if (return_to_start) {
      Eigen::MatrixXd m(c.at[prev - 1].size(), 1);
      for (int a = 0; a < m.rows(); ++a) m(a, 0) = c.Cost(prev, a, 0, 0);
      t.push_back(m);
    }
    best = std::min(best, ChooseAlongOrder(t).cost);
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

TEST(OrderAndChoose, BeatsOrderingOnTheFirstOptionsThenChoosingNearest) {
  // Cut 1 has options A (1 from the start, 10 to cut 2) and B (2 from the start, 1 to cut 2);
  // cut 2 is 20 from the start and from either option back. Ordered on the first options
  // (A): 1, 2; nearest first then takes A: 11. Jointly: B, then cut 2: 3.
  const MoveCost table = [](int i, int a, int j, int b) {
    if (i == 0) return j == 1 ? (b == 0 ? 1.0 : 2.0) : 20.0;
    if (i == 1) return j == 2 ? (a == 0 ? 10.0 : 1.0) : 20.0;
    return 20.0;  // from cut 2
  };
  const OrderChoiceResult r = OrderAndChoose({2, 1}, table);
  EXPECT_EQ(r.order, (std::vector<int>{1, 2}));
  EXPECT_EQ(r.choice, (std::vector<int>{0, 1, 0}));
  EXPECT_DOUBLE_EQ(r.cost, 3.0);
  EXPECT_TRUE(r.exact_order);
  // With one option per cut it is OrderCuts on that matrix.
  const OrderChoiceResult single = OrderAndChoose({1, 1}, table);
  EXPECT_DOUBLE_EQ(single.cost, 11.0);
}

TEST(OrderAndChoose, IsWithinTheJointOptimumOnRandomCases) {
  std::mt19937 rng(1102);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::uniform_int_distribution<int> options(1, 3);
  int optimal = 0;
  for (int trial = 0; trial < 30; ++trial) {
    LineCase c;
    for (int i = 0; i < 5; ++i) {
      c.at.emplace_back();
      for (int a = options(rng); a > 0; --a) c.at.back().push_back(u(rng));
    }
    std::vector<int> counts;
    for (const auto& o : c.at) counts.push_back(static_cast<int>(o.size()));
    const bool home = trial % 2 == 1;
    const MoveCost cost = [&](int i, int a, int j, int b) { return c.Cost(i, a, j, b); };
    const OrderChoiceResult r = OrderAndChoose(counts, cost, home);
    ASSERT_TRUE(IsPermutation(r.order, 5));
    ASSERT_EQ(r.choice.size(), 6u);
    // The reported cost is that of the order and options returned.
    double sum = 0.0;
    int prev = 0;
    for (int node : r.order) {
      ASSERT_LT(r.choice[node], counts[node - 1]);
      sum += c.Cost(prev, r.choice[prev], node, r.choice[node]);
      prev = node;
    }
    if (home) sum += c.Cost(prev, r.choice[prev], 0, 0);
    EXPECT_NEAR(sum, r.cost, 1e-9);
    const double best = BruteForceWithOptions(c, home);
    EXPECT_GE(r.cost, best - 1e-9);
    // Never worse than the order on first options with the options then chosen along it.
    Eigen::MatrixXd first(6, 6);
    for (int i = 0; i <= 5; ++i)
      for (int j = 0; j <= 5; ++j) first(i, j) = i == j ? 0.0 : c.Cost(i, 0, j, 0);
    EXPECT_LE(r.cost, OrderCost(first, OrderCuts(first, home).order, home) + 1e-9);
    if (r.cost <= best + 1e-9) ++optimal;
  }
  // Alternation is a heuristic, but on points on a line it is nearly always optimal.
  EXPECT_GE(optimal, 25);
}

}  // namespace
}  // namespace vb::plan
