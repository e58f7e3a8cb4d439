// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/correspondence.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "core/statistics.h"
#include "core/status_macros.h"
#include "workers/reconstruct/strand_halves.h"

namespace vb::reconstruct {
namespace {

absl::Status Invalid(const std::string& field, const std::string& message) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", message));
}

bool IsEmptyView(const View2D& view) {
  return view.width == 0 && view.height == 0 && view.classes.data.empty() &&
         view.segments.empty();
}

absl::Status ValidateSegment(const Segment2D& segment, const std::string& field) {
  if (segment.widths_px.size() != segment.points.size()) {
    return Invalid(field, absl::StrCat(segment.points.size(), " points but ",
                                       segment.widths_px.size(), " widths"));
  }
  for (size_t k = 0; k < segment.points.size(); ++k) {
    if (!segment.points[k].allFinite() || !std::isfinite(segment.widths_px[k]) ||
        segment.widths_px[k] < 0.0) {
      return Invalid(field, absl::StrCat("point ", k, " not finite or negative width"));
    }
  }
  return absl::OkStatus();
}

absl::Status ValidateInput(const std::vector<View2D>& views, const RigCalibration& rig) {
  if (views.size() != rig.cameras.size()) {
    return Invalid("views", absl::StrCat(views.size(), " views but ", rig.cameras.size(),
                                         " cameras"));
  }
  if (views.size() < 2) return Invalid("views", "correspondence needs at least 2 views");
  VB_RETURN_IF_ERROR(rig.Validate());
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    for (size_t j = i + 1; j < rig.cameras.size(); ++j) {
      const double baseline =
          (rig.cameras[i].CentreInPlatform() - rig.cameras[j].CentreInPlatform()).norm();
      if (!(baseline >= 0.01)) {
        return Invalid(absl::StrCat("cameras[", i, "], cameras[", j, "]"),
                       absl::StrCat("camera centres ", baseline, " m apart (need >= 0.01 m)"));
      }
    }
  }
  for (size_t v = 0; v < views.size(); ++v) {
    const View2D& view = views[v];
    const std::string field = absl::StrCat("views[", v, "]");
    if (IsEmptyView(view)) continue;
    const CameraCalibration& camera = rig.cameras[v];
    if (view.width != camera.image_width || view.height != camera.image_height) {
      return Invalid(field, absl::StrCat("size ", view.width, "x", view.height, " but camera '",
                                         camera.name, "' is ", camera.image_width, "x",
                                         camera.image_height));
    }
    const size_t pixels = static_cast<size_t>(view.width) * view.height;
    if (!view.classes.data.empty() &&
        (view.classes.data.size() != pixels || view.classes.width != view.width ||
         view.classes.height != view.height)) {
      return Invalid(field + ".classes", "size differs from the view's");
    }
    if (!view.centreline_distance_px.empty() && view.centreline_distance_px.size() != pixels) {
      return Invalid(field + ".centreline_distance_px", "size differs from the view's");
    }
    for (size_t s = 0; s < view.segments.size(); ++s) {
      VB_RETURN_IF_ERROR(ValidateSegment(view.segments[s],
                                         absl::StrCat(field, ".segments[", s, "]")));
    }
    for (size_t h = 0; h < view.strand_halves.size(); ++h) {
      const StrandHalf& half = view.strand_halves[h];
      const std::string hf = absl::StrCat(field, ".strand_halves[", h, "]");
      VB_RETURN_IF_ERROR(ValidateSegment(half.path, hf));
      if (half.to_sibling_px.size() != half.path.points.size()) {
        return Invalid(hf, absl::StrCat(half.path.points.size(), " points but ",
                                        half.to_sibling_px.size(), " steps to the sibling"));
      }
      if (half.sibling < 0 || half.sibling >= static_cast<int>(view.strand_halves.size())) {
        return Invalid(hf, absl::StrCat("sibling ", half.sibling, " out of range"));
      }
      for (const Eigen::Vector2d& step : half.to_sibling_px) {
        if (!step.allFinite()) return Invalid(hf, "step to the sibling not finite");
      }
    }
  }
  return absl::OkStatus();
}

