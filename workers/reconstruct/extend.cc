// SPDX-License-Identifier: Apache-2.0
// The single-view extension's depths and the stage itself (extend.h); its 2D paths are in
// extend_paths.cc, its which-tips rules and anchors in extend_tips.cc.
#include "workers/reconstruct/extend.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "Eigen/Dense"
#include "absl/strings/str_cat.h"
#include "workers/reconstruct/extend_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

using extend_internal::CaneLabels;
using extend_internal::SkeletonIndex;

struct Extension {
  std::vector<Eigen::Vector3d> points;
  int view = -1;
  ExtendStop stop = ExtendStop::kPathEnd;
  bool contradicted = false;
  bool uncertain = false;
};

// Depths along the rays through `pixels` of `camera` that continue `anchors` (oldest first, the
// tip last) most smoothly; returns the points and each depth's predicted sd.
void SolveDepths(const CameraCalibration& camera, const std::vector<Eigen::Vector3d>& anchors,
                 const std::vector<Eigen::Vector2d>& pixels, double plane_y,
                 const ExtendOptions& options, std::vector<Eigen::Vector3d>* points,
                 std::vector<double>* sd) {
  const int n = static_cast<int>(pixels.size());
  const int a = static_cast<int>(anchors.size());
  const Eigen::Vector3d centre = camera.CentreInPlatform();
  std::vector<Eigen::Vector3d> rays(n);
  for (int i = 0; i < n; ++i) rays[i] = camera.RayInPlatform(pixels[i]);
  // Point j of the sequence (anchors then unknowns) is c_j + t_j r_j (r_j = 0 for anchors).
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  const double w_dd = 1.0 / (options.second_difference_sd_m * options.second_difference_sd_m);
  for (int j = 1; j + 1 < a + n; ++j) {
    if (j + 1 < a) continue;  // anchors only: a constant
    // residual = sum_m coef_m * P_{j-1+m}, m = 0..2, coef = (1, -2, 1)
    Eigen::Vector3d constant = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> jac = Eigen::MatrixXd::Zero(3, n);
    const double coef[3] = {1, -2, 1};
    for (int m = 0; m < 3; ++m) {
      const int q = j - 1 + m;
      if (q < a) {
        constant += coef[m] * anchors[q];
      } else {
        constant += coef[m] * centre;
        jac.col(q - a) += coef[m] * rays[q - a];
      }
    }
    normal += w_dd * jac.transpose() * jac;
    rhs -= w_dd * jac.transpose() * constant;
  }
  const double w_plane = 1.0 / (options.plane_sd_m * options.plane_sd_m);
  for (int i = 0; i < n; ++i) {
    normal(i, i) += w_plane * rays[i].y() * rays[i].y();
    rhs(i) -= w_plane * rays[i].y() * (centre.y() - plane_y);
  }
  const Eigen::MatrixXd cov = normal.inverse();
  const Eigen::VectorXd t = cov * rhs;
  points->resize(n);
  sd->resize(n);
  for (int i = 0; i < n; ++i) {
    (*points)[i] = centre + t(i) * rays[i];
    (*sd)[i] = std::sqrt(std::max(cov(i, i), 0.0));
  }
}

// A tip about to be extended: what every view's attempt continues.
struct Tip {
  int cane = -1;                         // index into the model's canes
  std::vector<Eigen::Vector3d> anchors;  // oldest first, the tip last (TipAnchors)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // anchors.back()
  Eigen::Vector3d tangent = Eigen::Vector3d::Zero();  // unit, from the last two anchors
  double radius_m = 0.0;                 // the cane's last radius
};

// Whether another view than `v` that sees p (inside its image by image_margin_px) shows only
// background within background_px plus the projected tip radius of it.
bool Contradicted(const std::vector<View2D>& views, const RigCalibration& rig, int v,
                  const Eigen::Vector3d& p, double radius_m, const ExtendOptions& options) {
  for (size_t w = 0; w < views.size(); ++w) {
    if (static_cast<int>(w) == v) continue;
    const CameraCalibration& other = rig.cameras[w];
    const std::optional<Eigen::Vector2d> uv = ProjectInside(other, p, options.image_margin_px);
    if (!uv) continue;
    const double r_px = ProjectedRadiusPx(other, p, radius_m);
    if (!WoodNear(views[w], *uv, static_cast<int>(std::ceil(options.background_px + r_px))))
      return true;
  }
  return false;
}

