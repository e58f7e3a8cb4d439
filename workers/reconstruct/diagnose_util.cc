// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/diagnose_util.h"

#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/join_images.h"

namespace vb::reconstruct {

absl::StatusOr<RenderedMatch> RenderAndMatch(uint64_t seed, bool images, bool fiducials,
                                             const ReconstructOptions& options) {
  RenderedMatch out;
  out.stop = MakeRenderedStop(seed, images, fiducials);
  if (out.stop.views.empty())
    return absl::InternalError(absl::StrCat("seed ", seed, ": rendering or the 2D stage failed"));
  auto matched =
      MatchWithRigRefinement(out.stop.views, out.stop.rig, options, Deadline::Infinite());
  if (!matched.ok()) return matched.status();
  out.matched = std::move(*matched);
  return out;
}

absl::StatusOr<AssembledStop> AssembleStop(const std::vector<View2D>& views,
                                           const RigCalibration& rig,
                                           const std::vector<Piece3D>& pieces,
                                           const ReconstructOptions& options) {
  const Deadline deadline = Deadline::Infinite();
  AssembledStop out;
  auto canes = AssembleCanes(pieces, options.assembly, deadline);
  if (!canes.ok()) return canes.status();
  out.canes = std::move(*canes);
  std::erase_if(out.canes,
                [&](const Polyline3& cane) { return options.volume.MostlyOutside(cane); });
  std::vector<Eigen::Vector3d> hints;
  for (const Polyline3& c : out.canes) hints.insert(hints.end(), c.points.begin(), c.points.end());
  auto head = ReconstructHeadAndTrunk(views, rig, options.volume, options.head, deadline, hints);
  if (!head.ok()) return head.status();
  out.head = std::move(*head);
  auto prepared = PrepareCanes(out.canes, out.head.trunk, out.head.head, options.connect);
  if (!prepared.ok()) return prepared.status();
  out.prepared = std::move(*prepared);
  const JoinImageFn join_images = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return MeasureJoinImages(a, b, views, rig);
  };
  out.joins = FindJoins(out.prepared, out.head.head, options.connect, join_images);
  return out;
}

absl::StatusOr<ConnectedStop> ConnectAndRefine(const std::vector<View2D>& views,
                                               const RigCalibration& rig,
                                               const AssembledStop& assembled,
                                               const std::vector<JoinCandidate>& joins,
                                               const ReconstructOptions& options) {
  const GapSupportFn gap_support = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return GapSupport(a, b, views, rig);
  };
  ConnectedStop out;
  auto model = BuildTree(assembled.prepared, joins, assembled.head.head, options.connect,
                         &out.summary, gap_support);
  if (!model.ok()) return model.status();
  out.connected = *model;
  out.refined = std::move(*model);
  const absl::Status refined =
      RefineModel(&out.refined, views, rig, options.fit, Deadline::Infinite());
  if (!refined.ok()) return refined;
  return out;
}

std::vector<ViewSamples> SampleViews(const std::vector<View2D>& views, const RigCalibration& rig,
                                     double step_px) {
  std::vector<ViewSamples> samples;
  for (size_t v = 0; v < views.size(); ++v)
    samples.emplace_back(views[v], rig.cameras[v], step_px);
  return samples;
}

