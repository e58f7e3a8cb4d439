// SPDX-License-Identifier: Apache-2.0
#include "core/fallen_wood.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace vb {

FallingWood WoodFallingFromCut(const VineModel& vine, size_t index, double arc_length_m) {
  FallingWood fall;
  const Cane& cut = vine.canes[index];
  const double length = cut.polyline.Length();
  fall.cut_cane_whole = arc_length_m < kMinCaneStubM;
  if (fall.cut_cane_whole) fall.canes.push_back(cut.id);
  const bool is_trunk = cut.kind == CaneKind::kTrunk;
  std::unordered_set<int64_t> seen = {cut.id.value};
  for (CaneId child : vine.ChildrenOf(cut.id)) {
    const Cane& c = vine.canes[*vine.IndexOf(child)];
    double distance = 0.0;
    const double attach = cut.polyline.Project(c.polyline.points.front(), &distance);
    const bool on_head = is_trunk && distance > cut.polyline.RadiusAt(attach) + 1e-3;
    const double attach_arc = on_head ? length : attach;
    if ((fall.cut_cane_whole || attach_arc > arc_length_m) && seen.insert(child.value).second) {
      fall.canes.push_back(child);
    }
  }
  const size_t direct = fall.canes.size();
  for (size_t i = 0; i < direct; ++i) {
    for (CaneId d : vine.DescendantsOf(fall.canes[i])) {
      if (seen.insert(d.value).second) fall.canes.push_back(d);
    }
  }
  fall.head = is_trunk && (fall.cut_cane_whole || arc_length_m < length - kMinCaneStubM);
  return fall;
}

VineModel AfterCuts(const VineModel& vine, const std::vector<std::pair<size_t, double>>& cuts,
                    std::vector<FallingWood>* falls) {
  if (falls != nullptr) falls->clear();
  std::unordered_map<size_t, double> lowest;
  for (const auto& [index, arc] : cuts) {
    if (index >= vine.canes.size()) continue;
    auto [it, inserted] = lowest.emplace(index, arc);
    if (!inserted) it->second = std::min(it->second, arc);
  }
  std::unordered_set<int64_t> fallen;
  bool head = false;
  for (const auto& [index, arc] : lowest) {
    const FallingWood fall = WoodFallingFromCut(vine, index, arc);
    for (CaneId id : fall.canes) fallen.insert(id.value);
    head = head || fall.head;
    if (falls != nullptr) falls->push_back(fall);
  }
  VineModel after = vine;
  after.canes.clear();
  for (size_t i = 0; i < vine.canes.size(); ++i) {
    if (fallen.contains(vine.canes[i].id.value)) continue;
    Cane kept = vine.canes[i];
    if (const auto it = lowest.find(i); it != lowest.end()) kept.polyline.TruncateAt(it->second);
    after.canes.push_back(std::move(kept));
  }
  if (head) after.head.spheres.clear();
  return after;
}

}  // namespace vb
