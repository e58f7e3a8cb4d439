// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/match_candidates.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vb::reconstruct {
namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

SegmentSamples Resample(const Segment2D& segment, const CameraCalibration& camera,
                        double step_px) {
  SegmentSamples out;
  const auto& p = segment.points;
  if (p.empty()) return out;
  const bool has_widths = segment.widths_px.size() == p.size();
  auto width_at = [&](size_t i) { return has_widths ? segment.widths_px[i] : 1.0; };
  out.pixel.push_back(p[0]);
  out.arc_px.push_back(0.0);
  std::vector<double> widths_px{width_at(0)};
  double arc = 0.0;
  double next = step_px;
  for (size_t i = 1; i < p.size(); ++i) {
    const double len = (p[i] - p[i - 1]).norm();
    if (len <= 0.0) continue;
    while (next <= arc + len) {
      const double f = (next - arc) / len;
      out.pixel.push_back(p[i - 1] + f * (p[i] - p[i - 1]));
      out.arc_px.push_back(next);
      widths_px.push_back((1.0 - f) * width_at(i - 1) + f * width_at(i));
      next += step_px;
    }
    arc += len;
  }
  if (arc - out.arc_px.back() > 0.25 * step_px) {
    out.pixel.push_back(p.back());
    out.arc_px.push_back(arc);
    widths_px.push_back(width_at(p.size() - 1));
  }
  const size_t n = out.pixel.size();
  out.normalised.resize(n);
  for (size_t i = 0; i < n; ++i) out.normalised[i] = camera.PixelToNormalised(out.pixel[i]);
  out.tangent.resize(n, Eigen::Vector2d::UnitX());
  out.width.resize(n, 0.0);
  for (size_t i = 0; i < n && n >= 2; ++i) {
    const size_t lo = i == 0 ? 0 : i - 1;
    const size_t hi = i + 1 == n ? n - 1 : i + 1;
    const Eigen::Vector2d d = out.normalised[hi] - out.normalised[lo];
    if (d.norm() > 0.0) out.tangent[i] = d.normalized();
    // Width across the path through the local distortion: map a pixel-unit normal step.
    const Eigen::Vector2d dp = out.pixel[hi] - out.pixel[lo];
    if (dp.norm() > 0.0) {
      const Eigen::Vector2d normal_px(-dp.y() / dp.norm(), dp.x() / dp.norm());
      const double scale =
          (camera.PixelToNormalised(out.pixel[i] + normal_px) - out.normalised[i]).norm();
      out.width[i] = widths_px[i] * scale;
    }
  }
  return out;
}

// Parameter range [lo, hi] of the ray c + s d inside the box (slab method); false if none.
bool ClipRay(const Eigen::Vector3d& c, const Eigen::Vector3d& d, const Eigen::AlignedBox3d& box,
             double* lo, double* hi) {
  double t0 = 0.0;
  double t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (c[k] < box.min()[k] || c[k] > box.max()[k]) return false;
      continue;
    }
    double a = (box.min()[k] - c[k]) / d[k];
    double b = (box.max()[k] - c[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  *lo = t0;
  *hi = t1;
  return t0 < t1 && std::isfinite(t1);
}

struct Open {
  std::vector<EpipolarHit> hits;
};

}  // namespace

ViewSamples::ViewSamples(const View2D& view, const CameraCalibration& camera, double step_px,
                         const std::vector<StrandHalf>* halves) {
  segments_.reserve(view.segments.size() + (halves ? halves->size() : 0));
  for (const Segment2D& s : view.segments) segments_.push_back(Resample(s, camera, step_px));
  if (halves) {
    for (const StrandHalf& h : *halves) segments_.push_back(Resample(h.path, camera, step_px));
  }
  Eigen::AlignedBox2d bounds;
  int pieces = 0;
  for (const SegmentSamples& s : segments_) {
    piece_base_.push_back(pieces);
    pieces += static_cast<int>(std::max<size_t>(s.normalised.size(), 1) - 1);
    for (const Eigen::Vector2d& p : s.normalised) bounds.extend(p);
  }
  stamp_.assign(pieces, -1);
  if (pieces == 0) return;
  const double f = std::max(1.0, camera.camera_matrix(0, 0));
  cell_ = std::max(16.0 / f, 1e-6);
  // Keep the grid bounded whatever the distortion does at the edges.
  const Eigen::Vector2d size = bounds.sizes();
  cell_ = std::max({cell_, size.x() / 256.0, size.y() / 256.0});
  origin_ = bounds.min() - Eigen::Vector2d::Constant(cell_);
  nx_ = static_cast<int>(size.x() / cell_) + 3;
  ny_ = static_cast<int>(size.y() / cell_) + 3;
  cells_.assign(static_cast<size_t>(nx_) * ny_, {});
  for (int si = 0; si < static_cast<int>(segments_.size()); ++si) {
    const auto& q = segments_[si].normalised;
    for (int k = 0; k + 1 < static_cast<int>(q.size()); ++k) {
      int x0, y0, x1, y1;
      CellOf(q[k].cwiseMin(q[k + 1]), &x0, &y0);
      CellOf(q[k].cwiseMax(q[k + 1]), &x1, &y1);
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) cells_[static_cast<size_t>(y) * nx_ + x].push_back({si, k});
      }
    }
  }
}

