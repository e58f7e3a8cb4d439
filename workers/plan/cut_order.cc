// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/cut_order.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vb::plan {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kHeldKarpCap = 20;
constexpr int kRandomRestarts = 8;

// min_j (prev[j] + in[j]), the inner loop of Held-Karp. A minimum is exact in any order (every
// sum here is a number: Sanitised costs and +infinity), so two lanes and two accumulators give
// the scalar loop's result bit for bit; GCC does not vectorise a floating-point min reduction
// on its own.
double MinSum(const double* prev, const double* in, int n) {
  int j = 0;
  double m = kInf;
#if defined(__SSE2__)
  __m128d m0 = _mm_set1_pd(kInf), m1 = m0;
  for (; j + 4 <= n; j += 4) {
    m0 = _mm_min_pd(m0, _mm_add_pd(_mm_loadu_pd(prev + j), _mm_loadu_pd(in + j)));
    m1 = _mm_min_pd(m1, _mm_add_pd(_mm_loadu_pd(prev + j + 2), _mm_loadu_pd(in + j + 2)));
  }
  double lanes[2];
  _mm_storeu_pd(lanes, _mm_min_pd(m0, m1));
  m = std::min(lanes[0], lanes[1]);
#endif
  for (; j < n; ++j) m = std::min(m, prev[j] + in[j]);
  return m;
}

bool Square(const Eigen::MatrixXd& cost) { return cost.rows() >= 1 && cost.rows() == cost.cols(); }

// Unusable moves (inf, NaN) become one large finite cost, larger than any path of usable
// moves, so that the searches below compare sums without inf - inf; the reported cost is
// always recomputed on the original matrix.
Eigen::MatrixXd Sanitised(const Eigen::MatrixXd& cost) {
  double finite_sum = 0.0;
  for (Eigen::Index i = 0; i < cost.size(); ++i) {
    const double c = cost.data()[i];
    if (std::isfinite(c)) finite_sum += std::abs(c);
  }
  const double big = 10.0 * (finite_sum + 1.0);
  Eigen::MatrixXd out = cost;
  for (Eigen::Index i = 0; i < out.size(); ++i) {
    if (!std::isfinite(out.data()[i])) out.data()[i] = big;
  }
  return out;
}

OrderResult Invalid() { return OrderResult{{}, std::numeric_limits<double>::quiet_NaN(), false}; }

OrderResult Trivial(const Eigen::MatrixXd& cost, bool return_to_start) {
  OrderResult r;
  if (cost.rows() == 2) r.order = {1};
  r.cost = OrderCost(cost, r.order, return_to_start);
  r.exact = true;
  return r;
}

std::vector<int> NearestNeighbour(const Eigen::MatrixXd& c) {
  const int n = static_cast<int>(c.rows()) - 1;
  std::vector<int> order;
  std::vector<bool> visited(n + 1, false);
  int at = 0;
  for (int step = 0; step < n; ++step) {
    int best = -1;
    for (int j = 1; j <= n; ++j) {
      if (!visited[j] && (best < 0 || c(at, j) < c(at, best))) best = j;
    }
    visited[best] = true;
    order.push_back(best);
    at = best;
  }
  return order;
}

// Cost of the node sequence seq (seq[0] = 0; with return_to_start the caller appends 0).
double SequenceCost(const Eigen::MatrixXd& c, const std::vector<int>& seq) {
  double total = 0.0;
  for (size_t k = 0; k + 1 < seq.size(); ++k) total += c(seq[k], seq[k + 1]);
  return total;
}

