// SPDX-License-Identifier: Apache-2.0
// Exact search for the cheapest pruning scheme: depth-first branch and bound (Land & Doig 1960)
// over "which canes to keep", then, under each complete choice, "which canes to leave as spurs".
//
// The cost of a scheme is sum_keep a_i + sum_spurs b_j + w_imb |left - right|, where a_i and b_j
// are the per-cane costs w . KeepFeatures and w . SpurFeatures. A node fixes a prefix of the
// branching order; the rest must supply exactly rk more kept canes and rs spurs. Its lower bound
// relaxes the ancestry rules and the keep/spur exclusivity among the undecided candidates:
//   partial cost
//   + min over (x left, y right, z neutral; x + y + z = rk) of the x, y, z cheapest still-keepable
//     canes per side + w_imb |left + x - right - y|   (exact for the relaxation, any weight sign,
//     because the count is fixed: the cheapest k of a set are its k smallest values)
//   + the rs cheapest spur costs among canes still free to be spurs.
// Pass 1 branches in cost order (a good scheme early, so strong pruning) and prunes nodes that
// cannot beat the incumbent; pass 2 branches in id order and stops at the first scheme within the
// tie tolerance of pass 1's minimum: in id order, schemes are met smallest first, so that is the
// tie-break of the contract, whatever order the candidates came in.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/decide/scheme.h"

namespace vb::decide {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTieTolerance = 1e-9;   // relative to the cost scale; see scheme.h
constexpr double kPruneSlack = 1e-12;    // relative; far above rounding, far below ties
constexpr long long kDeadlinePollNodes = 256;

enum Role : char { kNone = 0, kKept = 1, kSpurred = 2 };

// What the search needs of the candidates, by candidate index.
struct Problem {
  int n = 0;
  std::vector<double> keep_cost;
  std::vector<double> spur_cost;
  std::vector<char> long_enough;
  std::vector<int> pool;                   // 0 left, 1 right, 2 neither side
  std::vector<std::vector<int>> related;   // ancestors and descendants among candidates
  std::vector<int> by_keep_cost;           // indices by (keep cost, id)
  std::vector<int> by_spur_cost;           // indices by (spur cost, id)
  std::vector<int> by_id;
  int pool_size[3] = {0, 0, 0};
  double imbalance_weight = 0.0;
  SchemeSize size;
  double scale = 1.0;                      // magnitude of any cost, for tolerances
};

class Search {
 public:
  Search(const Problem& problem, const std::vector<Candidate>& candidates,
         const PruningPolicy& policy, const SchemeWeights& weights, const Deadline& deadline)
      : p_(problem), candidates_(candidates), policy_(policy), weights_(weights),
        deadline_(deadline), role_(p_.n, kNone), blocked_(p_.n, 0), keep_pos_(p_.n),
        spur_pos_(p_.n) {}

  // Pass 1: the minimum cost (kInf if there is no feasible scheme).
  void Minimise() {
    SetOrders(p_.by_keep_cost, p_.by_spur_cost);
    mode_ = Mode::kMinimise;
    Keep(0, p_.size.keep, 0.0);
  }

  // Pass 2: the first scheme in id order costing at most `target` + tolerance.
  void FindFirstWithin(double target) {
    SetOrders(p_.by_id, p_.by_id);
    mode_ = Mode::kFirstWithin;
    best_cost_ = target;
    found_ = false;
    Keep(0, p_.size.keep, 0.0);
  }

  bool stopped() const { return stopped_; }
  bool found() const { return found_; }
  double best_cost() const { return best_cost_; }
  const Scheme& best() const { return best_; }
  long long nodes() const { return nodes_; }

 private:
  enum class Mode { kMinimise, kFirstWithin };

  void SetOrders(const std::vector<int>& keep_order, const std::vector<int>& spur_order) {
    keep_order_ = &keep_order;
    spur_order_ = &spur_order;
    for (int t = 0; t < p_.n; ++t) {
      keep_pos_[keep_order[t]] = t;
      spur_pos_[spur_order[t]] = t;
    }
  }

  bool Explore(double bound) const {
    if (mode_ == Mode::kMinimise) return bound < best_cost_ - kPruneSlack * p_.scale;
    return bound <= best_cost_ + kTieTolerance * p_.scale;
  }

  // Counts a node; false once the search must unwind (deadline, or pass 2 has its answer).
  bool Enter() {
    if (++nodes_ % kDeadlinePollNodes == 0 && deadline_.Expired()) stopped_ = true;
    return !Halted();
  }
  bool Halted() const { return stopped_ || (mode_ == Mode::kFirstWithin && found_); }

  bool CanKeep(int i) const { return role_[i] == kNone && blocked_[i] == 0 && p_.long_enough[i]; }
  bool CanSpur(int i) const { return role_[i] == kNone && blocked_[i] == 0; }