// Fraction of points on the foreground (1 px tolerance) of every view in which they are inside
// the image.
double Support(const std::vector<Eigen::Vector3d>& points, const std::vector<View2D>& views,
               const RigCalibration& rig) {
  if (points.empty()) return 0.0;
  int supported = 0;
  for (const Eigen::Vector3d& p : points) {
    bool ok = true;
    for (size_t v = 0; v < views.size() && ok; ++v) {
      const View2D& view = views[v];
      if (view.classes.data.size() != static_cast<size_t>(view.width) * view.height ||
          view.width == 0) {
        continue;
      }
      const auto uv = rig.cameras[v].Project(p);
      if (!uv || !rig.cameras[v].InImage(*uv)) continue;
      const int x = std::clamp(static_cast<int>(std::lround(uv->x())), 0, view.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(uv->y())), 0, view.height - 1);
      bool on = false;
      for (int dy = -1; dy <= 1 && !on; ++dy) {
        for (int dx = -1; dx <= 1 && !on; ++dx) {
          on = view.IsForeground(std::clamp(x + dx, 0, view.width - 1),
                                 std::clamp(y + dy, 0, view.height - 1));
        }
      }
      ok = on;
    }
    supported += ok ? 1 : 0;
  }
  return static_cast<double>(supported) / points.size();
}

// The views outside the pair (a, b) that show anything, for RefineInOtherViews.
std::vector<OtherView> OtherViewsOf(int a, int b, const std::vector<View2D>& views,
                                    const std::vector<ViewSamples>& samples,
                                    const RigCalibration& rig) {
  std::vector<OtherView> others;
  for (int c = 0; c < static_cast<int>(views.size()); ++c) {
    if (c == a || c == b || IsEmptyView(views[c])) continue;
    others.push_back({&samples[c], &rig.cameras[c], &views[c]});
  }
  return others;
}

// Best inside x aligned fraction of `points` over the views outside (a, b) that show anything.
double OtherViewSupport(const std::vector<Eigen::Vector3d>& points, int a, int b,
                        const std::vector<View2D>& views, const std::vector<ViewSamples>& samples,
                        const RigCalibration& rig) {
  if (points.size() < 2) return 0.0;
  double best = 0.0;
  for (int c = 0; c < static_cast<int>(views.size()); ++c) {
    if (c == a || c == b || IsEmptyView(views[c])) continue;
    const ViewSupport s = CheckInView(points, views[c], samples[c], rig.cameras[c]);
    best = std::max(best, s.in_image * s.aligned);
  }
  return best;
}

}  // namespace

absl::Status SharedClaimOptions::Validate() const {
  if (!(min_separation_m >= 0.0) || !std::isfinite(min_separation_m)) {
    return Invalid("shared_claims.min_separation_m",
                   absl::StrCat("must be finite and >= 0, got ", min_separation_m));
  }
  if (!(min_other_view_support >= 0.0 && min_other_view_support <= 1.0)) {
    return Invalid("shared_claims.min_other_view_support",
                   absl::StrCat("must be in [0, 1], got ", min_other_view_support));
  }
  return absl::OkStatus();
}

