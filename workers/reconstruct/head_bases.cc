// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_bases.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/reconstruct/connect_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d HeadCentre(const HeadModel& head) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double weight = 0.0;
  for (const Sphere& s : head.spheres) {
    const double w = s.radius * s.radius * s.radius;
    sum += w * s.center;
    weight += w;
  }
  return weight > 0.0 ? Eigen::Vector3d(sum / weight) : sum;
}

bool Thick(const View2D& view, const Eigen::Vector2d& uv) {
  const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
  if (x < 0 || y < 0 || x >= view.width || y >= view.height) return false;
  return view.thick_mask[static_cast<size_t>(y) * view.width + x] != 0;
}

// The end `last` (true: points.back()) of `line` and its outward unit tangent: the chord from the
// point span_m of arc length inward to the end.
std::pair<Eigen::Vector3d, Eigen::Vector3d> EndAndTangent(const Polyline3& line, bool last,
                                                          double span_m) {
  const double length = line.Length();
  const double span = std::min(span_m, length);
  const Eigen::Vector3d end = last ? line.points.back() : line.points.front();
  const Eigen::Vector3d inner = line.PointAt(last ? length - span : span);
  Eigen::Vector3d t = end - inner;
  if (t.norm() < 1e-9) t = Eigen::Vector3d::UnitX();
  return {end, t.normalized()};
}

// The angle between the chord over the end's last `span_m` and the chord over the span before
// it, and the axis it turns about (b x a); 0 and any axis for a cane shorter than two spans.
double BendDeg(const Polyline3& line, bool last, double span_m, Eigen::Vector3d* axis) {
  *axis = Eigen::Vector3d::UnitZ();
  const double length = line.Length();
  if (length < 2.0 * span_m) return 0.0;
  const auto at = [&](double s) { return line.PointAt(last ? length - s : s); };
  const Eigen::Vector3d a = at(0.0) - at(span_m), b = at(span_m) - at(2.0 * span_m);
  if (a.norm() < 1e-9 || b.norm() < 1e-9) return 0.0;
  const Eigen::Vector3d n = b.cross(a);
  if (n.norm() < 1e-12) return 0.0;
  *axis = n.normalized();
  const double c = std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0);
  return std::acos(c) * 180.0 / kPi;
}

// The distance from p to the nearest of `lines` other than lines[skip].
double DistanceToOthers(const Eigen::Vector3d& p, const std::vector<Polyline3>& lines,
                        size_t skip) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < lines.size(); ++i) {
    if (i == skip) continue;
    const std::vector<Eigen::Vector3d>& q = lines[i].points;
    for (size_t k = 0; k + 1 < q.size(); ++k)
      best = std::min(best, PointSegmentDistance(p, q[k], q[k + 1]));
  }
  return best;
}

// Whether the course `record` holds lies, on average, farther than options.max_skeleton_px from
// the skeletons of the views that see it outside their thick region.
bool OffSkeleton(const HeadBasesOptions& options, const HeadBaseExtension& record) {
  if (options.max_skeleton_px <= 0.0 || record.skeleton_px.empty()) return false;
  double sum = 0.0;
  for (double px : record.skeleton_px) sum += px;
  return sum / static_cast<double>(record.skeleton_px.size()) > options.max_skeleton_px;
}

