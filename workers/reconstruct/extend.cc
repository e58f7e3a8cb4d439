// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/extend.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <unordered_set>

#include "Eigen/Dense"
#include "absl/strings/str_cat.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

// Per view: which model cane (index into model->canes) each pixel is near, -1 for none. The
// extension stops where its 2D path runs onto another cane: that wood is reconstructed already
// (or the path has switched to a cane it crosses).
class CaneLabels {
 public:
  CaneLabels(int width, int height) : width_(width), height_(height), label_(width * height, -1) {}

  void Draw(const CameraCalibration& camera, const std::vector<Eigen::Vector3d>& points,
            double radius_m, double margin_px, int label) {
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      const double length = (points[i + 1] - points[i]).norm();
      const int steps = std::max(1, static_cast<int>(std::ceil(length / 0.001)));
      for (int k = 0; k <= steps; ++k) {
        const Eigen::Vector3d p = points[i] + (points[i + 1] - points[i]) * (double(k) / steps);
        const std::optional<Eigen::Vector2d> uv = camera.Project(p);
        if (!uv || !camera.InImage(*uv)) continue;
        const double r = ProjectedRadiusPx(camera, p, radius_m) + margin_px;
        const int ri = static_cast<int>(std::ceil(r));
        const int cx = static_cast<int>(std::lround(uv->x()));
        const int cy = static_cast<int>(std::lround(uv->y()));
        for (int y = std::max(0, cy - ri); y <= std::min(height_ - 1, cy + ri); ++y) {
          for (int x = std::max(0, cx - ri); x <= std::min(width_ - 1, cx + ri); ++x) {
            if ((x - uv->x()) * (x - uv->x()) + (y - uv->y()) * (y - uv->y()) <= r * r)
              label_[static_cast<size_t>(y) * width_ + x] = label;
          }
        }
      }
    }
  }

  int At(const Eigen::Vector2d& uv) const {
    const int x = static_cast<int>(std::lround(uv.x()));
    const int y = static_cast<int>(std::lround(uv.y()));
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return -1;
    return label_[static_cast<size_t>(y) * width_ + x];
  }

 private:
  int width_, height_;
  std::vector<int> label_;
};

// Skeleton points of a view in 8 px cells, for finding the path under a projected tip.
class SkeletonIndex {
 public:
  explicit SkeletonIndex(const View2D& view) : view_(view) {
    cols_ = view.width / kCell + 1;
    rows_ = view.height / kCell + 1;
    cells_.resize(static_cast<size_t>(cols_) * rows_);
    for (size_t s = 0; s < view.segments.size(); ++s) {
      const std::vector<Eigen::Vector2d>& pts = view.segments[s].points;
      for (size_t k = 0; k < pts.size(); ++k) {
        const int cx = std::clamp(static_cast<int>(pts[k].x()) / kCell, 0, cols_ - 1);
        const int cy = std::clamp(static_cast<int>(pts[k].y()) / kCell, 0, rows_ - 1);
        cells_[static_cast<size_t>(cy) * cols_ + cx].push_back({int(s), int(k)});
      }
    }
  }

  // The skeleton point nearest to uv within r px: (segment, index), or nullopt.
  std::optional<std::pair<int, int>> Nearest(const Eigen::Vector2d& uv, double r) const {
    std::optional<std::pair<int, int>> best;
    double best_d2 = r * r;
    const int x0 = std::max(0, static_cast<int>((uv.x() - r) / kCell));
    const int x1 = std::min(cols_ - 1, static_cast<int>((uv.x() + r) / kCell));
    const int y0 = std::max(0, static_cast<int>((uv.y() - r) / kCell));
    const int y1 = std::min(rows_ - 1, static_cast<int>((uv.y() + r) / kCell));
    for (int cy = y0; cy <= y1; ++cy) {
      for (int cx = x0; cx <= x1; ++cx) {
        for (const auto& [s, k] : cells_[static_cast<size_t>(cy) * cols_ + cx]) {
          const double d2 = (view_.segments[s].points[k] - uv).squaredNorm();
          if (d2 <= best_d2) best_d2 = d2, best = std::make_pair(s, k);
        }
      }
    }
    return best;
  }

 private:
  static constexpr int kCell = 8;
  const View2D& view_;
  int cols_ = 0, rows_ = 0;
  std::vector<std::vector<std::pair<int, int>>> cells_;
};