absl::Status CorrespondenceOptions::Validate() const {
  if (!(volume.box.min().allFinite() && volume.box.max().allFinite()) ||
      !(volume.box.min().array() < volume.box.max().array()).all()) {
    return Invalid("volume", "empty or non-finite box");
  }
  if (!(sample_step_px >= 0.5 && sample_step_px <= 50.0)) {
    return Invalid("sample_step_px", absl::StrCat("must be in [0.5, 50], got ", sample_step_px));
  }
  if (!(min_epipolar_sin >= 0.0 && min_epipolar_sin < 1.0)) {
    return Invalid("min_epipolar_sin", absl::StrCat("must be in [0, 1), got ", min_epipolar_sin));
  }
  if (!(min_epipolar_sin_refined >= 0.0 && min_epipolar_sin_refined < 1.0)) {
    return Invalid("min_epipolar_sin_refined",
                   absl::StrCat("must be in [0, 1), got ", min_epipolar_sin_refined));
  }
  if (min_hits < 2) return Invalid("min_hits", absl::StrCat("must be >= 2, got ", min_hits));
  if (max_gap_samples < 0) {
    return Invalid("max_gap_samples", absl::StrCat("must be >= 0, got ", max_gap_samples));
  }
  if (max_ill_conditioned_gap_samples < 0) {
    return Invalid("max_ill_conditioned_gap_samples",
                   absl::StrCat("must be >= 0, got ", max_ill_conditioned_gap_samples));
  }
  if (!(fit.control_spacing_m > 0.0) || fit.max_control_points < 2 || fit.max_iterations < 0 ||
      !(fit.smoothness_weight >= 0.0) || !std::isfinite(fit.control_spacing_m) ||
      !std::isfinite(fit.smoothness_weight)) {
    return Invalid("fit", "control_spacing_m > 0, max_control_points >= 2, max_iterations >= 0, "
                          "smoothness_weight >= 0 (all finite)");
  }
  if (!(fit.bundle_width_ratio >= 1.0) || !std::isfinite(fit.bundle_width_ratio)) {
    return Invalid("fit.bundle_width_ratio",
                   absl::StrCat("must be finite and >= 1 (1: off), got ", fit.bundle_width_ratio));
  }
  if (!(max_rms_px > 0.0)) return Invalid("max_rms_px", "must be > 0");
  if (!(other_views.gate_px > 0.0) || !std::isfinite(other_views.gate_px)) {
    return Invalid("other_views.gate_px", "must be > 0 and finite");
  }
  if (!(other_views.min_cos >= 0.0 && other_views.min_cos <= 1.0)) {
    return Invalid("other_views.min_cos", "must be in [0, 1]");
  }
  if (other_views.rounds < 0) return Invalid("other_views.rounds", "must be >= 0");
  if (other_views.min_associations < 1) {
    return Invalid("other_views.min_associations", "must be >= 1");
  }
  if (!(other_views.max_residual_growth_px >= 0.0) ||
      !std::isfinite(other_views.max_residual_growth_px)) {
    return Invalid("other_views.max_residual_growth_px", "must be >= 0 and finite");
  }
  if (absl::Status s = classifier.Validate(); !s.ok()) {
    return Invalid("classifier", std::string(s.message()));
  }
  if (!(min_probability >= 0.0 && min_probability < 1.0)) {
    return Invalid("min_probability", absl::StrCat("must be in [0, 1), got ", min_probability));
  }
  if (!(min_conflict_overlap_px >= 0.0) || !std::isfinite(min_conflict_overlap_px)) {
    return Invalid("min_conflict_overlap_px", "must be finite and >= 0");
  }
  VB_RETURN_IF_ERROR(shared_claims.Validate());
  if (absl::Status s = gibbs.Validate(); !s.ok()) {
    return Invalid("gibbs", std::string(s.message()));
  }
  if (!(alpha > 0.0)) return Invalid("alpha", absl::StrCat("must be > 0, got ", alpha));
  VB_RETURN_IF_ERROR(context.Validate());
  if (context.enabled && !(context.alpha >= alpha)) {
    return Invalid("context.alpha", absl::StrCat("must be >= alpha (", alpha, "), got ",
                                                 context.alpha));
  }
  return absl::OkStatus();
}

CandidateOptions CandidateOptionsFor(const CorrespondenceOptions& options,
                                     bool other_view_shows_anything) {
  CandidateOptions candidate_options;
  candidate_options.volume = options.volume;
  candidate_options.min_epipolar_sin =
      options.other_views.rounds > 0 && other_view_shows_anything
          ? std::min(options.min_epipolar_sin, options.min_epipolar_sin_refined)
          : options.min_epipolar_sin;
  candidate_options.min_hits = options.min_hits;
  candidate_options.max_gap_samples = options.max_gap_samples;
  candidate_options.max_ill_conditioned_gap_samples = options.max_ill_conditioned_gap_samples;
  return candidate_options;
}

absl::StatusOr<std::vector<ScoredCandidate>> ScoreCandidates(
    const std::vector<View2D>& views, const RigCalibration& rig,
    const CorrespondenceOptions& options, const Deadline& deadline) {
  std::vector<ViewSamples> samples;
  return ScoreCandidates(views, rig, options, deadline, &samples);
}

