// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/depth_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/geometry.h"
#include "core/status_macros.h"
#include "workers/reconstruct/depth_sweep_check.h"
#include "workers/reconstruct/depth_sweep_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

// Spacing of the skeleton samples the check's tangent lookups use (correspondence's default).
constexpr double kSkeletonSampleStepPx = 4.0;

// Per view: 1 where a cane's projected cross-section (plus explained_px) covers the pixel.
using ExplainedMask = std::vector<uint8_t>;

void StampDisc(int width, int height, const Eigen::Vector2d& uv, double radius_px,
               ExplainedMask* mask) {
  const int r = static_cast<int>(std::ceil(radius_px));
  const int cx = static_cast<int>(std::lround(uv.x())), cy = static_cast<int>(std::lround(uv.y()));
  const double r2 = radius_px * radius_px;
  for (int y = std::max(0, cy - r); y <= std::min(height - 1, cy + r); ++y) {
    for (int x = std::max(0, cx - r); x <= std::min(width - 1, cx + r); ++x) {
      if ((x - uv.x()) * (x - uv.x()) + (y - uv.y()) * (y - uv.y()) <= r2)
        (*mask)[static_cast<size_t>(y) * width + x] = 1;
    }
  }
}

// Marks the pixels of `view` within explained_px of the projected cross-section of `cane`.
void StampCane(const Polyline3& cane, const CameraCalibration& camera, const View2D& view,
               double explained_px, ExplainedMask* mask) {
  for (size_t i = 0; i + 1 < cane.points.size(); ++i) {
    const Eigen::Vector3d& a = cane.points[i];
    const Eigen::Vector3d& b = cane.points[i + 1];
    const std::optional<Eigen::Vector2d> ua = camera.Project(a), ub = camera.Project(b);
    if (!ua || !ub) continue;
    const double ra = explained_px + ProjectedRadiusPx(camera, a, cane.radii[i]);
    const double rb = explained_px + ProjectedRadiusPx(camera, b, cane.radii[i + 1]);
    // Discs no farther apart than half the smaller radius cover the swept band.
    const double step = std::max(0.5, 0.5 * std::min(ra, rb));
    const int n = std::min(4000, static_cast<int>(std::ceil((*ub - *ua).norm() / step)));
    for (int k = 0; k <= n; ++k) {
      const double u = n == 0 ? 0.0 : static_cast<double>(k) / n;
      StampDisc(view.width, view.height, *ua + u * (*ub - *ua), ra + u * (rb - ra), mask);
    }
  }
}

bool NearThick(const View2D& view, int x, int y, int margin) {
  if (view.thick_mask.size() != static_cast<size_t>(view.width) * view.height) return false;
  for (int yy = std::max(0, y - margin); yy <= std::min(view.height - 1, y + margin); ++yy)
    for (int xx = std::max(0, x - margin); xx <= std::min(view.width - 1, x + margin); ++xx)
      if (view.thick_mask[static_cast<size_t>(yy) * view.width + xx]) return true;
  return false;
}

// Whether pixel uv lies within margin_px beyond the half-width of one of `lines` (wires or
// posts, in normalised coordinates) and within its extent (plus the same margin).
bool NearLine(const std::vector<Line2D>& lines, const CameraCalibration& camera,
              const Eigen::Vector2d& uv, double margin_px) {
  if (lines.empty()) return false;
  const Eigen::Vector2d n = camera.PixelToNormalised(uv);
  const double fx = camera.camera_matrix(0, 0);
  for (const Line2D& line : lines) {
    const double reach = (margin_px + 0.5 * line.width_px) / fx;
    if (std::abs(line.line.dot(Eigen::Vector3d(n.x(), n.y(), 1.0))) > reach) continue;
    const Eigen::Vector2d along = line.end - line.begin;
    const double length = along.norm();
    if (length <= 0) continue;
    const double u = (n - line.begin).dot(along) / length;
    if (u >= -reach && u <= length + reach) return true;
  }
  return false;
}

