// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/trellis3d.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "Eigen/Eigenvalues"

namespace vb::reconstruct {
namespace {

struct Plane {
  Eigen::Vector3d normal;  // unit
  double offset;           // normal . x + offset = 0
};

Plane BackProject(const CameraCalibration& camera, const Line2D& line) {
  // l . x_cam = 0 for points on the line; x_cam = R x + t.
  const Eigen::Vector3d l = line.line;
  const Eigen::Vector3d n = camera.rotation_camera_from_platform.transpose() * l;
  const double scale = n.norm();
  return {n / scale, l.dot(camera.translation_camera_from_platform) / scale};
}

struct Line3 {
  Eigen::Vector3d point;
  Eigen::Vector3d direction;  // unit
};

std::optional<Line3> Intersect(const Plane& a, const Plane& b, double min_sin) {
  const Eigen::Vector3d d = a.normal.cross(b.normal);
  const double s = d.norm();
  if (s < min_sin) return std::nullopt;
  // The point on the line nearest the origin solves n_a.x = -d_a, n_b.x = -d_b, d.x = 0.
  Eigen::Matrix3d m;
  m.row(0) = a.normal;
  m.row(1) = b.normal;
  m.row(2) = d / s;
  const Eigen::Vector3d p = m.colPivHouseholderQr().solve(Eigen::Vector3d(-a.offset, -b.offset, 0));
  if (!p.allFinite()) return std::nullopt;
  return Line3{p, d / s};
}

// RMS pixel distance of the 3D segment [p, q]'s projection to the nearest of `lines` in `view`
// (nullopt if fewer than 3 of its samples are in the image); *nearest is that line's index.
std::optional<double> Residual(const CameraCalibration& camera, const std::vector<Line2D>& lines,
                               const Eigen::Vector3d& p, const Eigen::Vector3d& q, int* nearest) {
  double best = 1e9;
  *nearest = -1;
  for (size_t i = 0; i < lines.size(); ++i) {
    const Line2D& line = lines[i];
    double sum = 0;
    int n = 0;
    for (int k = 0; k <= 10; ++k) {
      const Eigen::Vector3d x = p + (q - p) * (k / 10.0);
      const auto uv = camera.Project(x);
      if (!uv || !camera.InImage(*uv)) continue;
      const Eigen::Vector2d xy = camera.PixelToNormalised(*uv);
      const double d = line.line.dot(xy.homogeneous()) * camera.camera_matrix(0, 0);
      sum += d * d;
      ++n;
    }
    if (n < 3) return std::nullopt;
    if (std::sqrt(sum / n) < best) {
      best = std::sqrt(sum / n);
      *nearest = static_cast<int>(i);
    }
  }
  return best;
}

struct Candidate {
  Eigen::Vector3d a, b;   // end points in the volume
  double residual;        // worst confirming residual (0 if no other view could confirm)
  int confirmations;
  int view_a, line_a, view_b, line_b;
  std::vector<int> lines;  // per view: the 2D line it was built from or confirmed by, or -1
  double width_px;
  std::vector<Eigen::Vector3d> polyline;  // wires with fit_sag: the fitted knots (else a, b)
};

// Clips the 3D line to the volume along its main axis (0 = x for wires, 2 = z for posts).
bool Clip(const Line3& line, const WorkingVolume& volume, int axis, double max_slope,
          Eigen::Vector3d* a, Eigen::Vector3d* b) {
  if (std::abs(line.direction[axis]) < 1e-6) return false;
  const Eigen::Vector3d dir = line.direction / line.direction[axis];
  for (int k = 0; k < 3; ++k)
    if (k != axis && std::abs(dir[k]) > max_slope) return false;
  const double lo = axis == 2 ? std::max(0.0, volume.box.min().z()) : volume.box.min()[axis];
  *a = line.point + dir * (lo - line.point[axis]);
  *b = line.point + dir * (volume.box.max()[axis] - line.point[axis]);
  const Eigen::Vector3d mid = 0.5 * (*a + *b);
  for (int k = 0; k < 3; ++k)
    if (k != axis && (mid[k] < volume.box.min()[k] || mid[k] > volume.box.max()[k])) return false;
  return true;
}

// Replaces a chosen candidate's line, the intersection of two views' planes, by the line nearest
// (least squares, in metres from each plane) to the planes of every view that saw it: with
// three views this averages the two lower cameras' errors instead of taking one of them.
void FitToAllViews(const std::vector<View2D>& views, const RigCalibration& rig,
                   const WorkingVolume& volume, const TrellisOptions& options, bool posts,
                   Candidate* c) {
  std::vector<Plane> planes;
  for (size_t v = 0; v < views.size(); ++v) {
    if (c->lines[v] < 0) continue;
    const auto& lines = posts ? views[v].posts : views[v].wires;
    planes.push_back(BackProject(rig.cameras[v], lines[static_cast<size_t>(c->lines[v])]));
  }
  if (planes.size() < 3) return;
  Eigen::Matrix3d normals = Eigen::Matrix3d::Zero();
  for (const Plane& p : planes) normals += p.normal * p.normal.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(normals);
  const Eigen::Vector3d direction = solver.eigenvectors().col(0);  // least explained by normals
  Eigen::Matrix3d a = direction * direction.transpose();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Plane& p : planes) {
    a += p.normal * p.normal.transpose();
    b -= p.normal * p.offset;
  }
  const Eigen::Vector3d point = a.ldlt().solve(b);
  if (!point.allFinite() || !direction.allFinite()) return;
  Eigen::Vector3d ea, eb;
  if (!Clip({point, direction}, volume, posts ? 2 : 0,
            posts ? options.max_post_tilt : options.max_wire_slope, &ea, &eb)) {
    return;
  }
  c->a = ea;
  c->b = eb;
}

std::vector<Candidate> Choose(std::vector<Candidate> candidates, const TrellisOptions& options,
                              size_t view_count) {
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    if (x.confirmations != y.confirmations) return x.confirmations > y.confirmations;
    return x.residual < y.residual;
  });
  std::vector<std::vector<int>> used(view_count);
  std::vector<Candidate> chosen;
  for (const Candidate& c : candidates) {
    auto taken = [&](int v, int l) {
      return std::find(used[v].begin(), used[v].end(), l) != used[v].end();
    };
    if (taken(c.view_a, c.line_a) || taken(c.view_b, c.line_b)) continue;
    bool duplicate = false;
    for (const Candidate& k : chosen) {
      const Eigen::Vector3d mid = 0.5 * (c.a + c.b);
      duplicate = duplicate || PointSegmentDistance(mid, k.a, k.b) < options.duplicate_distance_m;
    }
    if (duplicate) continue;
    used[c.view_a].push_back(c.line_a);
    used[c.view_b].push_back(c.line_b);
    chosen.push_back(c);
  }
  return chosen;
}