absl::StatusOr<std::vector<ScoredCandidate>> ScoreCandidates(
    const std::vector<View2D>& views, const RigCalibration& rig,
    const CorrespondenceOptions& options, const Deadline& deadline,
    std::vector<ViewSamples>* samples_out) {
  VB_RETURN_IF_ERROR(options.Validate());
  VB_RETURN_IF_ERROR(ValidateInput(views, rig));
  VB_RETURN_IF_ERROR(deadline.Check("correspondence"));
  std::vector<ViewSamples>& samples = *samples_out;
  samples.clear();
  samples.reserve(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    samples.emplace_back(views[v], rig.cameras[v], options.sample_step_px,
                         options.strand_halves ? &views[v].strand_halves : nullptr);
  }
  Eigen::AlignedBox3d margin_box = options.volume.box;
  margin_box.min().array() -= 0.05;
  margin_box.max().array() += 0.05;

  std::vector<ScoredCandidate> scored;
  const int n = static_cast<int>(views.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      VB_RETURN_IF_ERROR(deadline.Check("correspondence"));
      const std::vector<OtherView> other_views = OtherViewsOf(a, b, views, samples, rig);
      std::vector<MatchCandidate> candidates =
          FindCandidates(a, samples[a], rig.cameras[a], b, samples[b], rig.cameras[b],
                         CandidateOptionsFor(options, !other_views.empty()));
      // Segment indices from these on are strand halves (ViewSamples).
      const int own_a = static_cast<int>(views[a].segments.size());
      const int own_b = static_cast<int>(views[b].segments.size());
      for (size_t i = 0; i < candidates.size(); ++i) {
        if (i % 64 == 0) VB_RETURN_IF_ERROR(deadline.Check("correspondence"));
        const MatchCandidate& c = candidates[i];
        if (options.strand_halves && c.segment_a >= own_a && c.segment_b >= own_b &&
            CrossesStrands(c, views[a].strand_halves[c.segment_a - own_a],
                           views[b].strand_halves[c.segment_b - own_b], rig.cameras[a],
                           rig.cameras[b])) {
          continue;
        }
        ScoredCandidate s;
        s.candidate = std::move(candidates[i]);
        s.fit = FitPolyline(s.candidate, rig.cameras[a], rig.cameras[b], options.fit);
        if (!s.fit.ok || std::max(s.fit.rms_a_px, s.fit.rms_b_px) > options.max_rms_px) continue;
        bool inside = true;
        for (const Eigen::Vector3d& p : s.fit.control_points) inside = inside && margin_box.contains(p);
        if (!inside) continue;
        s.two_view_features = ComputeMatchFeatures(s.candidate, s.fit, {}, options.volume);
        if (options.refine_before_scoring && options.other_views.rounds > 0 &&
            !other_views.empty()) {
          RefineInOtherViews(s.candidate, rig.cameras[a], rig.cameras[b], other_views,
                             options.fit, options.other_views, &s.fit);
          s.refined = true;
        }
        std::vector<ViewSupport> others;
        for (const OtherView& o : other_views) {
          others.push_back(CheckInView(s.fit.points, *o.view, *o.samples, *o.camera));
        }
        s.multi_view = !others.empty();
        // How the selected pieces' refinement would move it (match_classifier.h).
        const RefinementAgreement refinement =
            s.refined ? RefinementAgreement{}
                      : MeasureRefinement(s.candidate, s.fit, rig.cameras[a], rig.cameras[b],
                                          other_views, others, options.fit,
                                          options.other_views);
        s.features = s.multi_view ? ComputeMatchFeatures(s.candidate, s.fit, others,
                                                         options.volume, refinement)
                                  : s.two_view_features;
        s.probability = options.classifier.Probability(s.features, s.multi_view);
        scored.push_back(std::move(s));
      }
    }
  }
  return scored;
}

std::vector<std::vector<int>> CandidateConflicts(const std::vector<ScoredCandidate>& candidates,
                                                 double min_overlap_px) {
  // Key: (view_a, view_b, which side, segment) -> candidates claiming that segment.
  std::map<std::tuple<int, int, int, int>, std::vector<int>> claims;
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    const MatchCandidate& c = candidates[i].candidate;
    claims[{c.view_a, c.view_b, 0, c.segment_a}].push_back(i);
    claims[{c.view_a, c.view_b, 1, c.segment_b}].push_back(i);
  }
  std::vector<std::vector<int>> conflicts(candidates.size());
  for (const auto& [key, members] : claims) {
    const bool side_b = std::get<2>(key) == 1;
    for (size_t u = 0; u < members.size(); ++u) {
      const MatchCandidate& p = candidates[members[u]].candidate;
      const double p0 = side_b ? p.begin_b_px : p.begin_a_px;
      const double p1 = side_b ? p.end_b_px : p.end_a_px;
      for (size_t v = u + 1; v < members.size(); ++v) {
        const MatchCandidate& q = candidates[members[v]].candidate;
        const double q0 = side_b ? q.begin_b_px : q.begin_a_px;
        const double q1 = side_b ? q.end_b_px : q.end_a_px;
        const double overlap = std::min(p1, q1) - std::max(p0, q0);
        if (overlap >= min_overlap_px) {
          conflicts[members[u]].push_back(members[v]);
          conflicts[members[v]].push_back(members[u]);
        }
      }
    }
  }
  for (auto& list : conflicts) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return conflicts;
}