// 2-opt and Or-opt to a local optimum, best improvement per pass. seq = 0, cuts..., [0]; the
// first node and (with return_to_start) the last stay in place. Deltas are O(1) from prefix sums
// of the forward and backward edge costs, so asymmetric costs are handled exactly.
void LocalSearch(const Eigen::MatrixXd& c, bool return_to_start, std::vector<int>& seq) {
  const int last = static_cast<int>(seq.size()) - 1;          // index of the last node
  const int last_movable = return_to_start ? last - 1 : last;  // cuts are 1..last_movable
  std::vector<double> fwd(seq.size(), 0.0), bwd(seq.size(), 0.0);
  for (int pass = 0; pass < 10000; ++pass) {
    for (int k = 1; k <= last; ++k) {
      fwd[k] = fwd[k - 1] + c(seq[k - 1], seq[k]);
      bwd[k] = bwd[k - 1] + c(seq[k], seq[k - 1]);
    }
    const double scale = 1e-12 * (1.0 + std::abs(fwd[last]));
    auto edge = [&](int a, int b) { return (b > last) ? 0.0 : c(seq[a], seq[b]); };
    double best_delta = -scale;
    int kind = 0, bi = 0, bj = 0, bl = 0;
    // 2-opt: reverse seq[i..j].
    for (int i = 1; i < last_movable; ++i) {
      for (int j = i + 1; j <= last_movable; ++j) {
        const bool tail = j + 1 <= last;
        const double before = c(seq[i - 1], seq[i]) + (fwd[j] - fwd[i]) +
                              (tail ? c(seq[j], seq[j + 1]) : 0.0);
        const double after = c(seq[i - 1], seq[j]) + (bwd[j] - bwd[i]) +
                             (tail ? c(seq[i], seq[j + 1]) : 0.0);
        if (after - before < best_delta) {
          best_delta = after - before;
          kind = 1, bi = i, bj = j;
        }
      }
    }
    // Or-opt: move the run seq[i..i+len-1] to between seq[k] and seq[k+1].
    for (int len = 1; len <= 3; ++len) {
      for (int i = 1; i + len - 1 <= last_movable; ++i) {
        const int e = i + len - 1;
        const double removed = c(seq[i - 1], seq[i]) + edge(e, e + 1) - edge(i - 1, e + 1);
        for (int k = 0; k <= last_movable; ++k) {
          if (k >= i - 1 && k <= e) continue;
          const double inserted = c(seq[k], seq[i]) + edge(e, k + 1) - edge(k, k + 1);
          const double delta = inserted - removed;
          if (delta < best_delta) {
            best_delta = delta;
            kind = 2, bi = i, bj = k, bl = len;
          }
        }
      }
    }
    if (kind == 0) return;
    if (kind == 1) {
      std::reverse(seq.begin() + bi, seq.begin() + bj + 1);
    } else {
      std::vector<int> run(seq.begin() + bi, seq.begin() + bi + bl);
      seq.erase(seq.begin() + bi, seq.begin() + bi + bl);
      const int at = bj < bi ? bj + 1 : bj + 1 - bl;  // position after seq[k] once the run is out
      seq.insert(seq.begin() + at, run.begin(), run.end());
    }
  }
}

std::vector<int> ToSequence(const std::vector<int>& order, bool return_to_start) {
  std::vector<int> seq = {0};
  seq.insert(seq.end(), order.begin(), order.end());
  if (return_to_start) seq.push_back(0);
  return seq;
}

std::vector<int> FromSequence(const std::vector<int>& seq, bool return_to_start) {
  return std::vector<int>(seq.begin() + 1, seq.end() - (return_to_start ? 1 : 0));
}

}  // namespace

double OrderCost(const Eigen::MatrixXd& cost, const std::vector<int>& order, bool return_to_start) {
  if (!Square(cost)) return std::numeric_limits<double>::quiet_NaN();
  const int n = static_cast<int>(cost.rows()) - 1;
  double total = 0.0;
  int at = 0;
  auto add = [&](double c) { total += std::isnan(c) ? kInf : c; };
  for (int node : order) {
    if (node < 1 || node > n) return std::numeric_limits<double>::quiet_NaN();
    add(cost(at, node));
    at = node;
  }
  if (return_to_start && !order.empty()) add(cost(at, 0));
  return total;
}

OrderResult NearestNeighbourOrder(const Eigen::MatrixXd& cost, bool return_to_start) {
  if (!Square(cost)) return Invalid();
  if (cost.rows() <= 2) return Trivial(cost, return_to_start);
  OrderResult r;
  r.order = NearestNeighbour(Sanitised(cost));
  r.cost = OrderCost(cost, r.order, return_to_start);
  return r;
}

OrderResult HeuristicOrder(const Eigen::MatrixXd& cost, bool return_to_start) {
  if (!Square(cost)) return Invalid();
  if (cost.rows() <= 2) return Trivial(cost, return_to_start);
  const Eigen::MatrixXd c = Sanitised(cost);
  std::vector<int> best = ToSequence(NearestNeighbour(c), return_to_start);
  LocalSearch(c, return_to_start, best);
  double best_cost = SequenceCost(c, best);
  std::mt19937_64 rng(20250101);
  std::vector<int> order(cost.rows() - 1);
  for (int restart = 0; restart < kRandomRestarts; ++restart) {
    std::iota(order.begin(), order.end(), 1);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<int> seq = ToSequence(order, return_to_start);
    LocalSearch(c, return_to_start, seq);
    const double seq_cost = SequenceCost(c, seq);
    if (seq_cost < best_cost) best_cost = seq_cost, best = seq;
  }
  OrderResult r;
  r.order = FromSequence(best, return_to_start);
  r.cost = OrderCost(cost, r.order, return_to_start);
  return r;
}

