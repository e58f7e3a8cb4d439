// SPDX-License-Identifier: Apache-2.0
// Maximum-weight spanning arborescence (Chu and Liu 1965; Edmonds 1967): the tree of directed
// arcs, rooted at a given node and reaching every other node, whose arc weights sum largest.
// Connection (connect.h, step 3) picks each cane's parent with it. Pure function; thread-safe.
#pragma once

#include <vector>

namespace vb::reconstruct {

// A directed arc from -> to, nodes numbered [0, n).
struct Arc {
  int from = 0;
  int to = 0;
  double weight = 0.0;
};

// Returns per node the index into `arcs` of its chosen incoming arc (-1 for the root and for a
// node without any incoming arc). Contracts one cycle per level (recursion depth at most n).
// Every node but the root must have an incoming arc for the result to be a spanning tree;
// arcs into the root and self-loops are ignored. Programmer errors
// (node indices outside [0, n)) are not checked.
std::vector<int> MaxArborescence(int n, int root, const std::vector<Arc>& arcs);

}  // namespace vb::reconstruct
