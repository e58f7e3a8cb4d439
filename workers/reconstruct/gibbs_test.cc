// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/gibbs.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

// Exact marginals and most likely assignment by enumerating every feasible assignment.
struct Exact {
  std::vector<double> marginals;
  std::vector<int> map_assignment;  // indices true in the most probable joint assignment
};

Exact Enumerate(const std::vector<double>& p, const std::vector<std::vector<int>>& conflicts) {
  const int n = static_cast<int>(p.size());
  Exact exact;
  exact.marginals.assign(n, 0.0);
  double z = 0.0, best = -1.0;
  for (int mask = 0; mask < (1 << n); ++mask) {
    bool feasible = true;
    for (int i = 0; i < n && feasible; ++i) {
      for (int j : conflicts[i]) feasible = feasible && !((mask >> i & 1) && (mask >> j & 1));
    }
    if (!feasible) continue;
    double w = 1.0;
    for (int i = 0; i < n; ++i) w *= (mask >> i & 1) ? p[i] : 1.0 - p[i];
    z += w;
    for (int i = 0; i < n; ++i) exact.marginals[i] += (mask >> i & 1) ? w : 0.0;
    if (w > best) {
      best = w;
      exact.map_assignment.clear();
      for (int i = 0; i < n; ++i) {
        if (mask >> i & 1) exact.map_assignment.push_back(i);
      }
    }
  }
  for (double& m : exact.marginals) m /= z;
  return exact;
}

