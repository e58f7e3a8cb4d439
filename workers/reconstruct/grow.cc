// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/grow.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/reconstruct/grow_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// The other canes, for the "alongside" test, each with a box grown by what growth can add.
struct OtherCane {
  const Polyline3* line;
  Eigen::AlignedBox3d box;
  int index;  // in the input
};

// A grown point alongside another cane: the nearest such cane, how far, and whether it is the
// end's own continuation (its end near the point, running on ahead).
struct AlongHit {
  int other = -1;
  double distance = 0.0;
  bool continuation = false;
};

// What the growth of one end gives: the points (not including the end), which of them lie
// alongside another cane, why and where it stopped.
struct Growth {
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> alongside;
  GrowStop stop = GrowStop::kCapped;
  Eigen::Vector3d stop_point = Eigen::Vector3d::Zero();
  int other = -1;
  int removed = 0;        // points backed off the end before growing (end_backoff_m)
  double removed_m = 0.0; // their length
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  // the end grown from
  // refit_end_m: the refitted positions of the end's last points (replacing as many of its
  // points, after any backed off), applied only with the growth.
  std::vector<Eigen::Vector3d> end_points;
};

// Mean radius over the last span_m of the line (its end's thickness, less noisy than one point).
double EndRadius(const Polyline3& line, double span_m) {
  const std::vector<double> arc = line.ArcLengths();
  double sum = 0;
  int count = 0;
  for (size_t i = 0; i < line.points.size(); ++i) {
    if (arc[i] >= arc.back() - span_m) {
      sum += line.radii[i];
      ++count;
    }
  }
  return count > 0 ? sum / count : line.radii.back();
}

using Stop = GrowStop;

class Grower {
 public:
  Grower(const std::vector<View2D>& views, const RigCalibration& rig, const WorkingVolume& volume,
         const GrowOptions& options)
      : volume_(volume), options_(options), evidence_(views, rig, options) {}

