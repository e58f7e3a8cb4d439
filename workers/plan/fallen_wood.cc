// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/fallen_wood.h"

#include <algorithm>
#include <limits>
#include <unordered_map>
#include <unordered_set>

namespace vb::plan {

VineModel WithoutFallenWood(const VineModel& model, std::span<const Cut> cuts) {
  // The lowest cut on each cane (arc length from its base) decides what falls.
  std::unordered_map<int64_t, double> cut_at;
  for (const Cut& cut : cuts) {
    const std::optional<size_t> i = model.IndexOf(cut.cane_id);
    if (!i) continue;
    const double s = model.canes[*i].polyline.Project(cut.point);
    auto [it, inserted] = cut_at.emplace(cut.cane_id.value, s);
    if (!inserted) it->second = std::min(it->second, s);
  }
  std::unordered_set<int64_t> fallen;
  for (const auto& [cane_id, s] : cut_at) {
    const Cane& cane = model.canes[*model.IndexOf(CaneId{cane_id})];
    if (s < kMinCaneStubM) fallen.insert(cane_id);
    for (CaneId child : model.ChildrenOf(cane.id)) {
      const Cane& c = model.canes[*model.IndexOf(child)];
      if (cane.polyline.Project(c.polyline.points.front()) > s) fallen.insert(child.value);
    }
  }
  // Descendants of fallen canes fall too.
  std::vector<int64_t> roots(fallen.begin(), fallen.end());
  for (int64_t id : roots)
    for (CaneId d : model.DescendantsOf(CaneId{id})) fallen.insert(d.value);

  VineModel after = model;
  after.canes.clear();
  for (const Cane& cane : model.canes) {
    if (fallen.count(cane.id.value)) continue;
    Cane kept = cane;
    const auto it = cut_at.find(cane.id.value);
    if (it != cut_at.end()) kept.polyline.TruncateAt(it->second);
    after.canes.push_back(std::move(kept));
  }
  return after;
}

}  // namespace vb::plan