OrderResult HeldKarpOrder(const Eigen::MatrixXd& cost, bool return_to_start) {
  if (!Square(cost)) return Invalid();
  if (cost.rows() <= 2) return Trivial(cost, return_to_start);
  const int n = static_cast<int>(cost.rows()) - 1;
  if (n > kHeldKarpCap) return HeuristicOrder(cost, return_to_start);
  const Eigen::MatrixXd c = Sanitised(cost);
  // best[mask * n + j]: cheapest path from node 0 through the cuts in mask (bit j = node j + 1),
  // ending at node j + 1; +infinity when j is not in mask. Computed by pulling from the mask
  // without j: the inner loop runs over every previous end j' without branches (absent ones are
  // +infinity) and over contiguous costs, so the compiler can vectorise it. Predecessors are not
  // stored; they are recovered at the end by finding the same sum again.
  const uint32_t full = (1u << n) - 1;
  std::vector<double> best(static_cast<size_t>(full + 1) * n, kInf);
  // into[k * n + j] = c(j + 1, k + 1): the moves into cut k, contiguous over j.
  std::vector<double> into(static_cast<size_t>(n) * n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) into[k * n + j] = c(j + 1, k + 1);
  }
  for (int k = 0; k < n; ++k) best[(1u << k) * n + k] = c(0, k + 1);
  for (uint32_t mask = 1; mask <= full; ++mask) {
    if ((mask & (mask - 1)) == 0) continue;  // singletons are set above
    double* out = &best[static_cast<size_t>(mask) * n];
    for (uint32_t bits = mask; bits != 0; bits &= bits - 1) {
      const int k = std::countr_zero(bits);
      const double* prev = &best[static_cast<size_t>(mask & ~(1u << k)) * n];
      const double* in = &into[static_cast<size_t>(k) * n];
      out[k] = MinSum(prev, in, n);
    }
  }
  auto total = [&](int j) {
    return best[static_cast<size_t>(full) * n + j] + (return_to_start ? c(j + 1, 0) : 0.0);
  };
  int end = 0;
  for (int j = 1; j < n; ++j) {
    if (total(j) < total(end)) end = j;
  }
  OrderResult r;
  uint32_t mask = full;
  for (int k = end;;) {
    r.order.push_back(k + 1);
    const double here = best[static_cast<size_t>(mask) * n + k];
    mask &= ~(1u << k);
    if (mask == 0) break;
    // The predecessor attains the minimum: the same sum, recomputed bit for bit.
    int from = -1;
    for (int j = 0; j < n && from < 0; ++j) {
      if ((mask & (1u << j)) && best[static_cast<size_t>(mask) * n + j] + into[k * n + j] == here) {
        from = j;
      }
    }
    k = from >= 0 ? from : std::countr_zero(mask);  // (always found; guards the index)
  }
  std::reverse(r.order.begin(), r.order.end());
  r.cost = OrderCost(cost, r.order, return_to_start);
  r.exact = true;
  return r;
}

OrderResult OrderCuts(const Eigen::MatrixXd& cost, bool return_to_start) {
  if (!Square(cost)) return Invalid();
  if (cost.rows() - 1 <= kMaxExactCuts) return HeldKarpOrder(cost, return_to_start);
  return HeuristicOrder(cost, return_to_start);
}

namespace {

double Usable(double c) { return std::isnan(c) ? std::numeric_limits<double>::infinity() : c; }

}  // namespace