  void Take(int i, Role role) {
    role_[i] = role;
    for (int j : p_.related[i]) ++blocked_[j];
    if (role == kKept) {
      ++kept_in_pool_[p_.pool[i]];
      kept_.push_back(i);
    } else {
      spurred_.push_back(i);
    }
  }

  void Drop(int i) {
    for (int j : p_.related[i]) --blocked_[j];
    if (role_[i] == kKept) {
      --kept_in_pool_[p_.pool[i]];
      kept_.pop_back();
    } else {
      spurred_.pop_back();
    }
    role_[i] = kNone;
  }

  double Imbalance(int left, int right) const {
    return p_.imbalance_weight * std::abs(left - right);
  }

  // Least cost of rk more kept canes from branching positions >= t, imbalance term included.
  double KeepCompletion(int t, int rk) const {
    double prefix[3][7];  // prefix[pool][m]: the m cheapest of that pool (rk <= 6)
    int got[3] = {0, 0, 0};
    int need[3];
    for (int k = 0; k < 3; ++k) {
      prefix[k][0] = 0.0;
      need[k] = std::min(rk, p_.pool_size[k]);
    }
    const bool sorted_order = keep_order_ == &p_.by_keep_cost;
    for (int u = sorted_order ? t : 0; u < p_.n; ++u) {
      if (got[0] == need[0] && got[1] == need[1] && got[2] == need[2]) break;
      const int i = p_.by_keep_cost[u];
      if (keep_pos_[i] < t || !CanKeep(i)) continue;
      const int k = p_.pool[i];
      if (got[k] == need[k]) continue;
      prefix[k][got[k] + 1] = prefix[k][got[k]] + p_.keep_cost[i];
      ++got[k];
    }
    double best = kInf;
    for (int x = 0; x <= got[0]; ++x) {
      for (int y = 0; y <= got[1] && x + y <= rk; ++y) {
        const int z = rk - x - y;
        if (z > got[2]) continue;
        const double v = prefix[0][x] + prefix[1][y] + prefix[2][z] +
                         Imbalance(kept_in_pool_[0] + x, kept_in_pool_[1] + y);
        best = std::min(best, v);
      }
    }
    return best;
  }

  // Least cost of rs more spurs from spur-branching positions >= t (all positions if t < 0).
  double SpurCompletion(int t, int rs) const {
    double sum = 0.0;
    int got = 0;
    const bool sorted_order = spur_order_ == &p_.by_spur_cost;
    for (int u = (sorted_order && t > 0) ? t : 0; u < p_.n && got < rs; ++u) {
      const int i = p_.by_spur_cost[u];
      if ((t >= 0 && spur_pos_[i] < t) || !CanSpur(i)) continue;
      sum += p_.spur_cost[i];
      ++got;
    }
    return got == rs ? sum : kInf;
  }

  void Keep(int q, int rk, double partial) {
    if (!Enter()) return;
    if (rk == 0) {
      Spur(0, p_.size.spurs, partial + Imbalance(kept_in_pool_[0], kept_in_pool_[1]));
      return;
    }
    // Spurs are drawn from canes not kept; more keeps only shrink that set, so this stays a bound.
    const double spurs_bound = SpurCompletion(-1, p_.size.spurs);
    for (int t = q; t < p_.n; ++t) {
      if (!Explore(partial + KeepCompletion(t, rk) + spurs_bound)) return;
      const int i = (*keep_order_)[t];
      if (!CanKeep(i)) continue;
      Take(i, kKept);
      Keep(t + 1, rk - 1, partial + p_.keep_cost[i]);
      Drop(i);
      if (Halted()) return;
    }
  }

  void Spur(int q, int rs, double partial) {
    if (!Enter()) return;
    if (rs == 0) {
      Leaf(partial);
      return;
    }
    for (int t = q; t < p_.n; ++t) {
      if (!Explore(partial + SpurCompletion(t, rs))) return;
      const int i = (*spur_order_)[t];
      if (!CanSpur(i)) continue;
      Take(i, kSpurred);
      Spur(t + 1, rs - 1, partial + p_.spur_cost[i]);
      Drop(i);
      if (Halted()) return;
    }
  }

  void Leaf(double partial) {
    if (!Explore(partial)) return;
    // The accumulated cost depends on summation order; decisions use the canonical cost, the
    // same number SchemeFeatures gives any caller.
    Scheme scheme;
    for (int i : kept_) scheme.keep.push_back(candidates_[i].id);
    for (int i : spurred_) scheme.spurs.push_back(candidates_[i].id);
    std::sort(scheme.keep.begin(), scheme.keep.end());
    std::sort(scheme.spurs.begin(), scheme.spurs.end());
    const double cost = weights_.w.dot(SchemeFeatures(candidates_, policy_, scheme));
    if (mode_ == Mode::kMinimise) {
      if (cost < best_cost_) {
        best_cost_ = cost;
        best_ = std::move(scheme);
        found_ = true;
      }
    } else if (cost <= best_cost_ + kTieTolerance * p_.scale) {
      best_cost_ = cost;
      best_ = std::move(scheme);
      found_ = true;
    }
  }