// Unit direction of a 2D path over its first (from_front) or last ~`span` px.
Eigen::Vector2d PathDirection(const std::vector<Eigen::Vector2d>& pts, bool from_front,
                              double span = 6.0) {
  if (pts.size() < 2) return Eigen::Vector2d::Zero();
  const int n = static_cast<int>(pts.size());
  const Eigen::Vector2d anchor = from_front ? pts.front() : pts.back();
  Eigen::Vector2d other = from_front ? pts.back() : pts.front();
  for (int i = 1; i < n; ++i) {
    const Eigen::Vector2d& q = from_front ? pts[i] : pts[n - 1 - i];
    if ((q - anchor).norm() >= span) {
      other = q;
      break;
    }
  }
  const Eigen::Vector2d d =
      from_front ? Eigen::Vector2d(other - anchor) : Eigen::Vector2d(anchor - other);
  return d.norm() > 0 ? Eigen::Vector2d(d.normalized()) : Eigen::Vector2d::Zero();
}

// The skeleton path from point k of segment s, walking toward increasing indices (forward) or
// decreasing, through junctions where a path continues within max_turn; at most max_px long.
std::vector<Eigen::Vector2d> FollowSkeleton(const View2D& view, int s, int k, bool forward,
                                            double max_turn, double max_px) {
  std::vector<Eigen::Vector2d> path;
  std::unordered_set<int> visited;
  double length = 0;
  while (true) {
    visited.insert(s);
    const std::vector<Eigen::Vector2d>& pts = view.segments[s].points;
    const int n = static_cast<int>(pts.size());
    for (int i = k; i >= 0 && i < n; i += forward ? 1 : -1) {
      if (!path.empty()) length += (pts[i] - path.back()).norm();
      path.push_back(pts[i]);
      if (length >= max_px) return path;
    }
    const int node = forward ? view.segments[s].node_end : view.segments[s].node_begin;
    if (node < 0 || node >= static_cast<int>(view.nodes.size())) return path;
    const Eigen::Vector2d in = PathDirection(path, false);
    int best = -1;
    bool best_forward = true;
    double best_turn = max_turn;
    for (int s2 : view.nodes[node].segments) {
      if (visited.count(s2)) continue;
      const Segment2D& seg = view.segments[s2];
      for (bool f : {true, false}) {
        if ((f ? seg.node_begin : seg.node_end) != node) continue;
        std::vector<Eigen::Vector2d> pts2 = seg.points;
        if (!f) std::reverse(pts2.begin(), pts2.end());
        const Eigen::Vector2d out = PathDirection(pts2, true);
        const double turn = std::acos(std::clamp(in.dot(out), -1.0, 1.0));
        if (turn < best_turn) best_turn = turn, best = s2, best_forward = f;
      }
    }
    if (best < 0) return path;
    s = best;
    forward = best_forward;
    k = forward ? 0 : static_cast<int>(view.segments[s].points.size()) - 1;
  }
}

// Points of `path` every `step` px of arc length, starting `step` past its first point.
std::vector<Eigen::Vector2d> Resample(const std::vector<Eigen::Vector2d>& path, double step) {
  std::vector<Eigen::Vector2d> out;
  double next = step, at = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const double seg = (path[i + 1] - path[i]).norm();
    while (seg > 0 && next <= at + seg) {
      out.push_back(path[i] + (path[i + 1] - path[i]) * ((next - at) / seg));
      next += step;
    }
    at += seg;
  }
  return out;
}

