// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/scheme.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb::decide {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::vector<CaneId> Ids(std::initializer_list<int> ids) {
  std::vector<CaneId> out;
  for (int id : ids) out.push_back(CaneId(id));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Brute force: every assignment of roles (none / keep / spur) obeying the rules, written
// independently of scheme.cc from the contract's words.

struct BruteResult {
  SchemeSize size;
  Scheme best;
  double cost = 0.0;
};

BruteResult BruteForce(const std::vector<Candidate>& cands, const PruningPolicy& policy,
                       const SchemeWeights& weights) {
  const int n = static_cast<int>(cands.size());
  const int keep_max = policy.style == PruningStyle::kSpur ? 0 : policy.canes_to_keep;
  auto related = [&](int i, int j) {
    for (CaneId a : cands[i].ancestors) {
      if (a == cands[j].id) return true;
    }
    for (CaneId a : cands[j].ancestors) {
      if (a == cands[i].id) return true;
    }
    return false;
  };
  std::vector<Scheme> allowed;
  std::vector<int> role(n, 0);
  std::vector<int> chosen;
  // Recursive enumeration with the count limits.
  std::function<void(int, int, int)> walk = [&](int i, int k, int s) {
    if (i == n) {
      Scheme scheme;
      for (int j = 0; j < n; ++j) {
        if (role[j] == 1) scheme.keep.push_back(cands[j].id);
        if (role[j] == 2) scheme.spurs.push_back(cands[j].id);
      }
      std::sort(scheme.keep.begin(), scheme.keep.end());
      std::sort(scheme.spurs.begin(), scheme.spurs.end());
      allowed.push_back(scheme);
      return;
    }
    walk(i + 1, k, s);
    bool free = true;
    for (int j : chosen) free = free && !related(i, j);
    if (!free) return;
    chosen.push_back(i);
    if (k < keep_max && cands[i].length_m >= policy.min_kept_length_m) {
      role[i] = 1;
      walk(i + 1, k + 1, s);
    }
    if (s < policy.spurs) {
      role[i] = 2;
      walk(i + 1, k, s + 1);
    }
    role[i] = 0;
    chosen.pop_back();
  };
  walk(0, 0, 0);
  BruteResult r;
  for (const Scheme& s : allowed) {
    r.size = std::max(r.size, SchemeSize{static_cast<int>(s.keep.size()),
                                         static_cast<int>(s.spurs.size())});
  }
  double min_cost = INFINITY;
  double scale = 1.0;
  std::vector<std::pair<double, Scheme>> sized;
  for (const Scheme& s : allowed) {
    if (SchemeSize{static_cast<int>(s.keep.size()), static_cast<int>(s.spurs.size())} != r.size) {
      continue;
    }
    const double cost = weights.w.dot(SchemeFeatures(cands, policy, s));
    min_cost = std::min(min_cost, cost);
    scale = std::max(scale, std::abs(cost));
    sized.push_back({cost, s});
  }
  bool have = false;
  for (const auto& [cost, s] : sized) {
    if (cost > min_cost + 1e-9 * scale) continue;
    if (!have || s < r.best) r.best = s, r.cost = cost, have = true;
  }
  return r;
}

// Random candidates forming a forest (secondary canes name all their ancestors).
std::vector<Candidate> RandomCandidates(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<int> ids(n);
  for (int i = 0; i < n; ++i) ids[i] = 2 + 3 * i;
  std::shuffle(ids.begin(), ids.end(), rng);
  std::vector<Candidate> out;
  for (int i = 0; i < n; ++i) {
    Candidate c;
    c.id = CaneId(ids[i]);
    c.cane_index = i;
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
    c.angle_from_head_rad = std::numbers::pi * u(rng);
    c.wire_z_m = 0.95;
    const double side = u(rng);
    c.side = side < 0.45 ? -1 : (side < 0.9 ? 1 : 0);
    out.push_back(c);
  }
  return out;
}

SchemeWeights RandomWeights(std::mt19937& rng, double sigma = 2.0) {
  std::normal_distribution<double> g(0.0, sigma);
  SchemeWeights w;
  for (int f = 0; f < kSchemeFeatureCount; ++f) w.w[f] = g(rng);
  return w;
}

PruningPolicy RandomPolicy(std::mt19937& rng, int max_keep, int max_spurs) {
  PruningPolicy p;
  if (std::uniform_int_distribution<int>(0, 5)(rng) == 0) {
    p.style = PruningStyle::kSpur;
    p.canes_to_keep = 0;
    p.spurs = std::uniform_int_distribution<int>(1, max_spurs)(rng);
  } else {
    p.canes_to_keep = std::uniform_int_distribution<int>(1, max_keep)(rng);
    p.spurs = std::uniform_int_distribution<int>(0, max_spurs)(rng);
  }
  p.min_kept_length_m = 0.3;
  return p;
}