// An unexplained run of one segment, resampled every ~sample_px.
struct Stretch {
  std::vector<Eigen::Vector2d> uv;
  std::vector<double> width_px;
};

Stretch Resample(const Segment2D& segment, size_t first, size_t last, double length,
                 double sample_px) {
  Stretch out;
  const int n = std::max(2, static_cast<int>(std::floor(length / sample_px)) + 1);
  const double spacing = length / (n - 1);
  size_t j = first;
  double s_j = 0.0;  // arc length at point j
  for (int k = 0; k < n; ++k) {
    const double s = std::min(length, k * spacing);
    while (j + 1 < last && s_j + (segment.points[j + 1] - segment.points[j]).norm() < s) {
      s_j += (segment.points[j + 1] - segment.points[j]).norm();
      ++j;
    }
    const double seg = (segment.points[j + 1] - segment.points[j]).norm();
    const double u = seg > 0 ? std::clamp((s - s_j) / seg, 0.0, 1.0) : 0.0;
    out.uv.push_back(segment.points[j] + u * (segment.points[j + 1] - segment.points[j]));
    out.width_px.push_back(segment.widths_px[j] + u * (segment.widths_px[j + 1] -
                                                       segment.widths_px[j]));
  }
  return out;
}

// The unexplained stretches of view v's segments; *unexplained counts their skeleton points.
std::vector<Stretch> FindStretches(const View2D& view, const CameraCalibration& camera,
                                   const ExplainedMask& mask, const DepthSweepOptions& options,
                                   int* unexplained) {
  std::vector<Stretch> out;
  for (const Segment2D& segment : view.segments) {
    const size_t n = segment.points.size();
    if (n < 2 || segment.widths_px.size() != n) continue;
    std::vector<bool> free(n, false);
    for (size_t j = 0; j < n; ++j) {
      const Eigen::Vector2d& p = segment.points[j];
      if (!camera.InImage(p)) continue;
      const int x = std::clamp(static_cast<int>(std::lround(p.x())), 0, view.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(p.y())), 0, view.height - 1);
      free[j] = !mask[static_cast<size_t>(y) * view.width + x] &&
                !NearThick(view, x, y, options.thick_margin_px) &&
                !NearLine(view.wires, camera, p, options.line_margin_px) &&
                !NearLine(view.posts, camera, p, options.line_margin_px);
      *unexplained += free[j];
    }
    for (size_t a = 0; a < n;) {
      if (!free[a]) {
        ++a;
        continue;
      }
      size_t b = a;
      double length = 0.0;
      while (b + 1 < n && free[b + 1]) {
        length += (segment.points[b + 1] - segment.points[b]).norm();
        ++b;
      }
      if (b > a && length >= options.min_stretch_px) {
        out.push_back(Resample(segment, a, b, length, options.sample_px));
      }
      a = b + 1;
    }
  }
  return out;
}

// Distance from p to the nearest cane of `canes` if below `limit`, else `limit`.
double DistanceToCanesBelow(const Eigen::Vector3d& p, const std::vector<Polyline3>& canes,
                            const std::vector<Eigen::AlignedBox3d>& boxes, double limit) {
  double best = limit;
  for (size_t c = 0; c < canes.size(); ++c) {
    if (boxes[c].exteriorDistance(p) >= best) continue;
    const std::vector<Eigen::Vector3d>& q = canes[c].points;
    for (size_t i = 0; i + 1 < q.size(); ++i)
      best = std::min(best, PointSegmentDistance(p, q[i], q[i + 1]));
    if (q.size() == 1) best = std::min(best, (q[0] - p).norm());
  }
  return best;
}

Eigen::AlignedBox3d BoxOf(const Polyline3& cane) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : cane.points) box.extend(p);
  return box;
}

}  // namespace

