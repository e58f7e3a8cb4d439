// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/join_images.h"

#include <algorithm>
#include <functional>
#include <utility>

#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {

absl::Status JoinImageOptions::Validate() const {
  if (absl::Status s = CheckPositive(gap.step_m, "join_images", "gap.step_m"); !s.ok()) return s;
  const std::pair<double, const char*> non_negative[] = {
      {static_cast<double>(gap.tolerance_px), "gap.tolerance_px"},
      {static_cast<double>(gap.min_views), "gap.min_views"},
      {junction_radius_px, "junction_radius_px"}};
  for (const auto& [value, field] : non_negative) {
    if (absl::Status s = CheckNonNegative(value, "join_images", field); !s.ok()) return s;
  }
  return absl::OkStatus();
}

JoinImageEvidence MeasureJoinImages(const Eigen::Vector3d& base, const Eigen::Vector3d& point,
                                    const std::vector<View2D>& views, const RigCalibration& rig,
                                    const JoinImageOptions& options) {
  JoinImageEvidence e;
  if (!base.allFinite() || !point.allFinite()) return e;
  e.gap_all_views = GapSupport(base, point, views, rig, options.gap);
  std::vector<double> by_view = GapSupportByView(base, point, views, rig, options.gap);
  if (by_view.size() >= 2) {
    std::nth_element(by_view.begin(), by_view.begin() + 1, by_view.end(), std::greater<>());
    e.gap_best_two = by_view[1];
  }
  const double r2 = options.junction_radius_px * options.junction_radius_px;
  int seen = 0, junctions = 0;
  const size_t n = std::min(views.size(), rig.cameras.size());
  for (size_t v = 0; v < n; ++v) {
    if (views[v].classes.width <= 0) continue;
    const auto uv = rig.cameras[v].Project(point);
    if (!uv || !rig.cameras[v].InImage(*uv)) continue;
    ++seen;
    // A fork shows as a junction of the skeleton where the child leaves its parent.
    junctions += std::any_of(views[v].nodes.begin(), views[v].nodes.end(), [&](const Node2D& d) {
      return d.segments.size() >= 3 && (d.position - *uv).squaredNorm() <= r2;
    });
  }
  e.junction_views = seen > 0 ? static_cast<double>(junctions) / seen : 0.0;
  return e;
}

}  // namespace vb::reconstruct