// The constructed ambiguity: segment s in view a could match t1 in view b (candidate A,
// p = 0.6) or s could be two pieces matching t2 and t3 (candidates B and C, p = 0.55 each);
// A claims the same part of s as B and C, which do not overlap each other.
//   P({A})    = 0.6 * 0.45 * 0.45 = 0.1215   <- the most likely joint assignment (ML)
//   P({B, C}) = 0.4 * 0.55 * 0.55 = 0.1210
//   P({B}) = P({C}) = 0.4 * 0.55 * 0.45 = 0.0990,   P({}) = 0.4 * 0.45 * 0.45 = 0.0810
// Normalised (Z = 0.5215): P(A) = 0.233, P(B) = P(C) = (0.121 + 0.099) / 0.5215 = 0.422.
// The ML assignment keeps A, although A is right in under a quarter of the feasible worlds: the
// mass of "A is wrong" is spread over {B, C}, {B}, {C} and {}. With alpha = 2 (a missed match
// costs twice a wrong one) the minimum expected loss keeps i iff P(i) > 1/3: {B, C}, expected
// loss 2 * 0.578 + 2 * 0.233 = 1.62 against 0.767 + 2 * 0.844 = 2.46 for ML's {A}.
TEST(Gibbs, MinimumExpectedLossDiffersFromMaximumLikelihood) {
  const std::vector<double> p = {0.6, 0.55, 0.55};
  const std::vector<std::vector<int>> conflicts = {{1, 2}, {0}, {0}};
  const Exact exact = Enumerate(p, conflicts);
  EXPECT_EQ(exact.map_assignment, std::vector<int>({0}));
  EXPECT_NEAR(exact.marginals[0], 0.1215 / 0.5215, 1e-9);
  EXPECT_NEAR(exact.marginals[1], 0.22 / 0.5215, 1e-9);

  GibbsOptions options;
  options.sweeps = 20000;
  const std::vector<double> marginals = GibbsMarginals(p, conflicts, options);
  ASSERT_EQ(marginals.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(marginals[i], exact.marginals[i], 0.02) << i;
  EXPECT_EQ(SelectMinimumExpectedLoss(marginals, 2.0), std::vector<int>({1, 2}));
  // With symmetric costs nothing here is more likely right than wrong.
  EXPECT_TRUE(SelectMinimumExpectedLoss(marginals, 1.0).empty());
}

// The same idea with symmetric costs (alpha = 1), which needs three compatible rivals:
// A (p = 0.93) against B, C, D (p = 0.7 each). ML keeps A (0.02511 vs 0.02401 for {B, C, D}),
// but P(A) = 0.264 and P(B) = P(C) = P(D) = 0.515.
TEST(Gibbs, SymmetricLossKeepsTheLikelyRivals) {
  const std::vector<double> p = {0.93, 0.7, 0.7, 0.7};
  const std::vector<std::vector<int>> conflicts = {{1, 2, 3}, {}, {}, {}};
  const std::vector<std::vector<int>> symmetric = {{1, 2, 3}, {0}, {0}, {0}};
  const Exact exact = Enumerate(p, symmetric);
  EXPECT_EQ(exact.map_assignment, std::vector<int>({0}));
  GibbsOptions options;
  options.sweeps = 100000;
  options.seed = 7;
  const std::vector<double> marginals = GibbsMarginals(p, conflicts, options);  // one-sided list
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(marginals[i], exact.marginals[i], 0.01) << i;
  EXPECT_EQ(SelectMinimumExpectedLoss(marginals, 1.0), std::vector<int>({1, 2, 3}));
}

TEST(Gibbs, UnconstrainedMarginalsAreThePriors) {
  const std::vector<double> marginals = GibbsMarginals({0.2, 0.9, 1.5, -1.0, NAN}, {});
  EXPECT_EQ(marginals, std::vector<double>({0.2, 0.9, 1.0, 0.0, 0.0}));
}

TEST(Gibbs, DeterministicInTheSeed) {
  const std::vector<double> p = {0.5, 0.6, 0.7, 0.4};
  const std::vector<std::vector<int>> conflicts = {{1}, {2}, {3}, {0}};
  GibbsOptions options;
  options.seed = 42;
  EXPECT_EQ(GibbsMarginals(p, conflicts, options), GibbsMarginals(p, conflicts, options));
  GibbsOptions other = options;
  other.seed = 43;
  EXPECT_NE(GibbsMarginals(p, conflicts, options), GibbsMarginals(p, conflicts, other));
}

TEST(Gibbs, CertainCandidateExcludesItsRivals) {
  const std::vector<double> marginals = GibbsMarginals({1.0, 0.9}, {{1}, {0}});
  EXPECT_DOUBLE_EQ(marginals[0], 1.0);
  EXPECT_DOUBLE_EQ(marginals[1], 0.0);
}

TEST(Gibbs, IgnoresBadConflictIndicesAndEmptyInput) {
  EXPECT_TRUE(GibbsMarginals({}, {{0, 1}}).empty());
  const std::vector<double> marginals = GibbsMarginals({0.3}, {{0, 5, -1}});
  EXPECT_EQ(marginals, std::vector<double>({0.3}));
}

TEST(GibbsOptions, ValidateRejectsBadSweeps) {
  GibbsOptions options;
  EXPECT_TRUE(options.Validate().ok());
  options.sweeps = 0;
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  options = {};
  options.burn_in_sweeps = -1;
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
}

TEST(SelectMinimumExpectedLoss, ThresholdIsOneOverOnePlusAlpha) {
  const std::vector<double> m = {0.1, 0.3, 0.5, 0.51, 0.9};
  EXPECT_EQ(SelectMinimumExpectedLoss(m, 1.0), std::vector<int>({3, 4}));
  EXPECT_EQ(SelectMinimumExpectedLoss(m, 3.0), std::vector<int>({1, 2, 3, 4}));  // > 0.25
  EXPECT_EQ(SelectMinimumExpectedLoss(m, 0.25), std::vector<int>({4}));          // > 0.8
  EXPECT_TRUE(SelectMinimumExpectedLoss(m, 0.0).empty());
  EXPECT_TRUE(SelectMinimumExpectedLoss(m, NAN).empty());
  EXPECT_EQ(SelectMinimumExpectedLoss(m, INFINITY).size(), 5u);
}

}  // namespace
}  // namespace vb::reconstruct