  // Grows the end at line.points.back(). `others` excludes `line` itself.
  Growth GrowBack(const Polyline3& input, const std::vector<OtherCane>& others) const {
    Growth out;
    out.start = input.points.back();
    // An end the views disagree on is backed off to the last point they agree on (within
    // end_backoff_m), if any: the growth then starts there.
    Polyline3 line = input;
    const double end_radius = EndRadius(input, options_.tangent_span_m);
    if (options_.require_end_support && !evidence_.EndSupported(line.points.back(), end_radius)) {
      bool found = false;
      double cut = 0;
      while (options_.end_backoff_m > 0 && line.points.size() > 2) {
        cut += (line.points.back() - line.points[line.points.size() - 2]).norm();
        if (cut > options_.end_backoff_m + 1e-12) break;
        line.points.pop_back();
        line.radii.pop_back();
        ++out.removed;
        if (evidence_.EndSupported(line.points.back(), end_radius)) {
          found = true;
          out.removed_m = cut;
          break;
        }
      }
      if (!found) {
        out.removed = 0;
        out.stop_point = input.points.back();
        out.stop = Stop::kEndUnsupported;
        return out;
      }
    }
    std::vector<Eigen::Vector3d> curve = line.points;
    const size_t grown_begin = curve.size();  // curve[grown_begin..] are grown
    // curve[movable_begin..grown_begin) are the end's own points that a refit may move.
    size_t movable_begin = grown_begin;
    if (options_.refit_span_m > 0 && options_.refit_end_m > 0 && grown_begin >= 3) {
      movable_begin = grown_begin - 1;  // the end itself; two points at least stay as anchors
      double s = 0;
      while (movable_begin > 2) {
        s += (curve[movable_begin] - curve[movable_begin - 1]).norm();
        if (s > options_.refit_end_m + 1e-12) break;
        --movable_begin;
      }
    }
    out.end_points.assign(curve.begin() + movable_begin, curve.end());
    const double length = line.Length();
    const std::vector<double> arc = line.ArcLengths();
    const Eigen::Vector3d end = line.points.back();
    out.start = end;
    const Eigen::Vector3d start_tangent =
        (end - line.PointAt(std::max(0.0, length - options_.tangent_span_m), arc)).normalized();
    const double radius = EndRadius(line, options_.tangent_span_m);
    out.stop_point = end;
    const double cos_turn = std::cos(options_.max_turn_deg * kDegToRad);
    const int max_steps = static_cast<int>(std::floor(options_.max_length_m / options_.step_m));
    const bool may_run_along = options_.alongside_max_m > 0;
    double alongside = 0;                // length grown alongside other canes so far
    size_t run_start = 0;                // where the current alongside run began, if in one
    bool in_run = false;
    bool in_band = false;                // the last step needed a view's band (band_support)
    out.stop = Stop::kCapped;
    for (int k = 0; k < max_steps; ++k) {
      const Eigen::Vector3d tangent = Tangent(curve);
      const Eigen::Vector3d predicted = curve.back() + options_.step_m * tangent;
      out.stop_point = predicted;
      if (!volume_.Contains(predicted)) {
        out.stop = Stop::kOutside;
        break;
      }
      double prior = in_run ? options_.alongside_prior_px_per_mm : options_.prior_px_per_mm;
      if (in_band) prior = std::max(prior, options_.band_prior_px_per_mm);
      Eigen::Vector3d p = evidence_.Correct(predicted, tangent, prior, radius);
      // With refit_span_m, the step's refitted stretch (from `refit_from` in `curve`), written
      // back only once the step is accepted.
      std::vector<Eigen::Vector3d> refit;
      size_t refit_from = 0;
      if (options_.refit_span_m > 0) {
        refit_from = RefitStretch(curve, movable_begin, p, &refit);
        p = refit.back();
      }
      out.stop_point = p;
      if (!volume_.Contains(p)) {
        out.stop = Stop::kOutside;
        break;
      }
      // (After a refit, from the refitted point before it.)
      const Eigen::Vector3d& previous = refit.size() >= 2 ? refit[refit.size() - 2] : curve.back();
      const Eigen::Vector3d step = (p - previous).normalized();
      if (step.dot(start_tangent) < cos_turn) {
        out.stop = Stop::kTurned;
        break;
      }
      if (const std::optional<Stop> s = evidence_.Check(p, step, radius, &in_band); s) {
        out.stop = *s;
        break;
      }
      const std::optional<AlongHit> hit = Alongside(p, step, others);
      if (hit) {
        const double step_length = (p - previous).norm();
        if (!may_run_along || hit->continuation || hit->distance < options_.alongside_min_gap_m ||
            alongside + step_length > options_.alongside_max_m + 1e-12) {
          out.stop = Stop::kAlongside;
          out.other = hit->other;
          break;
        }
        if (!in_run) run_start = out.points.size();
        in_run = true;
        alongside += step_length;
      } else {
        in_run = false;
      }
      for (size_t i = 0; i + 1 < refit.size(); ++i) {
        const size_t j = refit_from + i;
        curve[j] = refit[i];
        if (j >= grown_begin) {
          out.points[j - grown_begin] = refit[i];
        } else if (j >= movable_begin) {
          out.end_points[j - movable_begin] = refit[i];
        }
      }
      curve.push_back(p);
      out.points.push_back(p);
      out.alongside.push_back(hit.has_value());
    }
    if (in_run && options_.alongside_require_parting) {
      // The growth never left the other cane again: what it grew alongside it is not kept.
      out.points.resize(run_start);
      out.alongside.resize(run_start);
      out.stop = Stop::kAlongside;
    }
    return out;
  }

 private:
  // The stretch of `curve` + p to refit (refit_span_m): the points from `movable_begin` on
  // within refit_span_m of p, anchored by the two points of curve before them (the bending cost
  // at the stretch's first point reads those two; grow_refit.cc). Returns where in `curve` the
  // stretch begins; `stretch` receives it refitted, p last.
  size_t RefitStretch(const std::vector<Eigen::Vector3d>& curve, size_t movable_begin,
                      const Eigen::Vector3d& p, std::vector<Eigen::Vector3d>* stretch) const {
    size_t first_free = curve.size();  // p's index in curve + p
    double s = 0;
    Eigen::Vector3d next = p;
    while (first_free > movable_begin) {
      s += (next - curve[first_free - 1]).norm();
      if (s > options_.refit_span_m + 1e-12) break;
      next = curve[--first_free];
    }
    const size_t from = first_free >= 2 ? first_free - 2 : 0;
    stretch->assign(curve.begin() + from, curve.end());
    stretch->push_back(p);
    evidence_.Refit(stretch, first_free - from);
    return from;
  }