TEST(FindBestScheme, EqualsBruteForceOnRandomSetsAndSignedWeights) {
  std::mt19937 rng(4242);
  int nonempty = 0;
  int shrunk = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = std::uniform_int_distribution<int>(0, 9)(rng);
    const std::vector<Candidate> cands = RandomCandidates(rng, n);
    const PruningPolicy policy = RandomPolicy(rng, 4, 3);
    // Small weights make near-ties, where a bound that is off by a little would show.
    const SchemeWeights weights = RandomWeights(rng, trial % 2 == 0 ? 2.0 : 0.1);
    const BruteResult brute = BruteForce(cands, policy, weights);
    SCOPED_TRACE(::testing::Message() << "trial " << trial << " n " << n);
    EXPECT_EQ(FeasibleSchemeSize(cands, policy), brute.size);
    SearchStats stats;
    auto best = FindBestScheme(cands, policy, weights, Deadline::Infinite(), &stats);
    ASSERT_TRUE(best.ok()) << best.status();
    EXPECT_EQ(best->keep, brute.best.keep);
    EXPECT_EQ(best->spurs, brute.best.spurs);
    EXPECT_NEAR(stats.best_cost, brute.cost, 1e-9 * (1 + std::abs(brute.cost)));
    EXPECT_TRUE(IsFeasible(cands, policy, *best));
    EXPECT_EQ(stats.candidates, n);
    nonempty += !best->keep.empty() || !best->spurs.empty();
    const int keep_max = policy.style == PruningStyle::kSpur ? 0 : policy.canes_to_keep;
    shrunk += brute.size.keep < keep_max;
  }
  EXPECT_GT(nonempty, 200);  // the comparison is not vacuous
  EXPECT_GT(shrunk, 10);     // nor always at the policy's full size
}

TEST(FindBestScheme, EqualsBruteForceWithUpToSixKeptOrSpurred) {
  std::mt19937 rng(777);
  for (int trial = 0; trial < 25; ++trial) {
    const std::vector<Candidate> cands = RandomCandidates(rng, 11);
    PruningPolicy policy = RandomPolicy(rng, 6, 6);
    const SchemeWeights weights = RandomWeights(rng);
    const BruteResult brute = BruteForce(cands, policy, weights);
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    auto best = FindBestScheme(cands, policy, weights);
    ASSERT_TRUE(best.ok()) << best.status();
    EXPECT_EQ(*best, brute.best);
  }
}

// Larger sets cannot be enumerated; the optimum must at least survive every single exchange
// (a kept or spurred cane swapped for another candidate, or the roles of two swapped).
TEST(FindBestScheme, NoSingleExchangeImprovesOnThirtyCandidates) {
  std::mt19937 rng(99);
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<Candidate> cands = RandomCandidates(rng, 30);
    PruningPolicy policy;
    policy.canes_to_keep = 6;
    policy.spurs = 6;
    const SchemeWeights weights = trial % 2 == 0 ? DefaultSchemeWeights() : RandomWeights(rng);
    auto best = FindBestScheme(cands, policy, weights);
    ASSERT_TRUE(best.ok()) << best.status();
    ASSERT_TRUE(IsFeasible(cands, policy, *best));
    const double cost = weights.w.dot(SchemeFeatures(cands, policy, *best));
    int tried = 0;
    auto check = [&](Scheme s) {
      std::sort(s.keep.begin(), s.keep.end());
      std::sort(s.spurs.begin(), s.spurs.end());
      if (!IsFeasible(cands, policy, s)) return;
      ++tried;
      EXPECT_GE(weights.w.dot(SchemeFeatures(cands, policy, s)), cost - 1e-9);
    };
    for (const Candidate& c : cands) {
      for (size_t k = 0; k < best->keep.size(); ++k) {
        Scheme s = *best;
        s.keep[k] = c.id;
        check(s);
      }
      for (size_t k = 0; k < best->spurs.size(); ++k) {
        Scheme s = *best;
        s.spurs[k] = c.id;
        check(s);
      }
    }
    for (size_t k = 0; k < best->keep.size(); ++k) {
      for (size_t j = 0; j < best->spurs.size(); ++j) {
        Scheme s = *best;
        std::swap(s.keep[k], s.spurs[j]);
        check(s);
      }
    }
    EXPECT_GT(tried, 10);
  }
}