std::vector<Candidate> Candidates(const std::vector<View2D>& views, const RigCalibration& rig,
                                  const WorkingVolume& volume, const TrellisOptions& options,
                                  bool posts) {
  const double min_sin = std::sin(options.min_plane_angle_deg * M_PI / 180.0);
  std::vector<Candidate> out;
  for (size_t va = 0; va < views.size(); ++va)
    for (size_t vb = va + 1; vb < views.size(); ++vb) {
      const auto& la = posts ? views[va].posts : views[va].wires;
      const auto& lb = posts ? views[vb].posts : views[vb].wires;
      for (size_t i = 0; i < la.size(); ++i)
        for (size_t j = 0; j < lb.size(); ++j) {
          const auto line = Intersect(BackProject(rig.cameras[va], la[i]),
                                      BackProject(rig.cameras[vb], lb[j]), min_sin);
          if (!line) continue;
          Candidate c;
          if (!Clip(*line, volume, posts ? 2 : 0,
                    posts ? options.max_post_tilt : options.max_wire_slope, &c.a, &c.b)) {
            continue;
          }
          c.residual = 0.0;
          c.confirmations = 0;
          c.lines.assign(views.size(), -1);
          c.lines[va] = static_cast<int>(i);
          c.lines[vb] = static_cast<int>(j);
          bool rejected = false;
          for (size_t v = 0; v < views.size() && !rejected; ++v) {
            if (v == va || v == vb) continue;
            int nearest = -1;
            const auto r = Residual(rig.cameras[v], posts ? views[v].posts : views[v].wires, c.a,
                                    c.b, &nearest);
            if (!r) continue;
            if (*r > options.max_residual_px) rejected = true;
            c.residual = std::max(c.residual, *r);
            c.lines[v] = nearest;
            ++c.confirmations;
          }
          // With three or more views, an unconfirmed line is as likely a mismatch as not.
          if (rejected || (views.size() >= 3 && c.confirmations == 0)) continue;
          c.view_a = static_cast<int>(va);
          c.line_a = static_cast<int>(i);
          c.view_b = static_cast<int>(vb);
          c.line_b = static_cast<int>(j);
          c.width_px = 0.5 * (la[i].width_px + lb[j].width_px);
          out.push_back(c);
        }
    }
  return out;
}