  // Unit chord over the last tangent_span_m of the curve.
  Eigen::Vector3d Tangent(const std::vector<Eigen::Vector3d>& curve) const {
    const Eigen::Vector3d& end = curve.back();
    double s = 0;
    for (size_t i = curve.size() - 1; i > 0; --i) {
      s += (curve[i] - curve[i - 1]).norm();
      if (s >= options_.tangent_span_m || i == 1) return (end - curve[i - 1]).normalized();
    }
    return Eigen::Vector3d::UnitX();
  }

  // The nearest other cane within other_cane_m of p that runs within along_angle_deg of the step.
  std::optional<AlongHit> Alongside(const Eigen::Vector3d& p, const Eigen::Vector3d& step,
                                    const std::vector<OtherCane>& others) const {
    const double cos_along = std::cos(options_.along_angle_deg * kDegToRad);
    std::optional<AlongHit> best;
    for (const OtherCane& other : others) {
      if (!other.box.contains(p)) continue;
      const std::vector<Eigen::Vector3d>& q = other.line->points;
      double arc = 0;
      for (size_t i = 0; i + 1 < q.size(); ++i) {
        const double segment = (q[i + 1] - q[i]).norm();
        double t = 0;
        const double d = PointSegmentDistance(p, q[i], q[i + 1], &t);
        if (d <= options_.other_cane_m && (!best || d < best->distance)) {
          const Eigen::Vector3d dir = (q[i + 1] - q[i]).normalized();
          const double cos = dir.dot(step);
          if (std::abs(cos) >= cos_along) {
            // The other cane's end near p, and the other cane runs on ahead from it.
            const double s = arc + t * segment, rest = other.line->Length() - s;
            best = AlongHit{other.index, d,
                            (s < options_.continuation_m && cos > 0) ||
                                (rest < options_.continuation_m && cos < 0)};
          }
        }
        arc += segment;
      }
    }
    return best;
  }

  const WorkingVolume& volume_;
  const GrowOptions& options_;
  const grow_internal::GrowEvidence evidence_;
};

Polyline3 Reversed(const Polyline3& line) {
  Polyline3 out = line;
  std::reverse(out.points.begin(), out.points.end());
  std::reverse(out.radii.begin(), out.radii.end());
  return out;
}

}  // namespace

