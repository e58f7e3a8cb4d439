// SPDX-License-Identifier: Apache-2.0
// The trunk's unseen base stretch, cut off before the joint refinement (cane_fit.h: below the
// images the trunk is a straight line guessed down to the ground).
#include <algorithm>
#include <optional>

#include "workers/reconstruct/cane_fit_internal.h"

namespace vb::reconstruct::cane_fit_internal {
namespace {

// A trunk's unseen stretch is cut at least this far below the lowest base of a cane on it.
constexpr double kTrunkChildClearanceM = 0.05;

// How many cameras have p inside their image.
int ViewsSeeing(const Eigen::Vector3d& p, const RigCalibration& rig) {
  int n = 0;
  for (const CameraCalibration& camera : rig.cameras) {
    const std::optional<Eigen::Vector2d> uv = camera.Project(p);
    n += uv && camera.InImage(*uv);
  }
  return n;
}

// The arc length along `trunk` (base first) from which on it lies inside at least `min_views`
// images, sampled every `step_m` (0 if its base already does; nullopt if no sample does).
std::optional<double> FirstSeenArc(const Polyline3& trunk, const RigCalibration& rig,
                                   int min_views, double step_m) {
  const std::vector<double> arc = trunk.ArcLengths();
  const double length = arc.back();
  for (double s = 0.0; s < length; s += step_m) {
    if (ViewsSeeing(trunk.PointAt(s, arc), rig) < min_views) continue;
    // Refine the boundary between the last unseen sample and this one.
    double lo = std::max(0.0, s - step_m), hi = s;
    if (s == 0.0) return 0.0;
    for (int k = 0; k < 12; ++k) {
      const double mid = 0.5 * (lo + hi);
      (ViewsSeeing(trunk.PointAt(mid, arc), rig) >= min_views ? hi : lo) = mid;
    }
    return hi;
  }
  return std::nullopt;
}

// Splits `line` at arc length s into [0, s] and [s, end], the point at s in both.
std::pair<Polyline3, Polyline3> SplitAt(const Polyline3& line, double s) {
  const std::vector<double> arc = line.ArcLengths();
  Polyline3 below, above;
  const Eigen::Vector3d at = line.PointAt(s, arc);
  const double r = line.RadiusAt(s, arc);
  for (size_t i = 0; i < line.points.size(); ++i) {
    if (arc[i] < s) below.points.push_back(line.points[i]), below.radii.push_back(line.radii[i]);
  }
  below.points.push_back(at), below.radii.push_back(r);
  above.points.push_back(at), above.radii.push_back(r);
  for (size_t i = 0; i < line.points.size(); ++i) {
    if (arc[i] > s) above.points.push_back(line.points[i]), above.radii.push_back(line.radii[i]);
  }
  return {below, above};
}

}  // namespace

FitLines LinesForFit(const VineModel& model, const RigCalibration& rig,
                     const FitOptions& options) {
  const size_t cane_count = model.canes.size();
  FitLines out;
  out.lines.resize(cane_count);
  out.split.assign(cane_count, false);
  for (size_t c = 0; c < cane_count; ++c) {
    const Polyline3& source = model.canes[c].polyline;
    double s = 0.0;
    if (options.trunk_min_views > 0 && !model.canes[c].parent_id.has_value()) {
      const std::optional<double> seen =
          FirstSeenArc(source, rig, options.trunk_min_views, 0.005);
      if (seen.has_value()) s = *seen - options.trunk_unseen_keep_m;
      // Wood hanging on the trunk keeps the trunk it hangs on: the cut stays kTrunkChildClearanceM
      // below the lowest base of a cane on the trunk.
      for (const Cane& child : model.canes) {
        if (child.parent_id == model.canes[c].id && !child.polyline.points.empty()) {
          s = std::min(s, source.Project(child.polyline.points.front()) - kTrunkChildClearanceM);
        }
      }
    }
    if (s > 1e-6 && s < source.Length() - 0.01) {
      auto [below, above] = SplitAt(source, s);
      out.unseen.push_back(WoodObstacle{std::move(below)});
      out.unseen_of.push_back(c);
      out.lines[c] = above.Resampled(options.point_spacing_m);
      out.split[c] = true;
    } else {
      out.lines[c] = source.Resampled(options.point_spacing_m);
    }
  }
  return out;
}

}  // namespace vb::reconstruct::cane_fit_internal
