// SPDX-License-Identifier: Apache-2.0
// Phenomics of one vine: the measurements growers and researchers query across seasons (cane
// counts, lengths, diameters, trunk size, head volume, pruning weight), computed from a vine model
// and, optionally, the cut plan decided for it. docs/decide.md "Phenomics" defines every quantity.
// Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/vine_model.h"
#include "nlohmann/json.hpp"

namespace vb::decide {

// Fresh (as pruned) density of dormant one-year-old grapevine cane wood, kg/m^3. An estimate;
// its derivation and sources are in docs/decide.md "Phenomics".
inline constexpr double kFreshCaneDensityKgM3 = 1000.0;

struct PhenomicsOptions {
  double fresh_density_kg_m3 = kFreshCaneDensityKgM3;  // pruning weight = removed volume x this
  double diameter_bin_mm = 1.0;       // width of the cane diameter histogram's bins
  double head_grid_m = 0.001;         // cell size of the head volume's grid integral
  double trunk_sample_step_m = 0.005; // the trunk's diameter is sampled this far apart

  // INVALID_ARGUMENT naming the field unless every value is positive and finite.
  absl::Status Validate() const;
};

// Cane base diameters in 1-mm (diameter_bin_mm) bins: bin k counts diameters in
// [first_bin_mm + k * bin_mm, first_bin_mm + (k + 1) * bin_mm). Empty without canes.
struct DiameterHistogram {
  double bin_mm = 1.0;
  double first_bin_mm = 0.0;
  std::vector<int> counts;
};

struct Phenomics {
  // Canes of kind `cane` by origin (decide::FindCandidates: head, trunk below the head, another
  // cane), and old spurs (kind `spur`).
  int canes = 0;
  int canes_from_head = 0;
  int canes_from_trunk = 0;
  int canes_from_cane = 0;
  int old_spurs = 0;
  double cane_length_total_m = 0.0;
  double cane_length_mean_m = 0.0;  // 0 without canes
  // Cane diameters: each cane's base diameter (mean over its first 0.10 m, as the decision
  // uses). Quantiles interpolate (core/statistics.h). 0 without canes.
  double cane_diameter_mean_mm = 0.0;
  double cane_diameter_median_mm = 0.0;
  double cane_diameter_p10_mm = 0.0;
  double cane_diameter_p90_mm = 0.0;
  DiameterHistogram cane_diameter_histogram;
  // Median of the trunk's diameter sampled every trunk_sample_step_m along it; its length, plus
  // the height of its lowest point above the ground (a reconstruction's trunk stops 20 cm below
  // the images: the unseen part below is an obstacle, counted here as vertical).
  double trunk_diameter_mm = 0.0;
  double trunk_length_m = 0.0;
  // Volume of the union of the head spheres (grid integral, head_grid_m cells); 0 without a head.
  double head_volume_m3 = 0.0;

  // From the cut plan; zero when there is none (has_plan false).
  bool has_plan = false;
  int kept_canes = 0;
  int spurs = 0;
  // Length of the kept canes up to their first cut (the shortening cut), or their whole length.
  double kept_length_m = 0.0;
  // Volume of the wood the plan removes: each cut cane beyond its first cut, plus every cane
  // growing from the removed part (with all its descendants), which falls with it.
  double removed_wood_volume_m3 = 0.0;
  double pruning_weight_kg = 0.0;  // removed_wood_volume_m3 x fresh_density_kg_m3
  double fresh_density_kg_m3 = kFreshCaneDensityKgM3;
  int cuts_planned = 0;
  int cuts_remove = 0;
  int cuts_spur = 0;
  int cuts_shorten = 0;
};

// The phenomics of `model`; `plan` (may be null) is the cut plan decided for it. INVALID_ARGUMENT
// naming the field for an invalid model ("model: canes[3] (id 4): parent_id 9 is not a cane in
// this model"), a model without canes ("model: empty") or without a trunk, a plan that fails
// CutPlan::ValidateAgainst the model ("plan: ..."), or invalid options.
absl::StatusOr<Phenomics> ComputePhenomics(const VineModel& model, const CutPlan* plan,
                                           const PhenomicsOptions& options = {});

// One JSON object with the field names above (the histogram as {"bin_mm", "first_bin_mm",
// "counts"}, the cuts as "cuts_planned" and "cuts_by_reason": {"remove", "spur", "shorten"});
// the plan's fields are null when has_plan is false.
nlohmann::json PhenomicsToJson(const Phenomics& phenomics);

}  // namespace vb::decide