absl::Status GrowOptions::Validate() const {
  for (const auto& [value, field] : {std::pair{step_m, "step_m"},
                                     {tangent_span_m, "tangent_span_m"},
                                     {max_offset_m, "max_offset_m"},
                                     {offset_grid_m, "offset_grid_m"},
                                     {truncate_px, "truncate_px"},
                                     {support_px, "support_px"},
                                     {max_length_m, "max_length_m"},
                                     {other_cane_m, "other_cane_m"}}) {
    if (absl::Status s = CheckPositive(value, "grow", field); !s.ok()) return s;
  }
  for (const auto& [value, field] : {std::pair{min_cane_length_m, "min_cane_length_m"},
                                     {trim_m, "trim_m"},
                                     {support_along_px, "support_along_px"},
                                     {prior_px_per_mm, "prior_px_per_mm"},
                                     {min_length_m, "min_length_m"},
                                     {min_epipolar_angle_deg, "min_epipolar_angle_deg"},
                                     {alongside_max_m, "alongside_max_m"},
                                     {alongside_min_gap_m, "alongside_min_gap_m"},
                                     {continuation_m, "continuation_m"},
                                     {alongside_prior_px_per_mm, "alongside_prior_px_per_mm"},
                                     {end_backoff_m, "end_backoff_m"},
                                     {band_margin_px, "band_margin_px"},
                                     {band_tolerance_px, "band_tolerance_px"},
                                     {band_prior_px_per_mm, "band_prior_px_per_mm"},
                                     {refit_span_m, "refit_span_m"},
                                     {refit_end_m, "refit_end_m"},
                                     {refit_smooth_px_per_mm, "refit_smooth_px_per_mm"}}) {
    if (absl::Status s = CheckNonNegative(value, "grow", field); !s.ok()) return s;
  }
  for (const auto& [value, field] : {std::pair{max_turn_deg, "max_turn_deg"},
                                     {along_angle_deg, "along_angle_deg"}}) {
    if (!std::isfinite(value) || value <= 0 || value >= 90) {
      return absl::InvalidArgumentError(
          absl::StrCat("grow.", field, " must be in (0, 90) degrees, is ", value));
    }
  }
  if (min_epipolar_angle_deg >= 90) {
    return absl::InvalidArgumentError(absl::StrCat(
        "grow.min_epipolar_angle_deg must be < 90 degrees, is ", min_epipolar_angle_deg));
  }
  if (offset_grid_m > max_offset_m) {
    return absl::InvalidArgumentError(absl::StrCat("grow.offset_grid_m (", offset_grid_m,
                                                   ") must not exceed max_offset_m (",
                                                   max_offset_m, ")"));
  }
  // Bounds on the work per end: the offset grid has (2 max_offset_m / offset_grid_m + 1)^2
  // points, and an end takes up to max_length_m / step_m steps.
  if (max_offset_m > 100.0 * offset_grid_m) {
    return absl::InvalidArgumentError(absl::StrCat(
        "grow.offset_grid_m (", offset_grid_m, ") must be at least max_offset_m / 100"));
  }
  if (max_length_m > 1000.0 * step_m) {
    return absl::InvalidArgumentError(
        absl::StrCat("grow.max_length_m (", max_length_m, ") must be at most 1000 step_m"));
  }
  if (alongside_max_m > max_length_m) {
    return absl::InvalidArgumentError(absl::StrCat("grow.alongside_max_m (", alongside_max_m,
                                                   ") must not exceed max_length_m (",
                                                   max_length_m, ")"));
  }
  if (alongside_max_m > 0 && alongside_min_gap_m >= other_cane_m) {
    return absl::InvalidArgumentError(absl::StrCat("grow.alongside_min_gap_m (",
                                                   alongside_min_gap_m,
                                                   ") must be below other_cane_m (", other_cane_m,
                                                   ")"));
  }
  if (refit_span_m > 0) {
    if (absl::Status s = CheckPositive(refit_search_px, "grow", "refit_search_px"); !s.ok()) {
      return s;
    }
    if (refit_span_m > max_length_m) {
      return absl::InvalidArgumentError(absl::StrCat("grow.refit_span_m (", refit_span_m,
                                                     ") must not exceed max_length_m (",
                                                     max_length_m, ")"));
    }
    if (refit_search_px > 50) {
      return absl::InvalidArgumentError(
          absl::StrCat("grow.refit_search_px must be at most 50, is ", refit_search_px));
    }
  }
  if (min_support_views < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("grow.min_support_views must be >= 2, is ", min_support_views));
  }
  if (image_margin_px < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("grow.image_margin_px must be >= 0, is ", image_margin_px));
  }
  return absl::OkStatus();
}

