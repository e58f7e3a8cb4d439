// SPDX-License-Identifier: Apache-2.0
// Following a view's skeleton in 2D for the single-view extension (extend_internal.h).
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "workers/reconstruct/extend_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct::extend_internal {

CaneLabels::CaneLabels(int width, int height)
    : width_(width), height_(height), label_(width * height, -1) {}

void CaneLabels::Draw(const CameraCalibration& camera, const std::vector<Eigen::Vector3d>& points,
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

int CaneLabels::At(const Eigen::Vector2d& uv) const {
  const int x = static_cast<int>(std::lround(uv.x()));
  const int y = static_cast<int>(std::lround(uv.y()));
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return -1;
  return label_[static_cast<size_t>(y) * width_ + x];
}

SkeletonIndex::SkeletonIndex(const View2D& view) : view_(view) {
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

std::optional<std::pair<int, int>> SkeletonIndex::Nearest(const Eigen::Vector2d& uv,
                                                          double r) const {
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

Eigen::Vector2d PathDirection(const std::vector<Eigen::Vector2d>& pts, bool from_front,
                              double span) {
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

}  // namespace vb::reconstruct::extend_internal