  const Problem& p_;
  const std::vector<Candidate>& candidates_;
  const PruningPolicy& policy_;
  const SchemeWeights& weights_;
  const Deadline& deadline_;
  Mode mode_ = Mode::kMinimise;
  const std::vector<int>* keep_order_ = nullptr;
  const std::vector<int>* spur_order_ = nullptr;
  std::vector<char> role_;
  std::vector<int> blocked_;
  std::vector<int> keep_pos_;
  std::vector<int> spur_pos_;
  int kept_in_pool_[3] = {0, 0, 0};
  std::vector<int> kept_;
  std::vector<int> spurred_;
  double best_cost_ = kInf;
  Scheme best_;
  bool found_ = false;
  bool stopped_ = false;
  long long nodes_ = 0;
};

Problem MakeProblem(const std::vector<Candidate>& candidates, const PruningPolicy& policy,
                    const SchemeWeights& weights) {
  Problem p;
  p.n = static_cast<int>(candidates.size());
  p.size = FeasibleSchemeSize(candidates, policy);
  p.imbalance_weight = weights.w[kImbalance];
  p.related.resize(p.n);
  std::unordered_map<int64_t, int> index;
  for (int i = 0; i < p.n; ++i) index.emplace(candidates[i].id.value, i);
  double scale = 1.0 + std::abs(p.imbalance_weight) * p.size.keep;
  for (int i = 0; i < p.n; ++i) {
    const Candidate& c = candidates[i];
    const FeatureVector keep = KeepFeatures(c, policy);
    const FeatureVector spur = SpurFeatures(c, policy);
    p.keep_cost.push_back(weights.w.dot(keep));
    p.spur_cost.push_back(weights.w.dot(spur));
    scale += weights.w.cwiseProduct(keep).cwiseAbs().sum() +
             weights.w.cwiseProduct(spur).cwiseAbs().sum();
    p.long_enough.push_back(c.length_m >= policy.min_kept_length_m ? 1 : 0);
    const int pool = c.side < 0 ? 0 : (c.side > 0 ? 1 : 2);
    p.pool.push_back(pool);
    ++p.pool_size[pool];
    for (CaneId a : c.ancestors) {
      auto it = index.find(a.value);
      if (it == index.end()) continue;
      p.related[i].push_back(it->second);
      p.related[it->second].push_back(i);
    }
  }
  p.scale = scale;
  auto sorted = [&](const std::vector<double>* cost) {
    std::vector<int> order(p.n);
    for (int i = 0; i < p.n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int x, int y) {
      if (cost != nullptr && (*cost)[x] != (*cost)[y]) return (*cost)[x] < (*cost)[y];
      return candidates[x].id < candidates[y].id;
    });
    return order;
  };
  p.by_keep_cost = sorted(&p.keep_cost);
  p.by_spur_cost = sorted(&p.spur_cost);
  p.by_id = sorted(nullptr);
  return p;
}

}  // namespace

absl::StatusOr<Scheme> FindBestScheme(const std::vector<Candidate>& candidates,
                                      const PruningPolicy& policy, const SchemeWeights& weights,
                                      const Deadline& deadline, SearchStats* stats) {
  VB_RETURN_IF_ERROR(policy.Validate());
  VB_RETURN_IF_ERROR(weights.Validate());
  std::unordered_set<int64_t> ids;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (!ids.insert(candidates[i].id.value).second) {
      return absl::InvalidArgumentError(
          absl::StrCat("candidates[", i, "]: duplicate cane id ", candidates[i].id.value));
    }
  }
  VB_RETURN_IF_ERROR(deadline.Check("decide: scheme search"));
  const Problem problem = MakeProblem(candidates, policy, weights);
  Search search(problem, candidates, policy, weights, deadline);
  search.Minimise();
  const bool minimised = !search.stopped() && search.found();
  const Scheme minimum = search.best();
  if (minimised) search.FindFirstWithin(search.best_cost());
  if (stats != nullptr) {
    stats->schemes_visited = search.nodes();
    stats->candidates = problem.n;
    stats->best_cost = search.best_cost();
  }
  if (search.stopped()) return deadline.Check("decide: scheme search");
  // FeasibleSchemeSize promises a scheme of this size exists, so pass 1 finds one.
  if (!minimised) return absl::InternalError("decide: no feasible scheme found");
  // Pass 2 meets `minimum` itself if nothing smaller ties; rounding aside, it always finds one.
  return search.found() ? search.best() : minimum;
}

}  // namespace vb::decide
