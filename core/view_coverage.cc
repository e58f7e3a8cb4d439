// SPDX-License-Identifier: Apache-2.0
#include "core/view_coverage.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb {
namespace {

ImageSide SideOf(const CameraCalibration& camera, const Eigen::Vector3d& p) {
  Eigen::Vector2d uv;
  if (const auto projected = camera.Project(p)) {
    if (camera.InImage(*projected)) return ImageSide::kInside;
    uv = *projected;
  } else {
    // Behind the camera, or beyond the lens model's fold: no pixel. Points beside the camera
    // (z ~ 0) still have a side: the pinhole direction of their bearing.
    const Eigen::Vector3d q =
        camera.rotation_camera_from_platform * p + camera.translation_camera_from_platform;
    if (q.z() <= 0.0) return ImageSide::kNotProjected;
    uv = Eigen::Vector2d(camera.camera_matrix(0, 0) * q.x() / q.z() + camera.camera_matrix(0, 2),
                         camera.camera_matrix(1, 1) * q.y() / q.z() + camera.camera_matrix(1, 2));
  }
  const double w = camera.image_width - 0.5;
  const double h = camera.image_height - 0.5;
  const std::pair<double, ImageSide> excess[] = {{-0.5 - uv.x(), ImageSide::kBeyondLeft},
                                                 {uv.x() - w, ImageSide::kBeyondRight},
                                                 {-0.5 - uv.y(), ImageSide::kBeyondTop},
                                                 {uv.y() - h, ImageSide::kBeyondBottom}};
  return std::max_element(std::begin(excess), std::end(excess),
                          [](const auto& a, const auto& b) { return a.first < b.first; })
      ->second;
}

}  // namespace

absl::StatusOr<std::vector<CoverageSample>> SampleViewCoverage(const VineModel& truth,
                                                               const RigCalibration& rig,
                                                               double sample_step_m) {
  if (!std::isfinite(sample_step_m) || sample_step_m <= 0.0)
    return absl::InvalidArgumentError(
        absl::StrCat("sample_step_m must be positive and finite, is ", sample_step_m));
  if (absl::Status s = truth.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("truth: ", std::string(s.message())));
  if (absl::Status s = rig.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("rig: ", std::string(s.message())));
  std::vector<CoverageSample> out;
  for (size_t i = 0; i < truth.canes.size(); ++i) {
    const Cane& cane = truth.canes[i];
    if (cane.kind == CaneKind::kSpur) continue;
    const auto& points = cane.polyline.points;
    // The same samples as the recall metric: midpoints of equal pieces of each segment.
    for (size_t k = 0; k + 1 < points.size(); ++k) {
      const double length = (points[k + 1] - points[k]).norm();
      if (length <= 0.0) continue;
      const int n = std::max(1, static_cast<int>(std::ceil(length / sample_step_m)));
      for (int j = 0; j < n; ++j) {
        CoverageSample s;
        s.point = points[k] + (points[k + 1] - points[k]) * ((j + 0.5) / n);
        s.length_m = length / n;
        s.kind = cane.kind;
        s.cane_index = static_cast<int>(i);
        for (const CameraCalibration& camera : rig.cameras) {
          s.sides.push_back(SideOf(camera, s.point));
          s.views += s.sides.back() == ImageSide::kInside;
        }
        out.push_back(std::move(s));
      }
    }
  }
  return out;
}

ViewCoverage SummariseViewCoverage(const std::vector<CoverageSample>& samples, int camera_count) {
  ViewCoverage c;
  c.side_fraction.assign(std::max(0, camera_count), std::array<double, 6>{});
  for (const CoverageSample& s : samples) {
    c.truth_cane_length_m += s.length_m;
    if (s.views >= 2) c.in_two_or_more_fraction += s.length_m;
    if (s.views == 1) c.in_one_fraction += s.length_m;
    if (s.views == 0) c.in_none_fraction += s.length_m;
    if (s.views < 2 && s.kind == CaneKind::kTrunk) c.trunk_in_fewer_than_two_fraction += s.length_m;
    for (size_t v = 0; v < s.sides.size() && v < c.side_fraction.size(); ++v)
      c.side_fraction[v][static_cast<int>(s.sides[v])] += s.length_m;
  }
  if (c.truth_cane_length_m > 0.0) {
    const double inv = 1.0 / c.truth_cane_length_m;
    c.in_two_or_more_fraction *= inv;
    c.in_one_fraction *= inv;
    c.in_none_fraction *= inv;
    c.trunk_in_fewer_than_two_fraction *= inv;
    for (auto& sides : c.side_fraction)
      for (double& f : sides) f *= inv;
  }
  return c;
}

absl::StatusOr<ViewCoverage> EvaluateViewCoverage(const VineModel& truth, const RigCalibration& rig,
                                                  double sample_step_m) {
  absl::StatusOr<std::vector<CoverageSample>> samples =
      SampleViewCoverage(truth, rig, sample_step_m);
  if (!samples.ok()) return samples.status();
  return SummariseViewCoverage(*samples, static_cast<int>(rig.cameras.size()));
}

nlohmann::json ViewCoverageToJson(const ViewCoverage& c) {
  return nlohmann::json{{"cane_length_in_two_views_fraction", c.in_two_or_more_fraction},
                        {"cane_length_in_one_view_fraction", c.in_one_fraction},
                        {"cane_length_in_no_view_fraction", c.in_none_fraction},
                        {"trunk_length_in_fewer_than_two_views_fraction",
                         c.trunk_in_fewer_than_two_fraction}};
}

}  // namespace vb
