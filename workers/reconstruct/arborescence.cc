// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/arborescence.h"

#include <cstddef>

namespace vb::reconstruct {

std::vector<int> MaxArborescence(int n, int root, const std::vector<Arc>& arcs) {
  // Every node's best incoming arc; if they form no cycle, that is the answer.
  std::vector<int> in(n, -1);
  for (size_t k = 0; k < arcs.size(); ++k) {
    const Arc& a = arcs[k];
    if (a.to == root || a.from == a.to) continue;
    if (in[a.to] < 0 || a.weight > arcs[in[a.to]].weight) in[a.to] = static_cast<int>(k);
  }
  std::vector<int> seen(n, -1), cycle;
  for (int v = 0; v < n && cycle.empty(); ++v) {
    int u = v;
    while (u != root && seen[u] < 0 && in[u] >= 0) {
      seen[u] = v;
      u = arcs[in[u]].from;
    }
    if (u != root && seen[u] == v && in[u] >= 0) {
      int x = u;
      do {
        cycle.push_back(x);
        x = arcs[in[x]].from;
      } while (x != u);
    }
  }
  if (cycle.empty()) return in;
  // Contract the cycle into one node; arcs entering it are charged the cycle arc they replace.
  std::vector<char> on_cycle(n, 0);
  for (int x : cycle) on_cycle[x] = 1;
  std::vector<int> label(n, -1);
  int m = 0;
  for (int v = 0; v < n; ++v)
    if (!on_cycle[v]) label[v] = m++;
  const int contracted = m++;
  for (int x : cycle) label[x] = contracted;
  std::vector<Arc> sub;
  std::vector<int> origin;
  for (size_t k = 0; k < arcs.size(); ++k) {
    const Arc& a = arcs[k];
    const int u = label[a.from], v = label[a.to];
    if (u == v) continue;
    const double w = on_cycle[a.to] ? a.weight - arcs[in[a.to]].weight : a.weight;
    sub.push_back({u, v, w});
    origin.push_back(static_cast<int>(k));
  }
  const std::vector<int> sub_in = MaxArborescence(m, label[root], sub);
  std::vector<int> chosen(n, -1);
  for (int v = 0; v < m; ++v) {
    if (sub_in[v] < 0) continue;
    const int k = origin[sub_in[v]];
    chosen[arcs[k].to] = k;
  }
  // The cycle's nodes not entered from outside keep their cycle arcs (one is broken).
  for (int x : cycle)
    if (chosen[x] < 0) chosen[x] = in[x];
  return chosen;
}

}  // namespace vb::reconstruct
