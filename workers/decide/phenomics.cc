// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/phenomics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/model_metrics.h"
#include "core/statistics.h"
#include "core/status_macros.h"
#include "workers/decide/scheme.h"

namespace vb::decide {
namespace {

// Volume of the tube swept by the polyline's radii between arc lengths s0 and s1: a frustum per
// segment piece, pi h (r0^2 + r0 r1 + r1^2) / 3 (radius linear in arc length, as RadiusAt).
double TubeVolume(const Polyline3& line, double s0, double s1) {
  const std::vector<double> arc = line.ArcLengths();
  double volume = 0.0;
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    const double a = std::max(s0, arc[i]);
    const double b = std::min(s1, arc[i + 1]);
    if (b <= a) continue;
    const double r0 = line.RadiusAt(a);
    const double r1 = line.RadiusAt(b);
    volume += M_PI * (b - a) * (r0 * r0 + r0 * r1 + r1 * r1) / 3.0;
  }
  return volume;
}

// The bin of a diameter; the tolerance keeps a diameter computed as 5.9999999 mm in the 6 mm bin.
double BinOf(double d_mm, double bin_mm) { return std::floor(d_mm / bin_mm + 1e-9); }

DiameterHistogram Histogram(const std::vector<double>& diameters_mm, double bin_mm) {
  DiameterHistogram h;
  h.bin_mm = bin_mm;
  if (diameters_mm.empty()) return h;
  const auto [lo, hi] = std::minmax_element(diameters_mm.begin(), diameters_mm.end());
  const double first = BinOf(*lo, bin_mm);
  h.first_bin_mm = first * bin_mm;
  h.counts.assign(static_cast<size_t>(BinOf(*hi, bin_mm) - first) + 1, 0);
  for (double d : diameters_mm) {
    const size_t k = static_cast<size_t>(BinOf(d, bin_mm) - first);
    ++h.counts[std::min(k, h.counts.size() - 1)];
  }
  return h;
}

// Wood removed by `plan` and the kept canes' length: see Phenomics.
void ApplyPlan(const VineModel& model, const CutPlan& plan, const PhenomicsOptions& options,
               Phenomics* out) {
  out->has_plan = true;
  out->kept_canes = static_cast<int>(plan.keep.size());
  out->spurs = static_cast<int>(plan.spurs.size());
  out->cuts_planned = static_cast<int>(plan.cuts.size());
  // The first (nearest the base) cut of each cane, as an arc length along it.
  std::unordered_map<size_t, double> first_cut;
  for (const Cut& cut : plan.cuts) {
    out->cuts_remove += cut.reason == CutReason::kRemove;
    out->cuts_spur += cut.reason == CutReason::kSpur;
    out->cuts_shorten += cut.reason == CutReason::kShorten;
    const size_t i = *model.IndexOf(cut.cane_id);  // ValidateAgainst checked it exists
    const double s = model.canes[i].polyline.Project(cut.point);
    auto [it, inserted] = first_cut.emplace(i, s);
    if (!inserted) it->second = std::min(it->second, s);
  }
  // A cane falls if its parent falls, or if it grows from the part of its parent beyond the
  // parent's first cut. Memoised walk up the parent chain (the model is acyclic: validated).
  std::vector<std::optional<bool>> falls(model.canes.size());
  auto fallen = [&](auto&& self, size_t i) -> bool {
    if (falls[i].has_value()) return *falls[i];
    bool result = false;
    if (const auto& parent = model.canes[i].parent_id; parent.has_value()) {
      const size_t p = *model.IndexOf(*parent);
      const auto cut = first_cut.find(p);
      result = self(self, p) ||
               (cut != first_cut.end() &&
                model.canes[p].polyline.Project(model.canes[i].polyline.points.front()) >=
                    cut->second);
    }
    falls[i] = result;
    return result;
  };
  for (size_t i = 0; i < model.canes.size(); ++i) {
    const Polyline3& line = model.canes[i].polyline;
    const double length = line.Length();
    if (fallen(fallen, i)) {
      out->removed_wood_volume_m3 += TubeVolume(line, 0.0, length);
    } else if (const auto cut = first_cut.find(i); cut != first_cut.end()) {
      out->removed_wood_volume_m3 += TubeVolume(line, cut->second, length);
    }
  }
  out->pruning_weight_kg = out->removed_wood_volume_m3 * options.fresh_density_kg_m3;
  for (CaneId id : plan.keep) {
    const size_t i = *model.IndexOf(id);
    const auto cut = first_cut.find(i);
    out->kept_length_m += cut != first_cut.end() ? cut->second : model.canes[i].polyline.Length();
  }
}

}  // namespace

absl::Status PhenomicsOptions::Validate() const {
  const std::pair<const char*, double> fields[] = {{"fresh_density_kg_m3", fresh_density_kg_m3},
                                                   {"diameter_bin_mm", diameter_bin_mm},
                                                   {"head_grid_m", head_grid_m},
                                                   {"trunk_sample_step_m", trunk_sample_step_m}};
  for (const auto& [name, value] : fields) {
    if (!std::isfinite(value) || value <= 0)
      return absl::InvalidArgumentError(
          absl::StrCat("phenomics options.", name, " must be positive and finite, is ", value));
  }
  return absl::OkStatus();
}

