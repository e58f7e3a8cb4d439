// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/diagnose_util.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/join_images.h"
#include "workers/reconstruct/synthetic_views.h"

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

namespace {

// AssembleCanes on `pieces`, the canes mostly outside options.volume dropped.
absl::StatusOr<std::vector<Polyline3>> AssembleInVolume(const std::vector<Piece3D>& pieces,
                                                        const ReconstructOptions& options) {
  auto canes = AssembleCanes(pieces, options.assembly, Deadline::Infinite());
  if (!canes.ok()) return canes.status();
  std::erase_if(*canes,
                [&](const Polyline3& cane) { return options.volume.MostlyOutside(cane); });
  return canes;
}

std::vector<Eigen::Vector3d> PointsOf(const std::vector<Polyline3>& lines) {
  std::vector<Eigen::Vector3d> points;
  for (const Polyline3& l : lines) points.insert(points.end(), l.points.begin(), l.points.end());
  return points;
}

}  // namespace

absl::StatusOr<GrownCanes> AssembleAndGrow(const std::vector<View2D>& views,
                                           const RigCalibration& rig,
                                           const std::vector<Piece3D>& pieces,
                                           const ReconstructOptions& options) {
  auto canes = AssembleInVolume(pieces, options);
  if (!canes.ok()) return canes.status();
  GrownCanes out;
  out.canes = std::move(*canes);
  if (!options.grow.after_connection) {
    const absl::Status grown = GrowCaneEnds(views, rig, options.volume, options.grow, &out.canes);
    if (!grown.ok()) return grown;
  }
  out.hints = PointsOf(out.canes);
  return out;
}

absl::StatusOr<AssembledStop> AssembleStop(const std::vector<View2D>& views,
                                           const RigCalibration& rig,
                                           const std::vector<Piece3D>& pieces,
                                           const ReconstructOptions& options) {
  const Deadline deadline = Deadline::Infinite();
  AssembledStop out;
  auto canes = AssembleInVolume(pieces, options);
  if (!canes.ok()) return canes.status();
  out.canes = std::move(*canes);
  auto head = ReconstructHeadAndTrunk(views, rig, options.volume, options.head, deadline,
                                      PointsOf(out.canes));
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

std::vector<LengthSample> SampleTrueLength(const SimulatedStop& stop, double step_m,
                                           bool neighbours) {
  const std::vector<CameraCalibration>& cameras = stop.true_rig.cameras;
  // Per view, per cane, per sample; stop.drawn lists the vine's canes first.
  std::vector<std::vector<std::vector<bool>>> along, along_own;
  for (const CameraCalibration& camera : cameras) {
    if (neighbours) along.push_back(LyingAlongAnother(stop.drawn, camera, step_m, 2.0));
    along_own.push_back(LyingAlongAnother(stop.scene.vine, camera, step_m, 2.0));
  }
  std::vector<LengthSample> out;
  if (cameras.empty()) return out;
  for (size_t c = 0; c < stop.scene.vine.canes.size(); ++c) {
    const Polyline3& line = stop.scene.vine.canes[c].polyline;
    const std::vector<double> arc = line.ArcLengths();
    const size_t n = along_own[0][c].size();
    if (n < 2) continue;
    const double step = arc.back() / static_cast<double>(n - 1);
    for (size_t i = 0; i < n; ++i) {
      LengthSample s;
      s.cane = c;
      s.index = i;
      s.p = line.PointAt(arc.back() * i / (n - 1), arc);
      s.tangent = (line.PointAt(std::min(arc.back(), arc.back() * (i + 0.5) / (n - 1)), arc) -
                   line.PointAt(std::max(0.0, arc.back() * (i - 0.5) / (n - 1)), arc))
                      .normalized();
      s.step_m = step;
      s.weight_m = (i == 0 || i + 1 == n) ? 0.5 * step : step;
      for (size_t v = 0; v < cameras.size(); ++v) {
        const auto uv = cameras[v].Project(s.p);
        if (!uv || !cameras[v].InImage(*uv)) continue;
        ++s.in_image;
        if (neighbours) s.along += along[v][c][i];
        s.along_own += along_own[v][c][i];
      }
      out.push_back(s);
    }
  }
  return out;
}

SampleEvidence EvidenceOf(const SampleInViews& at, const RigCalibration& rig,
                          const Eigen::Vector3d& p, const Eigen::Vector3d& t,
                          double min_epipolar_sin) {
  const int n = static_cast<int>(at.segment.size());
  SampleEvidence out;
  out.in_image = at.in_image;
  out.foreground = at.foreground;
  out.segment.assign(n, -1);
  for (int v = 0; v < n; ++v) {
    if (at.on_foreground[v]) out.segment[v] = at.segment[v];
    out.skeleton += out.segment[v] >= 0;
  }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (out.segment[a] < 0 || out.segment[b] < 0) continue;
      const std::optional<double> sin = EpipolarSin(rig, a, b, p, t, at.px[a]);
      if (!sin) continue;
      out.pairs.push_back({a, b});
      if (*sin >= min_epipolar_sin) out.conditioned = true;
    }
  return out;
}