double RadiusFromWidth(const RigCalibration& rig, const Candidate& c, double lo, double hi) {
  const CameraCalibration& camera = rig.cameras[c.view_a];
  const double depth = (camera.camera_from_platform() * (0.5 * (c.a + c.b))).z();
  return std::clamp(0.5 * c.width_px * depth / camera.camera_matrix(0, 0), lo, hi);
}

}  // namespace

absl::Status TrellisOptions::Validate() const {
  for (auto [v, name] : {std::pair{min_plane_angle_deg, "min_plane_angle_deg"},
                         {max_residual_px, "max_residual_px"},
                         {duplicate_distance_m, "duplicate_distance_m"},
                         {max_wire_slope, "max_wire_slope"}, {max_post_tilt, "max_post_tilt"}}) {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("trellis options: ", name, " must be > 0"));
  }
  if (absl::Status s = wire_fit.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("trellis options: wire_fit: ", std::string(s.message())));
  }
  return absl::OkStatus();
}

absl::StatusOr<Trellis> ReconstructTrellis(const std::vector<View2D>& views,
                                           const RigCalibration& rig, const WorkingVolume& volume,
                                           const TrellisOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("trellis: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  Trellis trellis;
  std::vector<Candidate> wires =
      Choose(Candidates(views, rig, volume, options, false), options, views.size());
  if (options.fit_all_views)
    for (Candidate& c : wires) FitToAllViews(views, rig, volume, options, false, &c);
  if (options.fit_sag)
    for (Candidate& c : wires) c.polyline = FitWirePolyline(views, rig, c.a, c.b, options.wire_fit);
  std::sort(wires.begin(), wires.end(),
            [](const Candidate& x, const Candidate& y) { return x.a.z() + x.b.z() < y.a.z() + y.b.z(); });
  for (const Candidate& c : wires) {
    Wire wire;
    wire.id = WireId(static_cast<int64_t>(trellis.wires.size()) + 1);
    wire.points = c.polyline.empty() ? std::vector<Eigen::Vector3d>{c.a, c.b} : c.polyline;
    wire.radius = RadiusFromWidth(rig, c, 0.0008, 0.004);
    trellis.wires.push_back(wire);
  }
  std::vector<Candidate> posts =
      Choose(Candidates(views, rig, volume, options, true), options, views.size());
  if (options.fit_all_views)
    for (Candidate& c : posts) FitToAllViews(views, rig, volume, options, true, &c);
  std::sort(posts.begin(), posts.end(),
            [](const Candidate& x, const Candidate& y) { return x.a.x() < y.a.x(); });
  for (const Candidate& c : posts) {
    Post post;
    post.id = PostId(static_cast<int64_t>(trellis.posts.size()) + 1);
    post.base = c.a;
    post.top = c.b;
    post.radius = RadiusFromWidth(rig, c, 0.02, 0.1);
    trellis.posts.push_back(post);
  }
  return trellis;
}

absl::StatusOr<std::vector<TrellisLineMatch>> MatchTrellisLines(const std::vector<View2D>& views,
                                                                const RigCalibration& rig,
                                                                const WorkingVolume& volume,
                                                                const TrellisOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("trellis: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  std::vector<TrellisLineMatch> out;
  for (bool posts : {false, true}) {
    for (const Candidate& c :
         Choose(Candidates(views, rig, volume, options, posts), options, views.size())) {
      out.push_back({posts, c.a, c.b, c.lines});
    }
  }
  return out;
}

}  // namespace vb::reconstruct