TEST(FindBestScheme, IsDeterministicAndIndependentOfCandidateOrder) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Candidate> cands = RandomCandidates(rng, 25);
    PruningPolicy policy;
    policy.canes_to_keep = 1 + trial % 6;
    policy.spurs = trial % 7;
    const SchemeWeights weights = RandomWeights(rng);
    auto first = FindBestScheme(cands, policy, weights);
    auto again = FindBestScheme(cands, policy, weights);
    std::shuffle(cands.begin(), cands.end(), rng);
    auto shuffled = FindBestScheme(cands, policy, weights);
    ASSERT_TRUE(first.ok() && again.ok() && shuffled.ok());
    EXPECT_EQ(*first, *again);
    EXPECT_EQ(*first, *shuffled);
  }
}

TEST(FindBestScheme, TiesGoToTheSmallestScheme) {
  // Identical canes: every scheme of the right size costs the same.
  std::vector<Candidate> cands;
  for (int id : {40, 12, 33, 7, 25, 18}) {
    Candidate c;
    c.id = CaneId(id);
    c.length_m = 1.0;
    c.base_diameter_m = 0.009;
    c.base_distance_from_head_m = 0.05;
    c.side = 1;
    cands.push_back(c);
  }
  PruningPolicy policy;
  policy.canes_to_keep = 2;
  policy.spurs = 3;
  auto best = FindBestScheme(cands, policy, DefaultSchemeWeights());
  ASSERT_TRUE(best.ok());
  EXPECT_EQ(best->keep, Ids({7, 12}));
  EXPECT_EQ(best->spurs, Ids({18, 25, 33}));
  // All-zero weights: everything ties, still the smallest scheme, and quickly.
  SearchStats stats;
  std::mt19937 rng(3);
  const std::vector<Candidate> many = RandomCandidates(rng, 30);
  policy.canes_to_keep = 6;
  policy.spurs = 6;
  auto zero = FindBestScheme(many, policy, SchemeWeights{}, Deadline::Infinite(), &stats);
  ASSERT_TRUE(zero.ok());
  const BruteResult brute_small = BruteForce(
      std::vector<Candidate>(many.begin(), many.begin() + 10), policy, SchemeWeights{});
  auto small = FindBestScheme(std::vector<Candidate>(many.begin(), many.begin() + 10), policy,
                              SchemeWeights{});
  ASSERT_TRUE(small.ok());
  EXPECT_EQ(*small, brute_small.best);
  EXPECT_LT(stats.schemes_visited, 100000);
}

TEST(FindBestScheme, TieBreakDoesNotDependOnWhichTieIsMetFirst) {
  // Keep costs (base distance, weight 1) 2: 0.5, 3: 0.5, 4: 0.25, 5: 0.75, with 2 and 3 growing
  // from 4. {4, 5} and {2, 3} both cost exactly 1.0; a cost-ordered search meets {4, 5} first.
  std::vector<Candidate> cands(4);
  const int ids[] = {2, 3, 4, 5};
  const double distance[] = {0.5, 0.5, 0.25, 0.75};
  for (int i = 0; i < 4; ++i) {
    cands[i].id = CaneId(ids[i]);
    cands[i].length_m = 1.0;
    cands[i].base_distance_from_head_m = distance[i];
    cands[i].side = 1;
  }
  cands[0].ancestors = Ids({4});
  cands[1].ancestors = Ids({4});
  PruningPolicy policy;
  policy.canes_to_keep = 2;
  policy.spurs = 0;
  SchemeWeights w;
  w.w[kKeepBaseDistanceM] = 1.0;
  auto best = FindBestScheme(cands, policy, w);
  ASSERT_TRUE(best.ok());
  EXPECT_EQ(best->keep, Ids({2, 3}));
  EXPECT_EQ(*best, BruteForce(cands, policy, w).best);
}

TEST(FindBestScheme, PrefersWhatTheWeightsSay) {
  // Two canes each side; with imbalance weight the cheapest two are split one per side.
  std::vector<Candidate> cands;
  const double costs[] = {0.1, 0.2, 0.3, 0.4};
  const int sides[] = {-1, -1, 1, 1};
  for (int i = 0; i < 4; ++i) {
    Candidate c;
    c.id = CaneId(i + 2);
    c.length_m = 1.0;
    c.base_diameter_m = 0.009;
    c.base_distance_from_head_m = costs[i];
    c.side = sides[i];
    cands.push_back(c);
  }
  PruningPolicy policy;
  policy.canes_to_keep = 2;
  policy.spurs = 0;
  SchemeWeights w;
  w.w[kKeepBaseDistanceM] = 1.0;
  auto nearest = FindBestScheme(cands, policy, w);
  ASSERT_TRUE(nearest.ok());
  EXPECT_EQ(nearest->keep, Ids({2, 3}));  // both left: 0.1 + 0.2
  w.w[kImbalance] = 1.0;
  auto balanced = FindBestScheme(cands, policy, w);
  ASSERT_TRUE(balanced.ok());
  EXPECT_EQ(balanced->keep, Ids({2, 4}));  // 0.1 + 0.3, balanced
  w.w[kImbalance] = -1.0;                  // a (learned) preference for one-sidedness
  w.w[kKeepBaseDistanceM] = -1.0;          // and for far canes
  auto odd = FindBestScheme(cands, policy, w);
  ASSERT_TRUE(odd.ok());
  EXPECT_EQ(odd->keep, Ids({4, 5}));
}