// One end stepped toward the head (see the header); the points added, in order from the end,
// or none when the extension is dropped; `stop` says why it ended. `record` gets every point
// the course reached. `others` are the canes as they were before the stage, `self` this one.
std::vector<Eigen::Vector3d> ExtendEnd(const std::vector<View2D>& views, const RigCalibration& rig,
                                       const HeadModel& head, const HeadBasesOptions& options,
                                       const Eigen::Vector3d& end, const Eigen::Vector3d& tangent,
                                       const Eigen::Vector3d& bend_axis, double bend_rate,
                                       const std::vector<Polyline3>& others, size_t self,
                                       HeadBaseStop* stop, HeadBaseExtension* record) {
  // Two axes across the step.
  Eigen::Vector3d u = tangent.unitOrthogonal();
  Eigen::Vector3d w = tangent.cross(u).normalized();
  const double cos_turn = std::cos(options.max_turn_deg * kPi / 180.0);
  const double cap = options.truncate_px * options.truncate_px;
  const int n = std::max(1, static_cast<int>(std::lround(options.max_offset_m / 0.0005)));
  const double grid = options.max_offset_m / n;
  std::vector<Eigen::Vector3d> added;
  // The curved course turns about bend_axis at bend_rate (rad/m); the chord's direction lies
  // half a span's turn behind the end's tangent.
  const double turn_per_step = options.curve_gain * bend_rate * options.step_m;
  Eigen::Vector3d at = end;
  Eigen::Vector3d dir =
      Eigen::AngleAxisd(0.5 * options.curve_gain * bend_rate * options.tangent_span_m,
                        bend_axis) * tangent;
  double inside_m = 0.0;
  for (double length = options.step_m; length <= options.max_length_m + 1e-9;
       length += options.step_m) {
    if (turn_per_step != 0.0) dir = Eigen::AngleAxisd(turn_per_step, bend_axis) * dir;
    const Eigen::Vector3d predicted = at + options.step_m * dir;
    // Views whose image holds the prediction, and which of them show it in their thick region.
    std::vector<std::optional<Eigen::Vector2d>> px(views.size());
    int in_image = 0;
    std::vector<int> correcting;
    for (size_t v = 0; v < views.size(); ++v) {
      px[v] = ProjectInside(rig.cameras[v], predicted, 0);
      if (!px[v]) continue;
      ++in_image;
      if (!Thick(views[v], *px[v]) && HasCentrelineDistance(views[v]))
        correcting.push_back(static_cast<int>(v));
    }
    if (in_image < 2) {
      *stop = HeadBaseStop::kOutsideImages;
      return {};
    }
    // The correction across the step toward the skeleton of the views without thick wood there.
    Eigen::Vector3d p = predicted;
    if (!correcting.empty()) {
      double best = std::numeric_limits<double>::infinity();
      for (int i = -n; i <= n; ++i) {
        for (int j = -n; j <= n; ++j) {
          const Eigen::Vector3d q = predicted + (i * grid) * u + (j * grid) * w;
          double cost = 1e-6 * (i * i + j * j);  // ties go to the prediction
          for (int v : correcting) {
            const auto uv = ProjectInside(rig.cameras[v], q, 0);
            const double d = uv ? CentrelineDistanceBilinear(views[v], *uv) : options.truncate_px;
            cost += std::min(d * d, cap);
          }
          if (cost < best) best = cost, p = q;
        }
      }
    }
    // Every view that holds the point must show wood at it; count those showing thick wood.
    int thick = 0;
    for (size_t v = 0; v < views.size(); ++v) {
      const auto uv = ProjectInside(rig.cameras[v], p, 0);
      if (!uv) continue;
      if (!WoodInDisc(views[v], *uv, options.wood_px)) {
        *stop = HeadBaseStop::kNoWood;
        return {};
      }
      thick += Thick(views[v], *uv) ? 1 : 0;
    }
    // The course so far, from the end, must keep near the end's tangent.
    const Eigen::Vector3d chord = p - end;
    const Eigen::Vector3d step = p - at;
    if (step.norm() < 1e-12 || chord.normalized().dot(tangent) < cos_turn) {
      *stop = HeadBaseStop::kTurned;
      return {};
    }
    double skeleton_px = 0.0;
    int on_skeleton = 0;
    for (int v : correcting) {
      const auto uv = ProjectInside(rig.cameras[v], p, 0);
      const double d = uv ? std::min(CentrelineDistanceBilinear(views[v], *uv), 10.0) : 10.0;
      skeleton_px += d / static_cast<double>(correcting.size());
      on_skeleton += d <= 2.0 ? 1 : 0;
    }
    record->correcting_views.push_back(static_cast<int>(correcting.size()));
    record->skeleton_px.push_back(skeleton_px);
    record->on_skeleton_views.push_back(on_skeleton);
    added.push_back(p);
    dir = step.normalized();
    at = p;
    Eigen::Vector3d surface;
    const bool inside = connect_internal::DistanceToHead(p, head, &surface) < 0.0;
    if (inside) inside_m += step.norm();
    record->points.push_back(p);
    record->inside_m.push_back(inside_m);
    record->thick_views.push_back(thick);
    record->other_cane_m.push_back(DistanceToOthers(p, others, self));
    if (options.min_thick_views > 0 && thick >= options.min_thick_views) {
      *stop = OffSkeleton(options, *record) ? HeadBaseStop::kOffSkeleton
                                            : HeadBaseStop::kReachedThick;
      return *stop == HeadBaseStop::kOffSkeleton ? std::vector<Eigen::Vector3d>() : added;
    }
    // The length run inside the spheres since the course entered them. (The signed distance to
    // a union of small spheres is no depth: inside, it is at most one sphere's radius.)
    if (inside) {
      if (inside_m >= options.max_inside_m - 1e-9) {
        *stop = OffSkeleton(options, *record) ? HeadBaseStop::kOffSkeleton
                                              : HeadBaseStop::kReachedInside;
        return *stop == HeadBaseStop::kOffSkeleton ? std::vector<Eigen::Vector3d>() : added;
      }
    }
  }
  *stop = HeadBaseStop::kTooLong;
  return {};
}

}  // namespace