absl::Status GrowCaneEnds(const std::vector<View2D>& views, const RigCalibration& rig,
                          const WorkingVolume& volume, const GrowOptions& options,
                          std::vector<Polyline3>* canes, GrowSummary* summary,
                          bool tips_only) {
  VB_RETURN_IF_ERROR(options.Validate());
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("views: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  for (size_t v = 0; v < views.size(); ++v) {
    const CameraCalibration& camera = rig.cameras[v];
    if (views[v].width != camera.image_width || views[v].height != camera.image_height) {
      return absl::InvalidArgumentError(absl::StrCat(
          "views[", v, "]: size ", views[v].width, "x", views[v].height, " differs from camera '",
          camera.name, "' (", camera.image_width, "x", camera.image_height, ")"));
    }
  }
  GrowSummary local;
  if (summary == nullptr) summary = &local;
  *summary = GrowSummary();
  if (!options.enabled || canes == nullptr) return absl::OkStatus();

  const Grower grower(views, rig, volume, options);
  const double reach = options.max_length_m + options.other_cane_m;
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Polyline3& cane : *canes) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : cane.points) box.extend(p);
    box.min().array() -= reach;
    box.max().array() += reach;
    boxes.push_back(box);
  }

  for (size_t c = 0; c < canes->size(); ++c) {
    if ((*canes)[c].points.size() < 2 || (*canes)[c].Length() < options.min_cane_length_m)
      continue;
    std::vector<OtherCane> others;
    for (size_t o = 0; o < canes->size(); ++o)
      if (o != c) others.push_back({&(*canes)[o], boxes[o], static_cast<int>(o)});
    for (int side = 0; side < (tips_only ? 1 : 2); ++side) {
      Polyline3 line = side == 0 ? (*canes)[c] : Reversed((*canes)[c]);
      ++summary->ends_tried;
      const Growth growth = grower.GrowBack(line, others);
      const Stop stop = growth.stop;
      GrowEnd record;
      record.cane = static_cast<int>(c);
      record.side = side;
      record.stop = stop;
      record.stop_point = growth.stop_point;
      record.other_cane = growth.other;
      record.start_point = growth.start;
      record.steps = growth.points;
      summary->ends.push_back(record);
      switch (stop) {
        case Stop::kEndUnsupported: ++summary->end_unsupported; break;
        case Stop::kUnsupported: ++summary->unsupported; break;
        case Stop::kContradicted: ++summary->contradicted; break;
        case Stop::kAlongside: ++summary->alongside; break;
        case Stop::kThick: ++summary->thick; break;
        case Stop::kTurned: ++summary->turned; break;
        case Stop::kOutside: ++summary->outside; break;
        case Stop::kCapped: ++summary->capped; break;
      }
      std::vector<Eigen::Vector3d> kept = growth.points;
      line.points.resize(line.points.size() - growth.removed);
      line.radii.resize(line.radii.size() - growth.removed);
      if (stop == Stop::kUnsupported || stop == Stop::kContradicted || stop == Stop::kTurned) {
        double cut = 0;
        while (!kept.empty() && cut < options.trim_m - 1e-12) {
          const Eigen::Vector3d& before =
              kept.size() >= 2 ? kept[kept.size() - 2] : line.points.back();
          cut += (kept.back() - before).norm();
          kept.pop_back();
        }
      }
      if (kept.empty()) continue;  // (`line` is not written back)
      std::copy(growth.end_points.begin(), growth.end_points.end(),
                line.points.end() - static_cast<std::ptrdiff_t>(growth.end_points.size()));
      Polyline3 tail;
      tail.points.push_back(line.points.back());
      for (const Eigen::Vector3d& p : kept) tail.points.push_back(p);
      tail.radii.assign(tail.points.size(), EndRadius(line, options.tangent_span_m));
      const double added = tail.Length();
      // A backed-off end is replaced only by a growth that goes on beyond it.
      if (added < options.min_length_m + growth.removed_m) continue;
      double alongside = 0;
      for (size_t i = 0; i < kept.size(); ++i)
        if (growth.alongside[i]) alongside += (tail.points[i + 1] - tail.points[i]).norm();
      // Appended at the cane's own spacing, so later stages see the points they expect.
      const double spacing =
          std::max(options.step_m, line.Length() / static_cast<double>(line.points.size() - 1));
      const Polyline3 resampled = tail.Resampled(spacing);
      for (size_t i = 1; i < resampled.points.size(); ++i) {
        line.points.push_back(resampled.points[i]);
        line.radii.push_back(resampled.radii[i]);
      }
      ++summary->ends_grown;
      summary->added_length_m += added;
      summary->ends_alongside += alongside > 0;
      summary->alongside_length_m += alongside;
      summary->ends.back().grown_m = added;
      summary->ends.back().alongside_m = alongside;
      (*canes)[c] = side == 0 ? line : Reversed(line);
    }
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