// The extension of `tip` along view v's skeleton (empty points if there is none), cut where a
// rule of extend.h stops it.
Extension ExtendInView(const std::vector<View2D>& views, const RigCalibration& rig, int v,
                       const SkeletonIndex& skeleton, const CaneLabels& labels, const Tip& tip,
                       double plane_y, const WorkingVolume& volume, const ExtendOptions& options) {
  Extension ext;
  const CameraCalibration& camera = rig.cameras[v];
  const std::optional<Eigen::Vector2d> uv_tip = camera.Project(tip.point);
  const std::optional<Eigen::Vector2d> uv_ahead =
      camera.Project(tip.point + options.step_m * tip.tangent);
  if (!uv_tip || !uv_ahead || !camera.InImage(*uv_tip)) return ext;
  const Eigen::Vector2d ahead = *uv_ahead - *uv_tip;
  const double step_px = ahead.norm();
  if (step_px < 0.5) return ext;  // the cane runs along the ray: depth is unobservable
  const auto snapped = skeleton.Nearest(*uv_tip, options.snap_px);
  if (!snapped) return ext;
  const auto [s, k] = *snapped;
  const std::vector<Eigen::Vector2d>& seg = views[v].segments[s].points;
  // Walk the way the cane points.
  const int n = static_cast<int>(seg.size());
  const Eigen::Vector2d local = seg[std::min(n - 1, k + 2)] - seg[std::max(0, k - 2)];
  const bool forward = local.dot(ahead) >= 0;
  const double max_px = step_px * (options.max_length_m / options.step_m + 2);
  const std::vector<Eigen::Vector2d> path =
      extend_internal::FollowSkeleton(views[v], s, k, forward, options.max_turn_rad, max_px);
  const Eigen::Vector2d start_dir = extend_internal::PathDirection(path, true);
  if (start_dir.dot(ahead.normalized()) < std::cos(options.max_turn_rad)) return ext;
  std::vector<Eigen::Vector2d> pixels = extend_internal::Resample(path, step_px);
  ext.view = v;
  if (pixels.size() >= static_cast<size_t>(options.max_length_m / options.step_m))
    ext.stop = ExtendStop::kMaxLength;
  // Up to where the path runs onto another model cane.
  size_t keep = 0;
  while (keep < pixels.size()) {
    const int label = labels.At(pixels[keep]);
    if (label >= 0 && label != tip.cane) {
      ext.stop = ExtendStop::kOtherCane;
      break;
    }
    ++keep;
  }
  pixels.resize(keep);
  if (pixels.empty()) return ext;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sd;
  SolveDepths(camera, tip.anchors, pixels, plane_y, options, &points, &sd);
  for (size_t i = 0; i < points.size(); ++i) {
    if (sd[i] > options.max_depth_sd_m) {
      ext.uncertain = true;
      ext.stop = ExtendStop::kUncertain;
      break;
    }
    if (!volume.Contains(points[i])) {
      ext.stop = ExtendStop::kVolume;
      break;
    }
    if (Contradicted(views, rig, v, points[i], tip.radius_m, options)) {
      ext.contradicted = true;
      ext.stop = ExtendStop::kContradicted;
      break;
    }
    ext.points.push_back(points[i]);
  }
  double ext_length = 0;
  for (size_t i = 0; i < ext.points.size(); ++i)
    ext_length += ((i == 0 ? tip.point : ext.points[i - 1]) - ext.points[i]).norm();
  if (ext_length < options.min_length_m) ext.points.clear();
  return ext;
}

}  // namespace

absl::Status ExtendOptions::Validate() const {
  for (const auto& [value, field] : {std::pair{step_m, "step_m"},
                                     {min_cane_length_m, "min_cane_length_m"},
                                     {snap_px, "snap_px"},
                                     {second_difference_sd_m, "second_difference_sd_m"},
                                     {plane_sd_m, "plane_sd_m"},
                                     {max_depth_sd_m, "max_depth_sd_m"},
                                     {max_length_m, "max_length_m"},
                                     {max_turn_rad, "max_turn_rad"}}) {
    if (absl::Status s = CheckPositive(value, "extend", field); !s.ok()) return s;
  }
  for (const auto& [value, field] : {std::pair{min_length_m, "min_length_m"},
                                     {anchor_span_m, "anchor_span_m"},
                                     {other_cane_px, "other_cane_px"},
                                     {background_px, "background_px"},
                                     {support_span_m, "support_span_m"},
                                     {max_support_px, "max_support_px"},
                                     {max_tip_row_distance_m, "max_tip_row_distance_m"},
                                     {max_tip_out_of_plane, "max_tip_out_of_plane"}}) {
    if (absl::Status s = CheckNonNegative(value, "extend", field); !s.ok()) return s;
  }
  if (anchor_points < 3) {
    return absl::InvalidArgumentError(
        absl::StrCat("extend.anchor_points must be >= 3, is ", anchor_points));
  }
  if (image_margin_px < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("extend.image_margin_px must be >= 0, is ", image_margin_px));
  }
  return absl::OkStatus();
}