absl::Status DepthSweepOptions::Validate() const {
  constexpr const char* kStage = "sweep";
  VB_RETURN_IF_ERROR(CheckNonNegative(explained_px, kStage, "explained_px"));
  VB_RETURN_IF_ERROR(CheckNonNegative(min_stretch_px, kStage, "min_stretch_px"));
  VB_RETURN_IF_ERROR(CheckNonNegative(line_margin_px, kStage, "line_margin_px"));
  VB_RETURN_IF_ERROR(CheckPositive(sample_px, kStage, "sample_px"));
  VB_RETURN_IF_ERROR(CheckPositive(depth_step_px, kStage, "depth_step_px"));
  VB_RETURN_IF_ERROR(CheckPositive(cap_px, kStage, "cap_px"));
  VB_RETURN_IF_ERROR(CheckNonNegative(missing_view_cost_px2, kStage, "missing_view_cost_px2"));
  VB_RETURN_IF_ERROR(CheckNonNegative(smooth_px2, kStage, "smooth_px2"));
  VB_RETURN_IF_ERROR(CheckPositive(accept_px, kStage, "accept_px"));
  VB_RETURN_IF_ERROR(CheckPositive(accept_rms_px, kStage, "accept_rms_px"));
  VB_RETURN_IF_ERROR(CheckNonNegative(existing_cane_m, kStage, "existing_cane_m"));
  VB_RETURN_IF_ERROR(CheckNonNegative(min_length_m, kStage, "min_length_m"));
  VB_RETURN_IF_ERROR(CheckPositive(point_step_m, kStage, "point_step_m"));
  if (!(max_radius_m >= 0.0005) || !std::isfinite(max_radius_m)) {
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.max_radius_m must be finite and >= 0.0005, is ", max_radius_m));
  }
  if (thick_margin_px < 0 || thick_margin_px > 50)
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.thick_margin_px must be in [0, 50], is ", thick_margin_px));
  if (max_depths < 2 || max_depths > 10000)
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.max_depths must be in [2, 10000], is ", max_depths));
  if (max_step < 1 || max_step > 20)
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.max_step must be in [1, 20], is ", max_step));
  if (min_views < 2)
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.min_views must be >= 2, is ", min_views));
  if (unique_exclusion_steps < 0)
    return absl::InvalidArgumentError(absl::StrCat(
        "sweep.unique_exclusion_steps must be >= 0, is ", unique_exclusion_steps));
  if (!(max_ambiguous_share >= 0.0 && max_ambiguous_share <= 1.0))
    return absl::InvalidArgumentError(absl::StrCat(
        "sweep.max_ambiguous_share must be in [0, 1], is ", max_ambiguous_share));
  if (!(min_stretch_accepted_share >= 0.0 && min_stretch_accepted_share <= 1.0))
    return absl::InvalidArgumentError(absl::StrCat(
        "sweep.min_stretch_accepted_share must be in [0, 1], is ", min_stretch_accepted_share));
  VB_RETURN_IF_ERROR(
      CheckNonNegative(check_max_width_log_spread, kStage, "check_max_width_log_spread"));
  VB_RETURN_IF_ERROR(
      CheckNonNegative(check_max_width_log_excess, kStage, "check_max_width_log_excess"));
  if (!(check_min_foreground >= 0.0 && check_min_foreground <= 1.0))
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.check_min_foreground must be in [0, 1], is ", check_min_foreground));
  if (image_margin_px < 0)
    return absl::InvalidArgumentError(
        absl::StrCat("sweep.image_margin_px must be >= 0, is ", image_margin_px));
  return absl::OkStatus();
}

