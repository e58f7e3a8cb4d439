// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/grow_drift_diagnose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "workers/reconstruct/grow_internal.h"

namespace vb::reconstruct {

void DriftTally::Bin::Add(double distance, double depth, double growth) {
  ++points;
  distance_mm += distance;
  depth_mm += depth;
  lateral_mm += std::sqrt(std::max(0.0, distance * distance - depth * depth));
  growth_mm += growth;
  over_5mm += distance > 5.0;
}

void DriftTally::Bin::Print(const char* label) const {
  const double n = std::max(1, points);
  std::printf("DRIFT | %s | %d | %.2f | %.2f | %.2f | %+.2f | %.2f |\n", label, points,
              distance_mm / n, depth_mm / n, lateral_mm / n, growth_mm / n, over_5mm / n);
}

void DriftTally::Add(const VineModel& truth, const std::vector<View2D>& views,
                     const RigCalibration& rig, const GrowOptions& options,
                     const GrowSummary& summary) {
  std::vector<grow_internal::ViewProbe> probes;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (size_t v = 0; v < views.size(); ++v) {
    probes.emplace_back(views[v], rig.cameras[v], options.image_margin_px);
    centre += rig.cameras[v].CentreInPlatform() / static_cast<double>(views.size());
  }
  // The error of p against the cane: 3D distance and its component along the ray.
  const auto error = [&](const Polyline3& cane, const Eigen::Vector3d& p, double* depth) {
    const Eigen::Vector3d e = p - cane.PointAt(cane.Project(p));
    *depth = std::abs(e.dot((p - centre).normalized())) * 1000;
    return e.norm() * 1000;
  };
  for (const GrowEnd& end : summary.ends) {
    if (end.steps.empty()) continue;
    int own = -1;
    double best = 0.010;
    for (size_t i = 0; i < truth.canes.size(); ++i) {
      double d = 0;
      truth.canes[i].polyline.Project(end.start_point, &d);
      if (d <= best) {
        best = d;
        own = static_cast<int>(i);
      }
    }
    if (own < 0) {
      ++ends_off_;
      continue;
    }
    const Polyline3& cane = truth.canes[own].polyline;
    ++ends_;
    double start_depth = 0;
    const double start = error(cane, end.start_point, &start_depth);
    start_mm_ += start;
    start_depth_mm_ += start_depth;
    const int start_bin = start < 2 ? 0 : start < 4 ? 1 : 2;
    double previous = start;
    Eigen::Vector3d from = end.start_point;
    for (size_t k = 0; k < end.steps.size(); ++k) {
      const Eigen::Vector3d& p = end.steps[k];
      double depth = 0;
      const double d = error(cane, p, &depth);
      const double growth = d - previous;
      previous = d;
      const Eigen::Vector3d step = (p - from).normalized();
      from = p;
      const Eigen::Vector3d q = cane.PointAt(cane.Project(p));
      std::vector<int> near;
      int third = -1;
      for (size_t v = 0; v < probes.size(); ++v) {
        const auto uv = probes[v].Inside(p);
        if (!uv) continue;
        if (probes[v].Distance(*uv) <= options.support_px) {
          near.push_back(static_cast<int>(v));
        } else {
          third = static_cast<int>(v);
        }
      }
      const size_t n = k + 1;
      by_step_[n <= 2 ? 0 : n <= 4 ? 1 : n <= 8 ? 2 : n <= 16 ? 3 : 4].Add(d, depth, growth);
      by_views_[std::min<int>(2, std::max<int>(0, static_cast<int>(near.size()) - 1))].Add(
          d, depth, growth);
      by_start_[start_bin].Add(d, depth, growth);
      all_.Add(d, depth, growth);
      if (near.size() != 2) continue;
      const Eigen::Vector3d ca = probes[near[0]].Centre(), cb = probes[near[1]].Centre();
      const double angle =
          std::asin(std::min(1.0, std::abs((cb - ca).cross(p - ca).normalized().dot(step)))) *
          180 / M_PI;
      by_angle_[angle < 15 ? 0 : angle < 25 ? 1 : angle < 45 ? 2 : 3].Add(d, depth, growth);
      if (third >= 0) {
        ++third_seen_;
        const auto uv_q = probes[third].Inside(q);
        third_holds_truth_ += uv_q && probes[third].Distance(*uv_q) <= options.support_px;
        const auto uv_p = probes[third].Inside(p);
        third_holds_point_ += uv_p && probes[third].Distance(*uv_p) <= 2 * options.support_px;
      }
    }
  }
}

void DriftTally::Print() const {
  std::printf("DRIFT ends on the vine's canes %d (start > 10 mm off: %d); start end off its cane "
              "%.2f mm, depth %.2f mm\n",
              ends_, ends_off_, start_mm_ / std::max(1, ends_),
              start_depth_mm_ / std::max(1, ends_));
  std::printf("DRIFT | grown points | n | 3D mm | depth mm | lateral mm | change per step mm | "
              "> 5 mm |\n");
  all_.Print("all");
  const char* steps[kStepBins] = {"step 1-2", "step 3-4", "step 5-8", "step 9-16", "step 17+"};
  for (int i = 0; i < kStepBins; ++i) by_step_[i].Print(steps[i]);
  const char* views[kViewBins] = {"<= 1 view within 2 px", "2 views", "3 views"};
  for (int i = 0; i < kViewBins; ++i) by_views_[i].Print(views[i]);
  const char* angles[kAngleBins] = {"2 views, epipolar < 15 deg", "2 views, 15-25 deg",
                                    "2 views, 25-45 deg", "2 views, 45-90 deg"};
  for (int i = 0; i < kAngleBins; ++i) by_angle_[i].Print(angles[i]);
  const char* starts[kStartBins] = {"start end < 2 mm off", "start end 2-4 mm off",
                                    "start end 4-10 mm off"};
  for (int i = 0; i < kStartBins; ++i) by_start_[i].Print(starts[i]);
  std::printf("DRIFT two views hold the point and a third sees it: %d; the third holds the true "
              "point within 2 px %d, the grown point within 4 px %d\n",
              third_seen_, third_holds_truth_, third_holds_point_);
}

}  // namespace vb::reconstruct
