// SPDX-License-Identifier: Apache-2.0
#include "core/cut_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "absl/strings/str_cat.h"
#include "core/statistics.h"

namespace vb {
namespace {

absl::Status Prefixed(const char* what, const absl::Status& status) {
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrCat(what, ": ", status.message()));
}

// Where a reconstructed cut lands on the ground truth.
struct Landing {
  size_t cane = 0;        // index into truth.canes
  double distance_m = 0;  // to the cane's axis
  double arc_m = 0;       // arc length on it of the nearest axis point
};

Landing Land(const VineModel& truth, const Eigen::Vector3d& p) {
  Landing best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < truth.canes.size(); ++i) {
    double d = 0.0;
    const double s = truth.canes[i].polyline.Project(p, &d);
    if (d < best.distance_m) best = {i, d, s};
  }
  return best;
}

// Indices of truth canes that keep wood under the truth plan: kept and spurred canes and all
// their ancestors.
std::unordered_set<size_t> KeptCanes(const VineModel& truth, const CutPlan& plan) {
  std::unordered_set<size_t> kept;
  auto add_with_ancestors = [&](CaneId id) {
    std::optional<size_t> at = truth.IndexOf(id);
    // Bounded by the cane count; the model was validated (no cycles), so this only ends early.
    for (size_t steps = 0; at.has_value() && steps <= truth.canes.size(); ++steps) {
      if (!kept.insert(*at).second) break;  // its ancestors are in already
      const auto& parent = truth.canes[*at].parent_id;
      at = parent.has_value() ? truth.IndexOf(*parent) : std::nullopt;
    }
  };
  for (CaneId id : plan.keep) add_with_ancestors(id);
  for (CaneId id : plan.spurs) add_with_ancestors(id);
  return kept;
}

}  // namespace

absl::Status CutMetricsOptions::Validate() const {
  if (!std::isfinite(match_distance_m) || match_distance_m <= 0)
    return absl::InvalidArgumentError(
        absl::StrCat("cut metrics options.match_distance_m must be positive, is ",
                     match_distance_m));
  if (!std::isfinite(kept_distance_m) || kept_distance_m <= 0)
    return absl::InvalidArgumentError(
        absl::StrCat("cut metrics options.kept_distance_m must be positive, is ", kept_distance_m));
  if (!std::isfinite(on_cane_distance_m) || on_cane_distance_m <= 0)
    return absl::InvalidArgumentError(absl::StrCat(
        "cut metrics options.on_cane_distance_m must be positive, is ", on_cane_distance_m));
  return absl::OkStatus();
}