// The largest, over the views, of the mean distance (px) from the projections of the cane's
// last span_m (every 5 mm; those inside the image) to the nearest skeleton point.
double WorstSupportPx(const Polyline3& line, const std::vector<View2D>& views,
                      const RigCalibration& rig, double span_m) {
  const std::vector<double> arc = line.ArcLengths();
  const double length = arc.back();
  std::vector<Eigen::Vector3d> samples;
  for (double s = std::max(0.0, length - span_m); s <= length + 1e-9; s += 0.005)
    samples.push_back(line.PointAt(s, arc));
  double worst = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    const CameraCalibration& camera = rig.cameras[v];
    const View2D& view = views[v];
    if (!HasCentrelineDistance(view)) continue;
    double sum = 0;
    int n = 0;
    for (const Eigen::Vector3d& p : samples) {
      const std::optional<Eigen::Vector2d> uv = camera.Project(p);
      if (!uv || !camera.InImage(*uv)) continue;
      sum += CentrelineDistanceAt(view, *uv);
      ++n;
    }
    if (n > 0) worst = std::max(worst, sum / n);
  }
  return worst;
}

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
    const double length = cane.polyline.Length();
    if (length < options.min_cane_length_m) continue;
    ++sum.tips_tried;
    if (options.max_support_px > 0 &&
        WorstSupportPx(cane.polyline, views, rig, options.support_span_m) >
            options.max_support_px) {
      ++sum.tips_skipped;
      continue;
    }
    const std::vector<double> arc = cane.polyline.ArcLengths();
    std::vector<Eigen::Vector3d> anchors;
    for (int k = options.anchor_points - 1; k >= 0; --k)
      anchors.push_back(cane.polyline.PointAt(std::max(0.0, length - k * options.step_m), arc));
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
        samples.emplace_back(s_i, cane.polyline.PointAt(s_i, arc));
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
      const Eigen::Vector3d tip_point = cane.polyline.points.back();
      for (int k = 0; k < options.anchor_points; ++k)
        anchors[k] = tip_point - (options.anchor_points - 1 - k) * options.step_m * slope;
    }
    const Eigen::Vector3d tip = anchors.back();
    const Eigen::Vector3d tangent = (tip - anchors[anchors.size() - 2]).normalized();
    const double tip_radius = cane.polyline.radii.back();
    // Tips of which a wrong one is likelier than a right one is useful (docs/reconstruction.md,
    // step 4c, "Which tips"): far along the row, where neighbours' canes run along the same
    // wires, and tips pointing toward or away from the cameras, mostly mis-depthed ends.
    if ((options.max_tip_row_distance_m > 0 && trunk_x &&
         std::abs(tip.x() - *trunk_x) > options.max_tip_row_distance_m) ||
        (options.max_tip_out_of_plane > 0 &&
         std::abs(tangent.y()) > options.max_tip_out_of_plane)) {
      ++sum.tips_skipped;
      continue;
    }

    Extension best;
    for (int v = 0; v < nv; ++v) {
      const CameraCalibration& camera = rig.cameras[v];
      const std::optional<Eigen::Vector2d> uv_tip = camera.Project(tip);
      const std::optional<Eigen::Vector2d> uv_ahead =
          camera.Project(tip + options.step_m * tangent);
      if (!uv_tip || !uv_ahead || !camera.InImage(*uv_tip)) continue;
      const Eigen::Vector2d ahead = *uv_ahead - *uv_tip;
      const double step_px = ahead.norm();
      if (step_px < 0.5) continue;  // the cane runs along the ray: depth is unobservable
      const auto snapped = skeletons[v].Nearest(*uv_tip, options.snap_px);
      if (!snapped) continue;
      const auto [s, k] = *snapped;
      const std::vector<Eigen::Vector2d>& seg = views[v].segments[s].points;
      // Walk the way the cane points.
      const int n = static_cast<int>(seg.size());
      const Eigen::Vector2d local = seg[std::min(n - 1, k + 2)] - seg[std::max(0, k - 2)];
      const bool forward = local.dot(ahead) >= 0;
      const double max_px = step_px * (options.max_length_m / options.step_m + 2);
      const std::vector<Eigen::Vector2d> path =
          FollowSkeleton(views[v], s, k, forward, options.max_turn_rad, max_px);
      const Eigen::Vector2d start_dir = PathDirection(path, true);
      if (start_dir.dot(ahead.normalized()) < std::cos(options.max_turn_rad)) continue;
      std::vector<Eigen::Vector2d> pixels = Resample(path, step_px);
      Extension ext;
      ext.view = v;
      if (pixels.size() >= static_cast<size_t>(options.max_length_m / options.step_m))
        ext.stop = ExtendStop::kMaxLength;
      // Up to where the path runs onto another model cane.
      size_t keep = 0;
      while (keep < pixels.size()) {
        const int label = labels[v].At(pixels[keep]);
        if (label >= 0 && label != static_cast<int>(c)) {
          ext.stop = ExtendStop::kOtherCane;
          break;
        }
        ++keep;
      }
      pixels.resize(keep);
      if (pixels.empty()) continue;
      std::vector<Eigen::Vector3d> points;
      std::vector<double> sd;
      SolveDepths(camera, anchors, pixels, plane_y, options, &points, &sd);
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
        bool contradicted = false;
        for (int w = 0; w < nv && !contradicted; ++w) {
          if (w == v) continue;
          const CameraCalibration& other = rig.cameras[w];
          const std::optional<Eigen::Vector2d> uv =
              ProjectInside(other, points[i], options.image_margin_px);
          if (!uv) continue;
          const double r_px = ProjectedRadiusPx(other, points[i], tip_radius);
          contradicted =
              !WoodNear(views[w], *uv, static_cast<int>(std::ceil(options.background_px + r_px)));
        }
        if (contradicted) {
          ext.contradicted = true;
          ext.stop = ExtendStop::kContradicted;
          break;
        }
        ext.points.push_back(points[i]);
      }
      double ext_length = 0;
      for (size_t i = 0; i < ext.points.size(); ++i)
        ext_length += ((i == 0 ? tip : ext.points[i - 1]) - ext.points[i]).norm();
      if (ext_length < options.min_length_m) ext.points.clear();
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
      cane.polyline.radii.push_back(tip_radius);
    }
    sum.added_length_m += record.length_m;
    sum.extended.push_back(record);
    std::vector<Eigen::Vector3d> drawn = {tip};
    drawn.insert(drawn.end(), best.points.begin(), best.points.end());
    for (int v = 0; v < nv; ++v)
      labels[v].Draw(rig.cameras[v], drawn, tip_radius, options.other_cane_px, int(c));
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
