// SPDX-License-Identifier: Apache-2.0
// The order in which to visit the cuts of one vine: a shortest open path (or tour) through all
// cuts from the arm's start configuration, on a cost matrix of move times (MoveTimeS between cut
// configurations, or planned path times). Exact up to kMaxExactCuts cuts by Held-Karp dynamic
// programming (Held & Karp 1962; Bellman 1962), O(n^2 2^n) time and O(n 2^n) memory: 15 cuts
// take a few milliseconds and 4 MB. Above that, a heuristic: nearest neighbour, then local
// search with 2-opt (segment reversal, Croes 1958) and Or-opt (moving runs of 1-3 cuts, Or
// 1976) to a local optimum, repeated from a few seeded random orders; the best is kept.
//
// Cost matrix: (n+1) x (n+1), node 0 is the start, nodes 1..n the cuts; cost(i, j) is the cost of
// going from i to j and may differ from cost(j, i). The diagonal is ignored. +infinity (or NaN)
// marks an unusable move: orders avoid them when they can, and their cost is then +infinity.
// Orders are lists of the cut nodes 1..n, each once, in visiting order (node 0 not included).
// Thread-safe (pure functions).
#pragma once

#include <functional>
#include <vector>

#include "Eigen/Core"

namespace vb::plan {

inline constexpr int kMaxExactCuts = 15;

struct OrderResult {
  std::vector<int> order;  // cut nodes 1..n in visiting order
  double cost = 0.0;       // OrderCost(cost, order, return_to_start)
  bool exact = false;      // true when order is optimal (Held-Karp, or n <= 1)
};

// Held-Karp for n <= kMaxExactCuts, HeuristicOrder above. An open path from node 0 unless
// return_to_start, which adds the move from the last cut back to node 0. A matrix that is not
// square, or empty, is a programmer error: the result is then an empty order with cost NaN.
OrderResult OrderCuts(const Eigen::MatrixXd& cost, bool return_to_start = false);

// The exact order by Held-Karp; n is capped at 20 (more needs too much memory: the result is then
// HeuristicOrder's).
OrderResult HeldKarpOrder(const Eigen::MatrixXd& cost, bool return_to_start = false);

// Nearest neighbour (from node 0, always the cheapest unvisited cut next; ties to the lower
// index) improved by 2-opt and Or-opt, also from 8 random orders (fixed seed); the cheapest.
// exact is false (unless n <= 1). O(n^2) per local-search pass.
OrderResult HeuristicOrder(const Eigen::MatrixXd& cost, bool return_to_start = false);

// Nearest neighbour alone (the baseline orders are compared with).
OrderResult NearestNeighbourOrder(const Eigen::MatrixXd& cost, bool return_to_start = false);

// Cost of visiting `order` from node 0 (and back to it if return_to_start). NaN if the matrix is
// not square or an entry of `order` is not in [1, n]; +infinity if a move used is unusable.
// Repeated or missing cuts are not detected here.
double OrderCost(const Eigen::MatrixXd& cost, const std::vector<int>& order,
                 bool return_to_start = false);

// Choice among each cut's options (its alternative motions) along a fixed order, by dynamic
// programming over the layers (Viterbi 1967; Bellman 1957): exact for that order. Layer 0 is
// the start; transition[l] is the (options of layer l) x (options of layer l+1) cost matrix.
// O(sum of the matrices' sizes).
struct ChoiceResult {
  std::vector<int> choice;   // one option per layer (choice[0] for the start layer too)
  double cost = 0.0;         // the sum of the chosen transitions; +infinity if all are unusable
  // Per option of layer 1: the cheapest total through it (from choice[0]); empty if only one
  // layer. Ranks the first move's options when the chosen one cannot be reached.
  std::vector<double> first_costs;
};
// Empty transitions: one layer of one option, cost 0. Matrices whose sizes do not chain (rows of
// transition[l+1] != columns of transition[l]), or a matrix with no entries, are programmer
// errors: the result is then empty with cost NaN. +infinity and NaN entries are unusable moves.
ChoiceResult ChooseAlongOrder(const std::vector<Eigen::MatrixXd>& transition);

// Order and option choice together. Node 0 (the start) has one option, node i in 1..n has
// option_counts[i - 1] >= 1; move_cost(i, a, j, b) is the cost from node i's option a to node
// j's option b (j = 0 only for the return with return_to_start). Alternates exact steps from
// OrderCuts's cost matrix of the cheapest option pairs: order on it, choose the options along
// the order (ChooseAlongOrder), order again on the chosen options, choose again, ... while the
// cost decreases (at most `rounds` orders); also starts from options 0 (the first of each node),
// and keeps the cheapest. Costs are evaluated once per option pair (O(n^2 m^2) calls).
struct OrderChoiceResult {
  std::vector<int> order;    // nodes 1..n in visiting order
  std::vector<int> choice;   // per node 0..n, the option chosen (choice[0] = 0)
  double cost = 0.0;         // of the order with those options
  bool exact_order = false;  // the orders were Held-Karp's (n <= kMaxExactCuts)
};
using MoveCost = std::function<double(int from_node, int from_option, int to_node, int to_option)>;
OrderChoiceResult OrderAndChoose(const std::vector<int>& option_counts, const MoveCost& move_cost,
                                 bool return_to_start = false, int rounds = 4);

}  // namespace vb::plan