absl::Status HeadBasesOptions::Validate() const {
  for (const auto& [value, field] : {std::pair{reach_m, "reach_m"},
                                     {step_m, "step_m"},
                                     {tangent_span_m, "tangent_span_m"},
                                     {truncate_px, "truncate_px"},
                                     {max_length_m, "max_length_m"}}) {
    if (absl::Status s = CheckPositive(value, "head_bases", field); !s.ok()) return s;
  }
  for (const auto& [value, field] : {std::pair{max_offset_m, "max_offset_m"},
                                     {wood_px, "wood_px"},
                                     {max_inside_m, "max_inside_m"},
                                     {max_skeleton_px, "max_skeleton_px"},
                                     {min_cane_length_m, "min_cane_length_m"}}) {
    if (absl::Status s = CheckNonNegative(value, "head_bases", field); !s.ok()) return s;
  }
  if (!std::isfinite(min_cos) || min_cos < -1.0 || min_cos > 1.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("head_bases.min_cos must be in [-1, 1], is ", min_cos));
  }
  if (!std::isfinite(max_turn_deg) || max_turn_deg <= 0.0 || max_turn_deg >= 90.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("head_bases.max_turn_deg must be in (0, 90), is ", max_turn_deg));
  }
  if (!std::isfinite(curve_gain) || curve_gain < 0.0 || curve_gain > 2.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("head_bases.curve_gain must be in [0, 2], is ", curve_gain));
  }
  if (min_thick_views < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("head_bases.min_thick_views must be >= 0, is ", min_thick_views));
  }
  if (max_offset_m > 0.02) {
    return absl::InvalidArgumentError(
        absl::StrCat("head_bases.max_offset_m must be <= 0.02, is ", max_offset_m));
  }
  return absl::OkStatus();
}

