// SPDX-License-Identifier: Apache-2.0
#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_set>

#include "absl/strings/str_cat.h"

namespace vb::sim {
namespace {

struct AxisPoint {
  double arc_length_m = 0.0;
  double distance_m = std::numeric_limits<double>::infinity();
};

AxisPoint NearestOnAxis(const Polyline3& line, const Eigen::Vector3d& p) {
  AxisPoint best;
  const std::vector<double> arc = line.ArcLengths();
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    double t = 0.0;
    const double d = PointSegmentDistance(p, line.points[i], line.points[i + 1], &t);
    if (d < best.distance_m) {
      best.distance_m = d;
      best.arc_length_m = arc[i] + t * (arc[i + 1] - arc[i]);
    }
  }
  return best;
}

}  // namespace

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
  const Polyline3 before = vine.canes[*index].polyline;
  const AxisPoint at = NearestOnAxis(before, point_in_platform);
  const double surface_distance = at.distance_m - before.RadiusAt(at.arc_length_m);
  if (surface_distance > tolerance_m) {
    return absl::InvalidArgumentError(absl::StrCat(
        "ApplyCut: point is ", surface_distance, " m from the surface of cane ", cane_id.value,
        ", more than tolerance_m ", tolerance_m));
  }

  CutResult result;
  result.cane_id = cane_id;
  result.arc_length_m = at.arc_length_m;
  result.distance_m = at.distance_m;

  std::unordered_set<int64_t> fallen;
  const bool whole = at.arc_length_m < kMinStubM;
  if (whole) {
    fallen.insert(cane_id.value);
    result.removed.push_back(cane_id);
  }
  const double length = before.Length();
  const bool is_trunk = vine.canes[*index].kind == CaneKind::kTrunk;
  for (CaneId child : vine.ChildrenOf(cane_id)) {
    const Cane& c = vine.canes[*vine.IndexOf(child)];
    const Eigen::Vector3d& base = c.polyline.points.front();
    const AxisPoint attach = NearestOnAxis(before, base);
    // Canes of the head grow from sphere surfaces off the trunk axis: they hang on the trunk top.
    const bool on_head =
        is_trunk && attach.distance_m > before.RadiusAt(attach.arc_length_m) + 1e-3;
    const double attach_arc = on_head ? length : attach.arc_length_m;
    if (whole || attach_arc > at.arc_length_m) {
      fallen.insert(child.value);
      result.removed.push_back(child);
    }
  }
  // Everything growing from a fallen cane falls with it.
  const size_t direct = result.removed.size();
  for (size_t i = 0; i < direct; ++i) {
    for (CaneId d : vine.DescendantsOf(result.removed[i])) {
      if (fallen.insert(d.value).second) result.removed.push_back(d);
    }
  }
  if (is_trunk && (whole || at.arc_length_m < length - kMinStubM)) vine.head.spheres.clear();
  if (!whole) vine.canes[*index].polyline.TruncateAt(at.arc_length_m);
  std::erase_if(vine.canes, [&](const Cane& c) { return fallen.contains(c.id.value); });
  return result;
}

}  // namespace vb::sim
