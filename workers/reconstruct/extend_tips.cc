// SPDX-License-Identifier: Apache-2.0
// Which cane tips the single-view extension continues, and the anchors it continues them from
// (extend.h, extend_internal.h; docs/reconstruction.md, step 4c, "Which tips").
#include <algorithm>
#include <cmath>

#include "workers/reconstruct/extend_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {

TipSupport TipSupportOf(const Polyline3& line, const std::vector<View2D>& views,
                        const RigCalibration& rig, double span_m) {
  const std::vector<double> arc = line.ArcLengths();
  const double length = arc.back();
  std::vector<Eigen::Vector3d> samples;
  for (double s = std::max(0.0, length - span_m); s <= length + 1e-9; s += 0.005)
    samples.push_back(line.PointAt(s, arc));
  TipSupport support;
  for (size_t v = 0; v < views.size(); ++v) {
    const CameraCalibration& camera = rig.cameras[v];
    if (!HasCentrelineDistance(views[v])) continue;
    double sum = 0;
    int n = 0;
    for (const Eigen::Vector3d& p : samples) {
      const std::optional<Eigen::Vector2d> uv = camera.Project(p);
      if (!uv || !camera.InImage(*uv)) continue;
      sum += CentrelineDistanceAt(views[v], *uv);
      ++n;
    }
    if (n == 0) continue;
    ++support.views;
    support.worst_mean_px = std::max(support.worst_mean_px, sum / n);
  }
  return support;
}

namespace extend_internal {

std::vector<Eigen::Vector3d> TipAnchors(const Polyline3& line, const ExtendOptions& options) {
  const double length = line.Length();
  const std::vector<double> arc = line.ArcLengths();
  std::vector<Eigen::Vector3d> anchors;
  for (int k = options.anchor_points - 1; k >= 0; --k)
    anchors.push_back(line.PointAt(std::max(0.0, length - k * options.step_m), arc));
  if (options.anchor_span_m > 0) {
    // A line through the last anchor_span_m of the cane: one noisy point near the tip would
    // otherwise set the direction the depths continue in.
    const double span = std::min(options.anchor_span_m, length);
    const int m = std::max(3, static_cast<int>(span / 0.005) + 1);
    Eigen::Vector3d mean_p = Eigen::Vector3d::Zero();
    double mean_s = 0;
    std::vector<std::pair<double, Eigen::Vector3d>> samples;
    for (int i = 0; i < m; ++i) {
      const double s_i = length - span * i / (m - 1);
      samples.emplace_back(s_i, line.PointAt(s_i, arc));
      mean_p += samples.back().second;
      mean_s += s_i;
    }
    mean_p /= m;
    mean_s /= m;
    Eigen::Vector3d slope = Eigen::Vector3d::Zero();
    double var_s = 0;
    for (const auto& [s_i, p_i] : samples) {
      slope += (s_i - mean_s) * (p_i - mean_p);
      var_s += (s_i - mean_s) * (s_i - mean_s);
    }
    slope /= var_s;
    // Anchor the line at the tip as reconstructed (its projection continues into the 2D path).
    const Eigen::Vector3d tip_point = line.points.back();
    for (int k = 0; k < options.anchor_points; ++k)
      anchors[k] = tip_point - (options.anchor_points - 1 - k) * options.step_m * slope;
  }
  return anchors;
}

bool FarOrAcross(const Eigen::Vector3d& tip, const Eigen::Vector3d& tangent,
                 const std::optional<double>& trunk_x, const ExtendOptions& options) {
  // Tips of which a wrong one is likelier than a right one is useful: far along the row, where
  // neighbours' canes run along the same wires, and tips pointing toward or away from the
  // cameras, mostly mis-depthed ends.
  return (options.max_tip_row_distance_m > 0 && trunk_x &&
          std::abs(tip.x() - *trunk_x) > options.max_tip_row_distance_m) ||
         (options.max_tip_out_of_plane > 0 &&
          std::abs(tangent.y()) > options.max_tip_out_of_plane);
}

}  // namespace extend_internal
}  // namespace vb::reconstruct