SharedClaimPair DescribeSharedClaim(const std::vector<ScoredCandidate>& candidates, int i, int j,
                                    const std::vector<View2D>& views,
                                    const std::vector<ViewSamples>& samples,
                                    const RigCalibration& rig, double min_overlap_px) {
  SharedClaimPair pair;
  const ScoredCandidate& ci = candidates[i];
  const ScoredCandidate& cj = candidates[j];
  const MatchCandidate& p = ci.candidate;
  const MatchCandidate& q = cj.candidate;
  if (p.view_a != q.view_a || p.view_b != q.view_b) return pair;
  // Per side: the shared interval [lo, hi] of arc length, when they share that segment.
  double lo[2] = {0, 0}, hi[2] = {-1, -1};
  double share_i = 0.0, share_j = 0.0;
  for (int side = 0; side < 2; ++side) {
    if ((side == 0 ? p.segment_a != q.segment_a : p.segment_b != q.segment_b)) continue;
    const double p0 = side ? p.begin_b_px : p.begin_a_px, p1 = side ? p.end_b_px : p.end_a_px;
    const double q0 = side ? q.begin_b_px : q.begin_a_px, q1 = side ? q.end_b_px : q.end_a_px;
    const double overlap = std::min(p1, q1) - std::max(p0, q0);
    if (overlap < min_overlap_px) continue;
    ++pair.sides;
    lo[side] = std::max(p0, q0);
    hi[side] = std::min(p1, q1);
    share_i = std::max(share_i, overlap / std::max(1.0, p1 - p0));
    share_j = std::max(share_j, overlap / std::max(1.0, q1 - q0));
  }
  if (pair.sides == 0) return pair;
  pair.max_share = std::max(share_i, share_j);
  pair.min_share = std::min(share_i, share_j);
  pair.min_probability = std::min(ci.probability, cj.probability);
  // Each one's fitted points over the shared stretch and elsewhere.
  auto split = [&](const ScoredCandidate& c, std::vector<Eigen::Vector3d>* shared,
                   std::vector<Eigen::Vector3d>* own) {
    const auto& hits = c.candidate.hits;
    for (size_t k = 0; k < hits.size() && k < c.fit.points.size(); ++k) {
      const bool in = (hits[k].arc_a_px >= lo[0] && hits[k].arc_a_px <= hi[0]) ||
                      (hits[k].arc_b_px >= lo[1] && hits[k].arc_b_px <= hi[1]);
      (in ? shared : own)->push_back(c.fit.points[k]);
    }
  };
  std::vector<Eigen::Vector3d> shared_i, own_i, shared_j, own_j;
  split(ci, &shared_i, &own_i);
  split(cj, &shared_j, &own_j);
  // The median (core/statistics.h) distance from `from` to the polyline through `to`.
  auto separation = [](const std::vector<Eigen::Vector3d>& from,
                       const std::vector<Eigen::Vector3d>& to) {
    Polyline3 line;
    line.points = to;
    std::vector<double> d;
    for (const Eigen::Vector3d& x : from) d.push_back(DistanceToPolyline(x, line));
    return Median(std::move(d));
  };
  pair.separation_m = std::min(separation(shared_i, cj.fit.control_points),
                               separation(shared_j, ci.fit.control_points));
  pair.min_shared_support =
      std::min(OtherViewSupport(shared_i, p.view_a, p.view_b, views, samples, rig),
               OtherViewSupport(shared_j, p.view_a, p.view_b, views, samples, rig));
  pair.min_own_support = std::min(OtherViewSupport(own_i, p.view_a, p.view_b, views, samples, rig),
                                  OtherViewSupport(own_j, p.view_a, p.view_b, views, samples, rig));
  return pair;
}