StageGrids MakeStageGrids(const std::vector<MatchCandidate>& raw,
                          const std::vector<ScoredCandidate>& scored,
                          const std::vector<Piece3D>& pieces, const AssembledStop& assembled,
                          const ConnectedStop& connected) {
  StageGrids grids;
  for (const MatchCandidate& c : raw) grids.raw.AddLine(HitPoints(c), 1.0);
  for (const ScoredCandidate& s : scored)
    grids.fitted.AddLine(s.fit.control_points, s.probability);
  for (const Piece3D& p : pieces) grids.piece.AddLine(p.polyline.points, 1.0);
  for (const Polyline3& c : assembled.canes) grids.assembled.AddLine(c.points, 1.0);
  if (assembled.head.trunk) grids.assembled.AddLine(assembled.head.trunk->points, 1.0);
  for (const Cane& c : connected.connected.canes) grids.connected.AddLine(c.polyline.points, 1.0);
  for (const Cane& c : connected.refined.canes) grids.final.AddLine(c.polyline.points, 1.0);
  return grids;
}

LossStage FirstLostStage(const Eigen::Vector3d& p, const SampleEvidence& evidence,
                         const StageGrids& grids, double threshold) {
  if (evidence.in_image < 2) return kLossInImage;
  if (evidence.foreground < 2) return kLossForeground;
  if (evidence.skeleton < 2) return kLossSkeleton;
  if (!evidence.conditioned) return kLossConditioned;
  if (grids.raw.MaxNear(p) < 0) return kLossRaw;
  const double fitted = grids.fitted.MaxNear(p);
  if (fitted < 0) return kLossFitted;
  if (fitted <= threshold) return kLossProbable;
  if (grids.piece.MaxNear(p) < 0) return kLossPiece;
  if (grids.assembled.MaxNear(p) < 0) return kLossAssembled;
  if (grids.connected.MaxNear(p) < 0) return kLossConnected;
  if (grids.final.MaxNear(p) < 0) return kLossFinal;
  return kLossKept;
}

bool HoldsEnds(const Polyline3& a, const Polyline3& b) {
  bool front = false, back = false;
  for (const Eigen::Vector3d& q : b.points) {
    front = front || (q - a.points.front()).norm() < 1e-9;
    back = back || (q - a.points.back()).norm() < 1e-9;
  }
  return front && back;
}

double NearestOtherCane(const VineModel& vine, size_t own, const Eigen::Vector3d& p) {
  double nearest = 1e9;
  for (size_t o = 0; o < vine.canes.size(); ++o) {
    if (o == own) continue;
    double d = 0.0;
    vine.canes[o].polyline.Project(p, &d);
    nearest = std::min(nearest, d);
  }
  return nearest;
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