std::vector<MatchCandidate> RawCandidates(const std::vector<ViewSamples>& samples,
                                          const RigCalibration& rig,
                                          const CandidateOptions& options) {
  std::vector<MatchCandidate> out;
  const int n = static_cast<int>(samples.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      for (MatchCandidate& c :
           FindCandidates(a, samples[a], rig.cameras[a], b, samples[b], rig.cameras[b], options))
        out.push_back(std::move(c));
  return out;
}

std::vector<Eigen::Vector3d> HitPoints(const MatchCandidate& candidate) {
  std::vector<Eigen::Vector3d> points;
  for (const EpipolarHit& h : candidate.hits) points.push_back(h.point);
  return points;
}

SegmentMaps::SegmentMaps(const std::vector<View2D>& views) {
  for (const View2D& view : views) {
    width_.push_back(view.width);
    height_.push_back(view.height);
    std::vector<int>& index = index_.emplace_back(static_cast<size_t>(view.width) * view.height, -1);
    for (size_t s = 0; s < view.segments.size(); ++s)
      for (const Eigen::Vector2d& q : view.segments[s].points)
        for (int dy = -3; dy <= 3; ++dy)
          for (int dx = -3; dx <= 3; ++dx) {
            const int x = static_cast<int>(std::lround(q.x())) + dx;
            const int y = static_cast<int>(std::lround(q.y())) + dy;
            if (x < 0 || y < 0 || x >= view.width || y >= view.height) continue;
            index[static_cast<size_t>(y) * view.width + x] = static_cast<int>(s);
          }
  }
}

int SegmentMaps::At(int view, int x, int y) const {
  if (x < 0 || y < 0 || x >= width_[view] || y >= height_[view]) return -1;
  return index_[view][static_cast<size_t>(y) * width_[view] + x];
}

SampleInViews LocateSample(const Eigen::Vector3d& p, const RigCalibration& rig,
                           const std::vector<View2D>& views, const SegmentMaps& maps) {
  const int n = static_cast<int>(rig.cameras.size());
  SampleInViews out;
  out.inside.assign(n, false);
  out.on_foreground.assign(n, false);
  out.segment.assign(n, -1);
  out.px.assign(n, Eigen::Vector2d::Zero());
  for (int v = 0; v < n; ++v) {
    const auto uv = rig.cameras[v].Project(p);
    if (!uv || !rig.cameras[v].InImage(*uv)) continue;
    ++out.in_image;
    out.inside[v] = true;
    out.px[v] = *uv;
    const int x = static_cast<int>(std::lround(uv->x()));
    const int y = static_cast<int>(std::lround(uv->y()));
    out.on_foreground[v] = ForegroundWithin(views[v], x, y, 2);
    out.foreground += out.on_foreground[v];
    out.segment[v] = maps.At(v, x, y);
    out.skeleton += out.segment[v] >= 0;
  }
  return out;
}

Eigen::Vector3d TangentAt(const std::vector<Eigen::Vector3d>& points, size_t i) {
  return (points[std::min(i + 1, points.size() - 1)] - points[i > 0 ? i - 1 : 0]).normalized();
}

std::optional<double> EpipolarSin(const RigCalibration& rig, int a, int b,
                                  const Eigen::Vector3d& p, const Eigen::Vector3d& t,
                                  const Eigen::Vector2d& px_a) {
  const CameraCalibration& ca = rig.cameras[a];
  const Eigen::Vector3d cb = rig.cameras[b].CentreInPlatform();
  const auto e = ca.Project(p + 0.01 * (p - cb).normalized());
  const auto tt = ca.Project(p + 0.005 * t);
  if (!e || !tt) return std::nullopt;
  const Eigen::Vector2d de = (*e - px_a).normalized(), dt = (*tt - px_a).normalized();
  return std::abs(de.x() * dt.y() - de.y() * dt.x());
}

bool NearAnyCane(const Eigen::Vector3d& p, const std::vector<Cane>& canes, double radius_m) {
  for (const Cane& c : canes)
    if (DistanceToPolyline(p, c.polyline) <= radius_m) return true;
  return false;
}

namespace {

// Distance from p to the nearest segment of the polylines line_of(items[i]), as DistanceToCanes.
template <typename Item, typename LineOf>
double DistanceToNearest(const Eigen::Vector3d& p, const std::vector<Item>& items, LineOf line_of,
                         Eigen::Vector3d* nearest, int* index) {
  double best = 1e9;
  for (size_t k = 0; k < items.size(); ++k) {
    const std::vector<Eigen::Vector3d>& q = line_of(items[k]).points;
    for (size_t i = 0; i + 1 < q.size(); ++i) {
      double t = 0;
      const double d = PointSegmentDistance(p, q[i], q[i + 1], &t);
      if (d < best) {
        best = d;
        if (nearest) *nearest = q[i] + t * (q[i + 1] - q[i]);
        if (index) *index = static_cast<int>(k);
      }
    }
  }
  return best;
}

}  // namespace

double DistanceToCanes(const Eigen::Vector3d& p, const std::vector<Cane>& canes,
                       Eigen::Vector3d* nearest, int* cane) {
  return DistanceToNearest(
      p, canes, [](const Cane& c) -> const Polyline3& { return c.polyline; }, nearest, cane);
}

double DistanceToLines(const Eigen::Vector3d& p, const std::vector<Polyline3>& lines,
                       Eigen::Vector3d* nearest, int* line) {
  return DistanceToNearest(
      p, lines, [](const Polyline3& l) -> const Polyline3& { return l; }, nearest, line);
}

VineModel Flat(const std::vector<Polyline3>& lines) {
  VineModel model;
  for (const Polyline3& line : lines) {
    const bool first = model.canes.empty();
    model.canes.push_back({.id = CaneId(static_cast<int64_t>(model.canes.size()) + 1),
                           .parent_id = first ? std::nullopt : std::optional(CaneId(1)),
                           .kind = first ? CaneKind::kTrunk : CaneKind::kCane,
                           .polyline = line});
  }
  return model;
}

sim::RigOptions OldRigOptions() {
  sim::RigOptions options;
  options.rig_y_m = 0.0;
  options.distance_to_vine_plane_m = 0.8;
  options.baseline_m = 0.22;
  options.aim_below_rig_m = 0.0;
  return options;
}

bool OverrideFromEnv(const char* name, double* field) {
  const char* v = std::getenv(name);
  if (v != nullptr) *field = std::atof(v);
  return v != nullptr;
}

bool OverrideFromEnv(const char* name, int* field) {
  const char* v = std::getenv(name);
  if (v != nullptr) *field = std::atoi(v);
  return v != nullptr;
}

bool OverrideFromEnv(const char* name, bool* field) {
  const char* v = std::getenv(name);
  if (v != nullptr) *field = std::atoi(v) != 0;
  return v != nullptr;
}

std::vector<double> ListFromEnv(const char* name, std::vector<double> fallback) {
  const char* v = std::getenv(name);
  if (v == nullptr) return fallback;
  std::vector<double> out;
  for (const char* p = v; *p != '\0';) {
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p) break;
    out.push_back(x);
    p = *end == ',' ? end + 1 : end;
  }
  return out;
}

}  // namespace vb::reconstruct
