// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/fallen_wood.h"

#include <utility>
#include <vector>

#include "core/fallen_wood.h"

namespace vb::plan {

VineModel WithoutFallenWood(const VineModel& model, std::span<const Cut> cuts) {
  std::vector<std::pair<size_t, double>> at;
  for (const Cut& cut : cuts) {
    const std::optional<size_t> i = model.IndexOf(cut.cane_id);
    if (i) at.emplace_back(*i, model.canes[*i].polyline.Project(cut.point));
  }
  return AfterCuts(model, at);
}

}  // namespace vb::plan