ChoiceResult ChooseAlongOrder(const std::vector<Eigen::MatrixXd>& transition) {
  ChoiceResult r;
  if (transition.empty()) {
    r.choice = {0};
    return r;
  }
  const size_t layers = transition.size() + 1;
  for (size_t l = 0; l < transition.size(); ++l) {
    if (transition[l].size() == 0 ||
        (l + 1 < transition.size() && transition[l + 1].rows() != transition[l].cols())) {
      r.cost = std::numeric_limits<double>::quiet_NaN();
      return r;
    }
  }
  // Backward: value[l](a) = the cheapest cost from layer l's option a to the last layer.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::VectorXd> value(layers);
  std::vector<std::vector<int>> next(layers);
  value[layers - 1] = Eigen::VectorXd::Zero(transition.back().cols());
  for (size_t l = layers - 1; l-- > 0;) {
    const Eigen::MatrixXd& t = transition[l];
    value[l] = Eigen::VectorXd::Constant(t.rows(), inf);
    next[l].assign(t.rows(), 0);
    for (int a = 0; a < t.rows(); ++a) {
      for (int b = 0; b < t.cols(); ++b) {
        const double v = Usable(t(a, b)) + value[l + 1](b);
        if (v < value[l](a)) {
          value[l](a) = v;
          next[l][a] = b;
        }
      }
    }
  }
  int at = 0;
  for (int a = 1; a < value[0].size(); ++a)
    if (value[0](a) < value[0](at)) at = a;
  r.cost = value[0](at);
  r.choice.push_back(at);
  for (size_t l = 0; l + 1 < layers; ++l) {
    at = next[l][at];
    r.choice.push_back(at);
  }
  for (int b = 0; b < transition[0].cols(); ++b)
    r.first_costs.push_back(Usable(transition[0](r.choice[0], b)) + value[1](b));
  return r;
}

OrderChoiceResult OrderAndChoose(const std::vector<int>& option_counts, const MoveCost& move_cost,
                                 bool return_to_start, int rounds) {
  const int n = static_cast<int>(option_counts.size());
  std::vector<int> count = {1};
  count.insert(count.end(), option_counts.begin(), option_counts.end());
  // pair[i * (n + 1) + j]: node i's options x node j's options.
  std::vector<Eigen::MatrixXd> pair((n + 1) * (n + 1));
  for (int i = 0; i <= n; ++i) {
    for (int j = return_to_start ? 0 : 1; j <= n; ++j) {
      if (i == j) continue;
      Eigen::MatrixXd& m = pair[i * (n + 1) + j];
      m.resize(count[i], count[j]);
      for (int a = 0; a < count[i]; ++a)
        for (int b = 0; b < count[j]; ++b) m(a, b) = Usable(move_cost(i, a, j, b));
    }
  }
  auto matrix = [&](const std::vector<int>* choice) {
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n + 1, n + 1);
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const Eigen::MatrixXd& m = pair[i * (n + 1) + j];
        if (m.size() == 0) continue;
        c(i, j) = choice ? m((*choice)[i], (*choice)[j]) : m.minCoeff();
      }
    }
    return c;
  };
  auto choose = [&](const std::vector<int>& order) {
    std::vector<Eigen::MatrixXd> transition;
    int at = 0;
    for (int node : order) {
      transition.push_back(pair[at * (n + 1) + node]);
      at = node;
    }
    if (return_to_start && !order.empty()) transition.push_back(pair[at * (n + 1)]);
    const ChoiceResult chosen = ChooseAlongOrder(transition);
    std::vector<int> choice(n + 1, 0);
    for (size_t k = 0; k < order.size(); ++k) choice[order[k]] = chosen.choice[k + 1];
    return std::pair{choice, chosen.cost};
  };

  OrderChoiceResult best;
  best.cost = std::numeric_limits<double>::infinity();
  best.choice.assign(n + 1, 0);
  best.exact_order = true;
  const std::vector<int> first_options(n + 1, 0);
  for (const std::vector<int>* start : {static_cast<const std::vector<int>*>(nullptr),
                                        &first_options}) {
    Eigen::MatrixXd c = matrix(start);
    double previous = std::numeric_limits<double>::infinity();
    for (int round = 0; round < std::max(rounds, 1); ++round) {
      const OrderResult order = OrderCuts(c, return_to_start);
      auto [choice, cost] = choose(order.order);
      best.exact_order = best.exact_order && order.exact;
      if (cost < best.cost || best.order.empty()) {
        best.order = order.order;
        best.choice = choice;
        best.cost = cost;
      }
      // With the options fixed, the next exact order costs at most this; stop when it stops
      // paying (or when nothing is usable).
      if (!(cost < previous - 1e-12 * (1.0 + std::abs(cost)))) break;
      previous = cost;
      c = matrix(&choice);
    }
  }
  return best;
}

}  // namespace vb::plan