absl::StatusOr<Phenomics> ComputePhenomics(const VineModel& model, const CutPlan* plan,
                                           const PhenomicsOptions& options) {
  VB_RETURN_IF_ERROR(options.Validate());
  if (absl::Status s = model.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("model: ", s.message()));
  if (model.canes.empty()) return absl::InvalidArgumentError("model: empty (no canes)");
  if (plan != nullptr) {
    if (absl::Status s = plan->ValidateAgainst(model); !s.ok())
      return absl::InvalidArgumentError(absl::StrCat("plan: ", s.message()));
  }
  // The decision's own view of the canes, so counts by origin and diameters agree with it.
  VB_ASSIGN_OR_RETURN(const std::vector<Candidate> candidates,
                      FindCandidates(model, plan != nullptr ? plan->policy : PruningPolicy{}));

  Phenomics p;
  p.fresh_density_kg_m3 = options.fresh_density_kg_m3;
  std::vector<double> diameters_mm;
  for (const Candidate& c : candidates) {
    ++p.canes;
    p.canes_from_head += c.origin == CaneOrigin::kHead;
    p.canes_from_trunk += c.origin == CaneOrigin::kTrunk;
    p.canes_from_cane += c.origin == CaneOrigin::kCane;
    p.cane_length_total_m += c.length_m;
    diameters_mm.push_back(c.base_diameter_m * 1000.0);
  }
  if (p.canes > 0) {
    p.cane_length_mean_m = p.cane_length_total_m / p.canes;
    double sum = 0.0;
    for (double d : diameters_mm) sum += d;
    p.cane_diameter_mean_mm = sum / p.canes;
    p.cane_diameter_median_mm = Median(diameters_mm);
    p.cane_diameter_p10_mm = Quantile(diameters_mm, 0.10);
    p.cane_diameter_p90_mm = Quantile(diameters_mm, 0.90);
  }
  p.cane_diameter_histogram = Histogram(diameters_mm, options.diameter_bin_mm);
  for (const Cane& cane : model.canes) {
    p.old_spurs += cane.kind == CaneKind::kSpur;
    if (cane.kind != CaneKind::kTrunk) continue;
    // Equal arc-length samples, so the median is over the trunk's length, not its vertices.
    const Polyline3 samples = cane.polyline.Resampled(options.trunk_sample_step_m);
    p.trunk_diameter_mm = 2000.0 * Median(samples.radii);
    // A reconstruction leaves the trunk below the images out of its canes (an obstacle): the
    // stretch from the trunk's lowest point down to the ground (platform z = 0) counts as vertical.
    double lowest_z = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& point : cane.polyline.points) {
      lowest_z = std::min(lowest_z, point.z());
    }
    p.trunk_length_m = cane.polyline.Length() + std::max(0.0, lowest_z);
  }
  p.head_volume_m3 = SphereUnionVolume(model.head.spheres, options.head_grid_m);
  if (plan != nullptr) ApplyPlan(model, *plan, options, &p);
  return p;
}

nlohmann::json PhenomicsToJson(const Phenomics& p) {
  nlohmann::json j = {
      {"canes", p.canes},
      {"canes_from_head", p.canes_from_head},
      {"canes_from_trunk", p.canes_from_trunk},
      {"canes_from_cane", p.canes_from_cane},
      {"old_spurs", p.old_spurs},
      {"cane_length_total_m", p.cane_length_total_m},
      {"cane_length_mean_m", p.cane_length_mean_m},
      {"cane_diameter_mean_mm", p.cane_diameter_mean_mm},
      {"cane_diameter_median_mm", p.cane_diameter_median_mm},
      {"cane_diameter_p10_mm", p.cane_diameter_p10_mm},
      {"cane_diameter_p90_mm", p.cane_diameter_p90_mm},
      {"cane_diameter_histogram",
       {{"bin_mm", p.cane_diameter_histogram.bin_mm},
        {"first_bin_mm", p.cane_diameter_histogram.first_bin_mm},
        {"counts", p.cane_diameter_histogram.counts}}},
      {"trunk_diameter_mm", p.trunk_diameter_mm},
      {"trunk_length_m", p.trunk_length_m},
      {"head_volume_m3", p.head_volume_m3},
      {"has_plan", p.has_plan},
      {"fresh_density_kg_m3", p.fresh_density_kg_m3}};
  const nlohmann::json null;
  j["kept_canes"] = p.has_plan ? nlohmann::json(p.kept_canes) : null;
  j["spurs"] = p.has_plan ? nlohmann::json(p.spurs) : null;
  j["kept_length_m"] = p.has_plan ? nlohmann::json(p.kept_length_m) : null;
  j["removed_wood_volume_m3"] = p.has_plan ? nlohmann::json(p.removed_wood_volume_m3) : null;
  j["pruning_weight_kg"] = p.has_plan ? nlohmann::json(p.pruning_weight_kg) : null;
  j["cuts_planned"] = p.has_plan ? nlohmann::json(p.cuts_planned) : null;
  j["cuts_by_reason"] = p.has_plan ? nlohmann::json{{"remove", p.cuts_remove},
                                                    {"spur", p.cuts_spur},
                                                    {"shorten", p.cuts_shorten}}
                                   : null;
  return j;
}

}  // namespace vb::decide