namespace {


struct SweptSample {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  bool accepted = false;
  bool ambiguous = false;
  std::vector<double> distance_px;  // per view, -1 where the view does not see p
  double radius_m = 0.0;
};

// The canes of one stretch's accepted runs, and what *added records of each.
std::vector<Polyline3> RunsOf(const std::vector<SweptSample>& samples, size_t views,
                              const DepthSweepOptions& options, int view,
                              std::vector<SweptCane>* added) {
  std::vector<Polyline3> out;
  const size_t n = samples.size();
  int accepted = 0;
  for (const SweptSample& sample : samples) accepted += sample.accepted;
  const double stretch_share = n > 0 ? static_cast<double>(accepted) / n : 0.0;
  if (stretch_share < options.min_stretch_accepted_share) return out;
  for (size_t a = 0; a < n;) {
    if (!samples[a].accepted) {
      ++a;
      continue;
    }
    size_t b = a;
    while (b + 1 < n && samples[b + 1].accepted &&
           (samples[b + 1].p - samples[b].p).norm() < 0.008)
      ++b;
    Polyline3 run;
    std::vector<double> radii;
    std::vector<double> sum2(views, 0.0);
    std::vector<int> seen(views, 0);
    int ambiguous = 0;
    for (size_t i = a; i <= b; ++i) {
      ambiguous += samples[i].ambiguous;
      run.points.push_back(samples[i].p);
      radii.push_back(samples[i].radius_m);
      for (size_t w = 0; w < views; ++w) {
        if (samples[i].distance_px[w] < 0) continue;
        sum2[w] += samples[i].distance_px[w] * samples[i].distance_px[w];
        ++seen[w];
      }
    }
    const int run_samples = static_cast<int>(b - a + 1);
    a = b + 1;
    const double ambiguous_share = static_cast<double>(ambiguous) / run_samples;
    if (ambiguous_share > options.max_ambiguous_share) continue;
    bool consistent = true;
    for (size_t w = 0; w < views; ++w)
      if (seen[w] > 0 && std::sqrt(sum2[w] / seen[w]) > options.accept_rms_px) consistent = false;
    if (!consistent || run.points.size() < 2) continue;
    run.radii.assign(run.points.size(), 0.0);
    const double length = run.Length();
    if (length < options.min_length_m) continue;
    std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
    const double radius = std::clamp(radii[radii.size() / 2], 0.0005, options.max_radius_m);
    std::fill(run.radii.begin(), run.radii.end(), radius);
    const int points = std::max(2, static_cast<int>(std::round(length / options.point_step_m)) + 1);
    const std::vector<double> arc = run.ArcLengths();
    Polyline3 cane;
    for (int i = 0; i < points; ++i) {
      cane.points.push_back(run.PointAt(length * i / (points - 1), arc));
      cane.radii.push_back(radius);
    }
    out.push_back(std::move(cane));
    added->push_back({view, ambiguous_share, stretch_share, run_samples});
  }
  return out;
}

}  // namespace

bool PassesCheck(const SweptRunFeatures& features, const DepthSweepOptions& options) {
  return features.width_log_spread <= options.check_max_width_log_spread &&
         features.width_log_excess <= options.check_max_width_log_excess &&
         features.foreground >= options.check_min_foreground;
}