void ViewSamples::CellOf(const Eigen::Vector2d& p, int* cx, int* cy) const {
  const double fx = std::floor((p.x() - origin_.x()) / cell_);
  const double fy = std::floor((p.y() - origin_.y()) / cell_);
  *cx = static_cast<int>(std::clamp(fx, 0.0, static_cast<double>(nx_ - 1)));
  *cy = static_cast<int>(std::clamp(fy, 0.0, static_cast<double>(ny_ - 1)));
}

void ViewSamples::PiecesNearSegment(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                    std::vector<std::pair<int, int>>* out) const {
  out->clear();
  if (cells_.empty() || !p0.allFinite() || !p1.allFinite()) return;
  ++query_;
  auto visit = [&](int cx, int cy) {
    for (const auto& piece : cells_[static_cast<size_t>(cy) * nx_ + cx]) {
      int& stamp = stamp_[piece_base_[piece.first] + piece.second];
      if (stamp == query_) continue;
      stamp = query_;
      out->push_back(piece);
    }
  };
  // Amanatides-Woo traversal of the cells the segment passes through (clamped to the grid:
  // pieces exist only inside it, so cells outside hold nothing).
  const Eigen::Vector2d a = (p0 - origin_) / cell_;
  const Eigen::Vector2d b = (p1 - origin_) / cell_;
  const Eigen::Vector2d d = b - a;
  const double length = d.norm();
  const int steps_max = static_cast<int>(std::abs(d.x()) + std::abs(d.y())) + 4;
  int cx = static_cast<int>(std::floor(a.x()));
  int cy = static_cast<int>(std::floor(a.y()));
  const int sx = d.x() > 0 ? 1 : -1;
  const int sy = d.y() > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  double tmx = d.x() != 0.0 ? ((sx > 0 ? cx + 1 - a.x() : a.x() - cx) / std::abs(d.x())) : inf;
  double tmy = d.y() != 0.0 ? ((sy > 0 ? cy + 1 - a.y() : a.y() - cy) / std::abs(d.y())) : inf;
  const double tdx = d.x() != 0.0 ? 1.0 / std::abs(d.x()) : inf;
  const double tdy = d.y() != 0.0 ? 1.0 / std::abs(d.y()) : inf;
  for (int step = 0; step <= steps_max; ++step) {
    if (cx >= 0 && cy >= 0 && cx < nx_ && cy < ny_) visit(cx, cy);
    if (length == 0.0 || std::min(tmx, tmy) > 1.0) break;
    if (tmx < tmy) {
      cx += sx;
      tmx += tdx;
    } else {
      cy += sy;
      tmy += tdy;
    }
  }
}

bool ViewSamples::NearestPiece(const Eigen::Vector2d& p, double radius, double* distance,
                               Eigen::Vector2d* direction, Eigen::Vector2d* closest) const {
  if (cells_.empty() || !p.allFinite()) return false;
  int x0, y0, x1, y1;
  CellOf(p - Eigen::Vector2d::Constant(radius), &x0, &y0);
  CellOf(p + Eigen::Vector2d::Constant(radius), &x1, &y1);
  double best = radius;
  bool found = false;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      for (const auto& [si, k] : cells_[static_cast<size_t>(y) * nx_ + x]) {
        const Eigen::Vector2d& q0 = segments_[si].normalised[k];
        const Eigen::Vector2d& q1 = segments_[si].normalised[k + 1];
        const Eigen::Vector2d e = q1 - q0;
        const double len2 = e.squaredNorm();
        const double t = len2 > 0.0 ? std::clamp((p - q0).dot(e) / len2, 0.0, 1.0) : 0.0;
        const double dist = (q0 + t * e - p).norm();
        if (dist <= best) {
          best = dist;
          found = true;
          *direction = len2 > 0.0 ? Eigen::Vector2d(e / std::sqrt(len2)) : Eigen::Vector2d::UnitX();
          if (closest) *closest = q0 + t * e;
        }
      }
    }
  }
  if (found) *distance = best;
  return found;
}

