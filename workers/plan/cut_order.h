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

}  // namespace vb::plan