TEST(FindBestScheme, RejectsBadInputAndHonoursTheDeadline) {
  std::mt19937 rng(1);
  std::vector<Candidate> cands = RandomCandidates(rng, 8);
  const PruningPolicy policy;
  SchemeWeights w = DefaultSchemeWeights();
  w.w[kKeepAngleRad] = NAN;
  EXPECT_THAT(FindBestScheme(cands, policy, w).status().message(),
              HasSubstr("weights.keep_angle_rad: not finite"));
  PruningPolicy bad;
  bad.canes_to_keep = 8;
  EXPECT_THAT(FindBestScheme(cands, bad, DefaultSchemeWeights()).status().message(),
              HasSubstr("policy.canes_to_keep"));
  std::vector<Candidate> dup = cands;
  dup[3].id = dup[5].id;
  EXPECT_THAT(FindBestScheme(dup, policy, DefaultSchemeWeights()).status().message(),
              HasSubstr("candidates[5]: duplicate cane id"));
  EXPECT_EQ(FindBestScheme(cands, policy, DefaultSchemeWeights(), Deadline::In(0.0)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  std::atomic<bool> cancelled{true};
  EXPECT_EQ(FindBestScheme(cands, policy, DefaultSchemeWeights(), Deadline::In(60, &cancelled))
                .status()
                .code(),
            absl::StatusCode::kCancelled);
  auto none = FindBestScheme({}, policy, DefaultSchemeWeights());
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->keep.empty() && none->spurs.empty());
}

// ---------------------------------------------------------------------------------------------
// Feasibility.

std::vector<Candidate> Family() {
  // 2 <- 3 <- 4 (a secondary and a tertiary cane), 5 and 6 from the head; 6 is short.
  std::vector<Candidate> cands(5);
  const int ids[] = {2, 3, 4, 5, 6};
  for (int i = 0; i < 5; ++i) {
    cands[i].id = CaneId(ids[i]);
    cands[i].length_m = 1.0;
    cands[i].side = i % 2 == 0 ? -1 : 1;
  }
  cands[1].ancestors = Ids({2});
  cands[2].ancestors = Ids({3, 2});
  cands[4].length_m = 0.2;
  return cands;
}

TEST(IsFeasible, AppliesEveryRule) {
  const std::vector<Candidate> cands = Family();
  PruningPolicy policy;
  policy.canes_to_keep = 2;
  policy.spurs = 1;
  EXPECT_EQ(FeasibleSchemeSize(cands, policy), (SchemeSize{2, 1}));
  EXPECT_TRUE(IsFeasible(cands, policy, {Ids({2, 5}), Ids({6})}));
  EXPECT_TRUE(IsFeasible(cands, policy, {Ids({5, 4}), Ids({6})}));  // order does not matter
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 5}), {}}));        // too few spurs
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2}), Ids({6})}));     // too few kept
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 6}), Ids({5})}));  // 6 is too short to keep
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 3}), Ids({6})}));  // 3 grows from 2
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({4, 5}), Ids({2})}));  // 4 from spur 2
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 5}), Ids({5})}));  // kept and spurred
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 2}), Ids({6})}));  // listed twice
  EXPECT_FALSE(IsFeasible(cands, policy, {Ids({2, 9}), Ids({6})}));  // not a candidate
}

TEST(FeasibleSchemeSize, ShrinksWhenAncestryForbidsThePolicySize) {
  std::vector<Candidate> cands = Family();
  cands.erase(cands.begin() + 3);  // only 2, 3, 4 (one line of descent) and short 6 remain
  PruningPolicy policy;
  policy.canes_to_keep = 2;
  policy.spurs = 2;
  EXPECT_EQ(FeasibleSchemeSize(cands, policy), (SchemeSize{1, 1}));
  auto best = FindBestScheme(cands, policy, DefaultSchemeWeights());
  ASSERT_TRUE(best.ok());
  EXPECT_EQ(best->keep.size(), 1u);
  EXPECT_THAT(best->spurs, ElementsAre(CaneId(6)));
  policy.style = PruningStyle::kSpur;
  policy.canes_to_keep = 0;
  policy.spurs = 12;
  EXPECT_EQ(FeasibleSchemeSize(cands, policy), (SchemeSize{0, 2}));
  EXPECT_EQ(FeasibleSchemeSize({}, policy), (SchemeSize{0, 0}));
}

}  // namespace
}  // namespace vb::decide