bool RelaxesConflict(const SharedClaimPair& pair, const SharedClaimOptions& options) {
  return options.enabled && pair.sides == 1 && pair.separation_m >= options.min_separation_m &&
         pair.min_shared_support >= options.min_other_view_support;
}

std::vector<std::vector<int>> CandidateConflicts(const std::vector<ScoredCandidate>& candidates,
                                                 const CorrespondenceOptions& options,
                                                 const std::vector<View2D>& views,
                                                 const std::vector<ViewSamples>& samples,
                                                 const RigCalibration& rig) {
  std::vector<std::vector<int>> conflicts =
      CandidateConflicts(candidates, options.min_conflict_overlap_px);
  if (!options.shared_claims.enabled) return conflicts;
  std::vector<std::vector<int>> relaxed(conflicts.size());
  for (int i = 0; i < static_cast<int>(conflicts.size()); ++i) {
    for (int j : conflicts[i]) {
      if (j > i && RelaxesConflict(DescribeSharedClaim(candidates, i, j, views, samples, rig,
                                                       options.min_conflict_overlap_px),
                                   options.shared_claims)) {
        relaxed[i].push_back(j);
        relaxed[j].push_back(i);
      }
    }
  }
  for (size_t i = 0; i < conflicts.size(); ++i) {
    std::erase_if(conflicts[i], [&](int j) {
      return std::find(relaxed[i].begin(), relaxed[i].end(), j) != relaxed[i].end();
    });
  }
  return conflicts;
}

absl::StatusOr<std::vector<Piece3D>> MatchSegments(const std::vector<View2D>& views,
                                                   const RigCalibration& rig,
                                                   const CorrespondenceOptions& options,
                                                   const Deadline& deadline) {
  std::vector<ViewSamples> samples;
  VB_ASSIGN_OR_RETURN(std::vector<ScoredCandidate> all,
                      ScoreCandidates(views, rig, options, deadline, &samples));
  std::vector<ScoredCandidate> candidates;
  for (ScoredCandidate& c : all) {
    if (c.probability >= options.min_probability) candidates.push_back(std::move(c));
  }
  std::vector<double> probabilities;
  probabilities.reserve(candidates.size());
  for (const ScoredCandidate& c : candidates) probabilities.push_back(c.probability);
  const std::vector<std::vector<int>> conflicts =
      CandidateConflicts(candidates, options, views, samples, rig);
  VB_RETURN_IF_ERROR(deadline.Check("correspondence"));
  const std::vector<double> marginals = GibbsMarginals(probabilities, conflicts, options.gibbs);
  std::vector<int> kept = SelectMinimumExpectedLoss(marginals, options.alpha);
  if (options.context.enabled) {
    std::vector<std::vector<Eigen::Vector3d>> curves;
    curves.reserve(candidates.size());
    for (const ScoredCandidate& c : candidates) curves.push_back(c.fit.control_points);
    const std::vector<int> added =
        SelectInContext(curves, marginals, conflicts, kept, options.context);
    kept.insert(kept.end(), added.begin(), added.end());
    std::sort(kept.begin(), kept.end());
  }
  VB_RETURN_IF_ERROR(deadline.Check("correspondence"));

  std::vector<Piece3D> pieces;
  pieces.reserve(kept.size());
  for (int i : kept) {
    ScoredCandidate& c = candidates[i];
    if (options.other_views.rounds > 0 && !c.refined) {
      RefineInOtherViews(c.candidate, rig.cameras[c.candidate.view_a],
                         rig.cameras[c.candidate.view_b],
                         OtherViewsOf(c.candidate.view_a, c.candidate.view_b, views, samples, rig),
                         options.fit, options.other_views, &c.fit);
    }
    Piece3D piece;
    piece.polyline.points = c.fit.control_points;
    piece.polyline.radii = c.fit.radii;
    piece.probability = marginals[i];
    piece.view_a = c.candidate.view_a;
    piece.segment_a = c.candidate.segment_a;
    piece.view_b = c.candidate.view_b;
    piece.segment_b = c.candidate.segment_b;
    piece.support = Support(c.fit.points, views, rig);
    pieces.push_back(std::move(piece));
  }
  std::stable_sort(pieces.begin(), pieces.end(), [](const Piece3D& l, const Piece3D& r) {
    return std::tie(l.view_a, l.view_b, l.segment_a) < std::tie(r.view_a, r.view_b, r.segment_a);
  });
  return pieces;
}

}  // namespace vb::reconstruct