std::vector<MatchCandidate> FindCandidates(int view_a, const ViewSamples& a,
                                           const CameraCalibration& camera_a, int view_b,
                                           const ViewSamples& b,
                                           const CameraCalibration& camera_b,
                                           const CandidateOptions& options) {
  std::vector<MatchCandidate> candidates;
  const Eigen::Matrix3d ra = camera_a.rotation_camera_from_platform;
  const Eigen::Matrix3d rb = camera_b.rotation_camera_from_platform;
  const Eigen::Vector3d tb = camera_b.translation_camera_from_platform;
  const Eigen::Vector3d ca = camera_a.CentreInPlatform();
  const Eigen::Vector3d cb = camera_b.CentreInPlatform();
  const Eigen::Vector3d baseline = cb - ca;
  const Eigen::Vector3d a_in_b = rb * ca + tb;  // A: camera a's centre in b's frame
  constexpr double kMinZ = 1e-3;
  std::vector<std::pair<int, int>> pieces;
  std::vector<std::pair<int, EpipolarHit>> hits;  // (segment_b, hit)

  // conditioned_before[i]: samples before i of the segment that were searched (not skipped as
  // too near their epipolar line). Gaps of a run are counted in searched samples.
  std::vector<int> conditioned_before;
  for (int si = 0; si < static_cast<int>(a.segments().size()); ++si) {
    const SegmentSamples& s = a.segments()[si];
    hits.clear();
    conditioned_before.assign(s.normalised.size() + 1, 0);
    for (int i = 0; i < static_cast<int>(s.normalised.size()); ++i) {
      conditioned_before[i + 1] = conditioned_before[i];
      const Eigen::Vector2d& x = s.normalised[i];
      const Eigen::Vector3d d = (ra.transpose() * Eigen::Vector3d(x.x(), x.y(), 1.0)).normalized();
      // Epipolar plane normal in a's frame gives the epipolar line's direction at x.
      const Eigen::Vector3d plane_in_a = ra * baseline.cross(d);
      const double plane_xy = plane_in_a.head<2>().norm();
      if (plane_xy < 1e-12) continue;
      const double sin_a = std::abs(s.tangent[i].dot(plane_in_a.head<2>())) / plane_xy;
      if (sin_a < options.min_epipolar_sin) continue;
      ++conditioned_before[i + 1];
      double lo, hi;
      if (!ClipRay(ca, d, options.volume.box, &lo, &hi)) continue;
      const Eigen::Vector3d db = rb * d;  // B: the ray direction in b's frame
      if (std::abs(db.z()) < 1e-12) {
        if (a_in_b.z() <= kMinZ) continue;
      } else {
        const double s_z = (kMinZ - a_in_b.z()) / db.z();
        if (db.z() > 0) lo = std::max(lo, s_z); else hi = std::min(hi, s_z);
      }
      if (!(lo < hi)) continue;
      const Eigen::Vector2d e0 = (a_in_b + lo * db).hnormalized();
      const Eigen::Vector2d e1 = (a_in_b + hi * db).hnormalized();
      const Eigen::Vector2d e = e1 - e0;
      if (!(e.norm() > 0.0)) continue;
      const Eigen::Vector2d e_unit = e.normalized();
      b.PiecesNearSegment(e0, e1, &pieces);
      for (const auto& [ti, k] : pieces) {
        const SegmentSamples& t = b.segments()[ti];
        const Eigen::Vector2d& q0 = t.normalised[k];
        const Eigen::Vector2d q = t.normalised[k + 1] - q0;
        const double den = Cross(e, q);
        if (std::abs(den) < 1e-15) continue;
        const Eigen::Vector2d w = q0 - e0;
        const double alpha = Cross(w, q) / den;
        const double beta = Cross(w, e) / den;
        const bool last_piece = k + 2 == static_cast<int>(t.normalised.size());
        if (alpha < 0.0 || alpha > 1.0 || beta < 0.0 || beta > 1.0) continue;
        if (beta == 1.0 && !last_piece) continue;  // counted by the next piece
        const Eigen::Vector2d h = q0 + beta * q;
        // Depth along a's ray from the crossing: (A + s B).xy / (A + s B).z = h.
        const double den_x = db.x() - h.x() * db.z();
        const double den_y = db.y() - h.y() * db.z();
        const double depth = std::abs(den_x) > std::abs(den_y)
                                 ? (h.x() * a_in_b.z() - a_in_b.x()) / den_x
                                 : (h.y() * a_in_b.z() - a_in_b.y()) / den_y;
        if (!std::isfinite(depth) || depth <= 0.0) continue;
        EpipolarHit hit;
        hit.sample_a = i;
        hit.xa = x;
        hit.xb = h;
        const Eigen::Vector2d q_unit = q.normalized();
        hit.normal_b = Eigen::Vector2d(-q_unit.y(), q_unit.x());
        hit.point = ca + depth * d;
        hit.arc_a_px = s.arc_px[i];
        hit.arc_b_px = t.arc_px[k] + beta * (t.arc_px[k + 1] - t.arc_px[k]);
        hit.depth_a = depth;
        hit.width_a = s.width[i];
        hit.width_b = (1.0 - beta) * t.width[k] + beta * t.width[k + 1];
        hit.sin_a = sin_a;
        hit.sin_b = std::abs(Cross(e_unit, q_unit));
        hits.push_back({ti, hit});
      }
    }
    if (hits.empty()) continue;
    std::stable_sort(hits.begin(), hits.end(),
                     [](const auto& l, const auto& r) { return l.first < r.first; });
    // Group each segment_b's hits into runs of consistent depth (greedy, in sample order).
    for (size_t begin = 0; begin < hits.size();) {
      size_t end = begin;
      while (end < hits.size() && hits[end].first == hits[begin].first) ++end;
      std::vector<Open> runs;
      for (size_t h = begin; h < end; ++h) {
        const EpipolarHit& hit = hits[h].second;
        int best = -1;
        double best_error = std::numeric_limits<double>::infinity();
        for (int r = 0; r < static_cast<int>(runs.size()); ++r) {
          const EpipolarHit& last = runs[r].hits.back();
          const int gap = hit.sample_a - last.sample_a;
          if (gap <= 0) continue;
          // Searched samples skipped; plus, up to a limit, samples not searched because the
          // segment ran along the epipolar line there (the run resumes where it turns away).
          const int searched_gap =
              conditioned_before[hit.sample_a] - conditioned_before[last.sample_a + 1];
          if (searched_gap > options.max_gap_samples ||
              gap - 1 > options.max_gap_samples + options.max_ill_conditioned_gap_samples) {
            continue;
          }
          const double lateral = (hit.xa - last.xa).norm() * hit.depth_a;
          const double depth_error = std::abs(hit.depth_a - last.depth_a);
          if (depth_error > options.depth_tolerance_m + options.max_depth_slope * lateral) continue;
          const double da = std::abs(hit.arc_a_px - last.arc_a_px);
          if (std::abs(hit.arc_b_px - last.arc_b_px) > 4.0 * da + 4.0) continue;
          if (depth_error < best_error) {
            best_error = depth_error;
            best = r;
          }
        }
        if (best < 0) {
          runs.push_back({});
          best = static_cast<int>(runs.size()) - 1;
        }
        runs[best].hits.push_back(hit);
      }
      for (Open& run : runs) {
        if (static_cast<int>(run.hits.size()) < options.min_hits) continue;
        MatchCandidate c;
        c.view_a = view_a;
        c.segment_a = si;
        c.view_b = view_b;
        c.segment_b = hits[begin].first;
        c.begin_a_px = run.hits.front().arc_a_px;
        c.end_a_px = run.hits.back().arc_a_px;
        c.begin_b_px = std::numeric_limits<double>::infinity();
        c.end_b_px = -std::numeric_limits<double>::infinity();
        for (const EpipolarHit& hit : run.hits) {
          c.begin_b_px = std::min(c.begin_b_px, hit.arc_b_px);
          c.end_b_px = std::max(c.end_b_px, hit.arc_b_px);
        }
        c.length_a_px = s.arc_px.back();
        c.length_b_px = b.segments()[c.segment_b].arc_px.back();
        c.hits = std::move(run.hits);
        candidates.push_back(std::move(c));
      }
      begin = end;
    }
  }
  return candidates;
}

}  // namespace vb::reconstruct
