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

}  // namespace
}  // namespace vb::plan