absl::StatusOr<CutMatching> MatchCuts(const VineModel& truth, const CutPlan& truth_plan,
                                      const VineModel& model, const CutPlan* model_plan,
                                      const CutMetricsOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = Prefixed("truth", truth.Validate()); !s.ok()) return s;
  if (absl::Status s = Prefixed("truth_plan", truth_plan.ValidateAgainst(truth)); !s.ok()) return s;
  if (absl::Status s = Prefixed("model", model.Validate()); !s.ok()) return s;
  if (model_plan != nullptr) {
    if (absl::Status s = Prefixed("model_plan", model_plan->ValidateAgainst(model)); !s.ok())
      return s;
  }

  CutMatching out;
  out.truth_partner.assign(truth_plan.cuts.size(), -1);
  if (model_plan == nullptr) return out;
  const std::vector<Cut>& model_cuts = model_plan->cuts;
  out.model_partner.assign(model_cuts.size(), -1);

  // Truth cuts by the index of their cane, and the first truth cut's arc length on each cane.
  std::vector<size_t> truth_cane(truth_plan.cuts.size());
  std::unordered_map<size_t, double> first_cut_arc;
  for (size_t i = 0; i < truth_plan.cuts.size(); ++i) {
    const Cut& cut = truth_plan.cuts[i];
    truth_cane[i] = *truth.IndexOf(cut.cane_id);  // ValidateAgainst checked it exists
    const double s = truth.canes[truth_cane[i]].polyline.Project(cut.point);
    auto [it, inserted] = first_cut_arc.emplace(truth_cane[i], s);
    if (!inserted) it->second = std::min(it->second, s);
  }

  std::vector<Landing> landing(model_cuts.size());
  for (size_t j = 0; j < model_cuts.size(); ++j) {
    landing[j] = Land(truth, model_cuts[j].point);
    out.model_truth_cane.push_back(landing[j].cane);
    out.model_truth_distance_m.push_back(landing[j].distance_m);
  }

  // Cuts that would take wood the truth keeps, if left unpaired (step 3).
  const std::unordered_set<size_t> kept = KeptCanes(truth, truth_plan);
  std::vector<bool> cuts_kept_wood(model_cuts.size(), false);
  for (size_t j = 0; j < model_cuts.size(); ++j) {
    const Landing& l = landing[j];
    if (!kept.contains(l.cane)) continue;
    const double reach =
        std::max(options.kept_distance_m, truth.canes[l.cane].polyline.RadiusAt(l.arc_m));
    if (l.distance_m > reach) continue;
    const auto first = first_cut_arc.find(l.cane);
    // Beyond the truth's first cut on the cane: wood the truth removes anyway.
    if (first != first_cut_arc.end() && l.arc_m >= first->second) continue;
    cuts_kept_wood[j] = true;
  }

  // Candidate pairs on the same truth cane within the match distance: first those on the model
  // cut's nearest cane, nearest first, then those on another cane it lies on, so that every pair
  // the nearest-cane rule alone would make is still made.
  std::vector<std::tuple<int, double, size_t, size_t>> pairs;
  for (size_t i = 0; i < truth_plan.cuts.size(); ++i) {
    const Polyline3& cane = truth.canes[truth_cane[i]].polyline;
    for (size_t j = 0; j < model_cuts.size(); ++j) {
      const int pass = landing[j].cane == truth_cane[i] ? 0 : 1;
      if (pass == 1) {
        // Never on another cane when it would cut wood the truth keeps on its nearest one.
        if (cuts_kept_wood[j]) continue;
        double off_axis = 0.0;
        cane.Project(model_cuts[j].point, &off_axis);
        if (off_axis > options.on_cane_distance_m) continue;
      }
      const double d = (truth_plan.cuts[i].point - model_cuts[j].point).norm();
      if (d <= options.match_distance_m) pairs.emplace_back(pass, d, i, j);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [pass, d, i, j] : pairs) {
    if (out.truth_partner[i] >= 0 || out.model_partner[j] >= 0) continue;
    out.truth_partner[i] = static_cast<int>(j);
    out.model_partner[j] = static_cast<int>(i);
  }

  out.model_on_kept_cane.assign(model_cuts.size(), false);
  for (size_t j = 0; j < model_cuts.size(); ++j)
    out.model_on_kept_cane[j] = cuts_kept_wood[j] && out.model_partner[j] < 0;
  return out;
}

absl::StatusOr<CutMetrics> EvaluateCuts(const VineModel& truth, const CutPlan& truth_plan,
                                        const VineModel& model, const CutPlan* model_plan,
                                        const CutMetricsOptions& options) {
  absl::StatusOr<CutMatching> matching = MatchCuts(truth, truth_plan, model, model_plan, options);
  if (!matching.ok()) return matching.status();
  CutMetrics m;
  m.truth_cuts = static_cast<int>(truth_plan.cuts.size());
  m.cuts_missed_fraction = m.truth_cuts > 0 ? 1.0 : 0.0;
  if (model_plan == nullptr) return m;
  m.model_cuts = static_cast<int>(model_plan->cuts.size());
  std::vector<double> errors;
  for (size_t i = 0; i < truth_plan.cuts.size(); ++i) {
    const int j = matching->truth_partner[i];
    if (j >= 0) errors.push_back((truth_plan.cuts[i].point - model_plan->cuts[j].point).norm());
  }
  m.matched_cuts = static_cast<int>(errors.size());
  m.cut_error_median_m = Median(errors);
  m.cut_error_p95_m = Quantile(errors, 0.95);
  if (m.truth_cuts > 0)
    m.cuts_missed_fraction = static_cast<double>(m.truth_cuts - m.matched_cuts) / m.truth_cuts;
  if (m.model_cuts > 0)
    m.cuts_spurious_fraction = static_cast<double>(m.model_cuts - m.matched_cuts) / m.model_cuts;
  m.cuts_on_kept_canes = static_cast<int>(std::count(
      matching->model_on_kept_cane.begin(), matching->model_on_kept_cane.end(), true));
  return m;
}

nlohmann::json CutMetricsToJson(const CutMetrics& m) {
  return {{"cut_error_median_m", m.cut_error_median_m},
          {"cut_error_p95_m", m.cut_error_p95_m},
          {"cuts_missed_fraction", m.cuts_missed_fraction},
          {"cuts_spurious_fraction", m.cuts_spurious_fraction},
          {"cuts_on_kept_canes", m.cuts_on_kept_canes},
          {"truth_cuts", m.truth_cuts},
          {"model_cuts", m.model_cuts},
          {"matched_cuts", m.matched_cuts}};
}

}  // namespace vb