absl::Status ExtendBasesToHead(const std::vector<View2D>& views, const RigCalibration& rig,
                               const HeadModel& head, const HeadBasesOptions& options,
                               std::vector<Polyline3>* canes, HeadBasesSummary* summary) {
  VB_RETURN_IF_ERROR(options.Validate());
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("views: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  for (size_t v = 0; v < views.size(); ++v) {
    const size_t pixels = static_cast<size_t>(views[v].width) * views[v].height;
    if (views[v].thick_mask.size() != pixels) {
      return absl::InvalidArgumentError(
          absl::StrCat("views[", v, "]: thick_mask has ", views[v].thick_mask.size(),
                       " pixels for a ", views[v].width, "x", views[v].height, " image"));
    }
  }
  HeadBasesSummary local;
  if (summary == nullptr) summary = &local;
  *summary = HeadBasesSummary();
  if (!options.enabled || canes == nullptr || head.spheres.empty()) return absl::OkStatus();
  const Eigen::Vector3d centre = HeadCentre(head);
  const std::vector<Polyline3> before = *canes;
  for (size_t c = 0; c < canes->size(); ++c) {
    Polyline3& line = (*canes)[c];
    if (line.points.size() < 2 || line.Length() < options.min_cane_length_m) continue;
    // Only the end nearer the head is its base; the other is left to growth and extension.
    Eigen::Vector3d at_front, at_back;
    const double d_front = connect_internal::DistanceToHead(line.points.front(), head, &at_front);
    const double d_back = connect_internal::DistanceToHead(line.points.back(), head, &at_back);
    const bool last = d_back < d_front;
    const double d = last ? d_back : d_front;
    if (d > options.reach_m) continue;
    const auto [end, tangent] = EndAndTangent(line, last, options.tangent_span_m);
    const Eigen::Vector3d target = d > 0.0 ? (last ? at_back : at_front) : centre;
    const Eigen::Vector3d to_head = target - end;
    if (to_head.norm() < 1e-9 || tangent.dot(to_head.normalized()) < options.min_cos) continue;
    // An end already in the thick region of enough views has reached the head.
    int thick = 0;
    for (size_t v = 0; v < views.size(); ++v) {
      const auto uv = ProjectInside(rig.cameras[v], end, 0);
      thick += uv && Thick(views[v], *uv) ? 1 : 0;
    }
    if (options.min_thick_views > 0 && thick >= options.min_thick_views) continue;
    ++summary->ends_tried;
    HeadBaseExtension record;
    record.end = end;
    record.tangent = tangent;
    record.end_distance_m = d;
    Eigen::Vector3d bend_axis;
    record.bend_deg = BendDeg(line, last, options.tangent_span_m, &bend_axis);
    // The chords' directions are a span apart: the turn per metre of the circle through them.
    const double bend_rate = record.bend_deg * kPi / 180.0 / options.tangent_span_m;
    HeadBaseStop stop = HeadBaseStop::kNotTried;
    const std::vector<Eigen::Vector3d> added = ExtendEnd(
        views, rig, head, options, end, tangent, bend_axis, bend_rate, before, c, &stop, &record);
    record.stop = stop;
    summary->extensions.push_back(std::move(record));
    switch (stop) {
      case HeadBaseStop::kReachedThick: ++summary->reached_thick; break;
      case HeadBaseStop::kReachedInside: ++summary->reached_inside; break;
      case HeadBaseStop::kNoWood: ++summary->no_wood; break;
      case HeadBaseStop::kTurned: ++summary->turned; break;
      case HeadBaseStop::kTooLong: ++summary->too_long; break;
      case HeadBaseStop::kOutsideImages: ++summary->outside_images; break;
      case HeadBaseStop::kOffSkeleton: ++summary->off_skeleton; break;
      case HeadBaseStop::kNotTried: break;
    }
    if (added.empty()) continue;
    ++summary->ends_extended;
    const double radius = last ? line.radii.back() : line.radii.front();
    Eigen::Vector3d previous = end;
    for (const Eigen::Vector3d& p : added) {
      summary->added_length_m += (p - previous).norm();
      previous = p;
      if (last) {
        line.points.push_back(p);
        line.radii.push_back(radius);
      } else {
        line.points.insert(line.points.begin(), p);
        line.radii.insert(line.radii.begin(), radius);
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
