// SPDX-License-Identifier: Apache-2.0
#include "sim/world.h"

#include <cmath>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/fallen_wood.h"

namespace vb::sim {

absl::StatusOr<CutResult> SimWorld::ApplyCut(CaneId cane_id,
                                             const Eigen::Vector3d& point_in_platform,
                                             double tolerance_m) {
  if (!point_in_platform.allFinite()) {
    return absl::InvalidArgumentError("ApplyCut: point_in_platform is not finite");
  }
  if (!std::isfinite(tolerance_m) || tolerance_m < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("ApplyCut: tolerance_m must be finite and >= 0, is ", tolerance_m));
  }
  VineModel& vine = scene_.vine;
  const std::optional<size_t> index = vine.IndexOf(cane_id);
  if (!index.has_value()) {
    return absl::NotFoundError(
        absl::StrCat("ApplyCut: cane ", cane_id.value, " is not in the world (or already fell)"));
  }
  const Polyline3& axis = vine.canes[*index].polyline;
  double distance = 0.0;
  const double arc = axis.Project(point_in_platform, &distance);
  const double surface_distance = distance - axis.RadiusAt(arc);
  if (surface_distance > tolerance_m) {
    return absl::InvalidArgumentError(absl::StrCat(
        "ApplyCut: point is ", surface_distance, " m from the surface of cane ", cane_id.value,
        ", more than tolerance_m ", tolerance_m));
  }

  CutResult result;
  result.cane_id = cane_id;
  result.arc_length_m = arc;
  result.distance_m = distance;
  std::vector<FallingWood> fall;
  vine = AfterCuts(vine, {{*index, arc}}, &fall);
  result.removed = std::move(fall.front().canes);
  return result;
}

}  // namespace vb::sim