absl::Status SweepUnexplainedPaths(const std::vector<View2D>& views, const RigCalibration& rig,
                                   const WorkingVolume& volume, const DepthSweepOptions& options,
                                   const Deadline& deadline, std::vector<Polyline3>* canes,
                                   DepthSweepSummary* summary) {
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("views: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  VB_RETURN_IF_ERROR(options.Validate());
  DepthSweepSummary local;
  DepthSweepSummary& out = summary != nullptr ? *summary : local;
  out = DepthSweepSummary{};
  out.unexplained_px.assign(views.size(), 0);
  out.stretches.assign(views.size(), 0);
  if (!options.enabled) return absl::OkStatus();

  std::vector<ExplainedMask> masks(views.size());
  for (size_t w = 0; w < views.size(); ++w) {
    masks[w].assign(static_cast<size_t>(views[w].width) * views[w].height, 0);
    for (const Polyline3& cane : *canes)
      StampCane(cane, rig.cameras[w], views[w], options.explained_px, &masks[w]);
  }
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Polyline3& cane : *canes) boxes.push_back(BoxOf(cane));
  std::vector<ViewSamples> view_samples;
  for (size_t w = 0; w < views.size(); ++w)
    view_samples.emplace_back(views[w], rig.cameras[w], kSkeletonSampleStepPx);

  for (size_t v = 0; v < views.size(); ++v) {
    VB_RETURN_IF_ERROR(deadline.Check("depth sweep"));
    const CameraCalibration& camera = rig.cameras[v];
    const std::vector<Stretch> stretches =
        FindStretches(views[v], camera, masks[v], options, &out.unexplained_px[v]);
    out.stretches[v] = static_cast<int>(stretches.size());
    const Eigen::Isometry3d camera_from_platform = camera.camera_from_platform();
    const double fx = camera.camera_matrix(0, 0);
    const size_t first_new = canes->size();
    for (const Stretch& stretch : stretches) {
      VB_RETURN_IF_ERROR(deadline.Check("depth sweep"));
      std::vector<Eigen::Vector3d> rays;
      for (const Eigen::Vector2d& uv : stretch.uv) rays.push_back(camera.RayInPlatform(uv));
      const depth_sweep_internal::StretchDepths depths = depth_sweep_internal::SweepStretch(
          rays, static_cast<int>(v), views, rig, volume, options);
      const std::vector<double>& q = depths.q;
      std::vector<SweptSample> samples(q.size());
      const Eigen::Vector3d c = camera.CentreInPlatform();
      for (size_t i = 0; i < q.size(); ++i) {
        SweptSample& sample = samples[i];
        sample.distance_px.assign(views.size(), -1.0);
        if (q[i] <= 0.0) continue;
        sample.ambiguous = depths.ambiguous[i];
        sample.p = c + rays[i] / q[i];
        const double depth = (camera_from_platform * sample.p).z();
        sample.radius_m = 0.5 * stretch.width_px[i] * depth / fx;
        if (!volume.Contains(sample.p)) continue;
        int support = 1;  // the swept view's own skeleton
        bool contradicted = false;
        sample.distance_px[v] = 0.0;
        for (size_t w = 0; w < views.size(); ++w) {
          if (w == v) continue;
          const auto uv = ProjectInside(rig.cameras[w], sample.p, options.image_margin_px);
          if (!uv) continue;
          const double d = CentrelineDistanceBilinear(views[w], *uv);
          sample.distance_px[w] = d;
          if (d <= options.accept_px) {
            ++support;
          } else {
            contradicted = true;
          }
        }
        sample.accepted = !contradicted && support >= options.min_views &&
                          DistanceToCanesBelow(sample.p, *canes, boxes, options.existing_cane_m) >=
                              options.existing_cane_m;
        ++out.samples;
        out.accepted_samples += sample.accepted;
      }
      std::vector<SweptCane> found;
      std::vector<Polyline3> runs =
          RunsOf(samples, views.size(), options, static_cast<int>(v), &found);
      for (size_t r = 0; r < runs.size(); ++r) {
        Polyline3& cane = runs[r];
        found[r].features = MeasureSweptRun(cane, views, rig, view_samples);
        found[r].checked = PassesCheck(found[r].features, options);
        if (options.check && !found[r].checked) {
          ++out.rejected_canes;
          out.rejected_length_m += cane.Length();
          continue;
        }
        out.added.push_back(found[r]);
        out.added_length_m += cane.Length();
        ++out.added_canes;
        boxes.push_back(BoxOf(cane));
        canes->push_back(std::move(cane));
      }
    }
    // What this view added explains the other views' pixels before they are swept.
    for (size_t i = first_new; i < canes->size(); ++i)
      for (size_t w = 0; w < views.size(); ++w)
        StampCane((*canes)[i], rig.cameras[w], views[w], options.explained_px, &masks[w]);
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