absl::Status ExtendCanes(const std::vector<View2D>& views, const RigCalibration& rig,
                         const WorkingVolume& volume, const ExtendOptions& options,
                         VineModel* model, ExtendSummary* summary) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("views: ", views.size(), " for ", rig.cameras.size(), " cameras"));
  }
  ExtendSummary local;
  ExtendSummary& sum = summary != nullptr ? *summary : local;
  sum = ExtendSummary{};
  if (!options.enabled || model->canes.empty()) return absl::OkStatus();

  std::vector<double> ys;
  for (const Cane& cane : model->canes)
    for (const Eigen::Vector3d& p : cane.polyline.points) ys.push_back(p.y());
  std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
  const double plane_y = ys[ys.size() / 2];

  const int nv = static_cast<int>(views.size());
  std::vector<CaneLabels> labels;
  std::vector<SkeletonIndex> skeletons;
  for (int v = 0; v < nv; ++v) {
    labels.emplace_back(views[v].width, views[v].height);
    skeletons.emplace_back(views[v]);
    for (size_t c = 0; c < model->canes.size(); ++c) {
      const Polyline3& line = model->canes[c].polyline;
      double radius = 0;
      for (double r : line.radii) radius = std::max(radius, r);
      labels[v].Draw(rig.cameras[v], line.points, radius, options.other_cane_px, int(c));
    }
  }

  std::optional<double> trunk_x;
  for (const Cane& cane : model->canes)
    if (cane.kind == CaneKind::kTrunk && !cane.polyline.points.empty())
      trunk_x = cane.polyline.points.back().x();
  for (size_t c = 0; c < model->canes.size(); ++c) {
    Cane& cane = model->canes[c];
    if (cane.kind != CaneKind::kCane) continue;
    if (cane.polyline.Length() < options.min_cane_length_m) continue;
    ++sum.tips_tried;
    if (options.max_support_px > 0 &&
        TipSupportOf(cane.polyline, views, rig, options.support_span_m).worst_mean_px >
            options.max_support_px) {
      ++sum.tips_skipped;
      continue;
    }
    Tip tip;
    tip.cane = static_cast<int>(c);
    tip.anchors = extend_internal::TipAnchors(cane.polyline, options);
    tip.point = tip.anchors.back();
    tip.tangent = (tip.point - tip.anchors[tip.anchors.size() - 2]).normalized();
    tip.radius_m = cane.polyline.radii.back();
    if (extend_internal::FarOrAcross(tip.point, tip.tangent, trunk_x, options)) {
      ++sum.tips_skipped;
      continue;
    }

    Extension best;
    for (int v = 0; v < nv; ++v) {
      Extension ext = ExtendInView(views, rig, v, skeletons[v], labels[v], tip, plane_y, volume,
                                   options);
      if (ext.points.size() > best.points.size() ||
          (best.points.empty() && (ext.contradicted || ext.uncertain)))
        best = std::move(ext);
    }
    sum.contradicted += best.contradicted;
    sum.uncertain += best.uncertain;
    if (best.points.empty()) continue;
    ++sum.tips_extended;
    ExtendedTip record;
    record.cane = static_cast<int>(c);
    record.view = best.view;
    record.first_point = static_cast<int>(cane.polyline.points.size());
    record.points = static_cast<int>(best.points.size());
    record.stop = best.stop;
    for (const Eigen::Vector3d& p : best.points) {
      record.length_m += (p - cane.polyline.points.back()).norm();
      cane.polyline.points.push_back(p);
      cane.polyline.radii.push_back(tip.radius_m);
    }
    sum.added_length_m += record.length_m;
    sum.extended.push_back(record);
    std::vector<Eigen::Vector3d> drawn = {tip.point};
    drawn.insert(drawn.end(), best.points.begin(), best.points.end());
    for (int v = 0; v < nv; ++v)
      labels[v].Draw(rig.cameras[v], drawn, tip.radius_m, options.other_cane_px, int(c));
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
