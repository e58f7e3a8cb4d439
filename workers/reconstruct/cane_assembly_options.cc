// SPDX-License-Identifier: Apache-2.0
// AssemblyOptions::Validate (cane_assembly.h). Split from cane_assembly.cc.
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/cane_assembly.h"

namespace vb::reconstruct {
namespace {

bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }

}  // namespace

absl::Status AssemblyOptions::Validate() const {
  const std::pair<const char*, double> positive[] = {
      {"step_m", step_m},
      {"merge_distance_m", merge_distance_m},
      {"min_overlap_m", min_overlap_m},
      {"end_tolerance_m", end_tolerance_m},
      {"max_gap_m", max_gap_m},
      {"max_long_gap_m", max_long_gap_m},
      {"tangent_baseline_m", tangent_baseline_m},
      {"radius_smoothing_m", radius_smoothing_m}};
  for (const auto& [name, value] : positive) {
    if (!PositiveFinite(value)) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": must be finite and > 0, is ", value));
    }
  }
  const std::pair<const char*, double> non_negative[] = {
      {"min_isolated_length_m", min_isolated_length_m},
      {"min_cane_length_m", min_cane_length_m},
      {"min_evidence_m", min_evidence_m}};
  for (const auto& [name, value] : non_negative) {
    if (!(std::isfinite(value) && value >= 0.0)) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": must be finite and >= 0, is ", value));
    }
  }
  for (const auto& [name, value] : {std::pair{"merge_angle_deg", merge_angle_deg},
                                    std::pair{"max_chain_angle_deg", max_chain_angle_deg},
                                    std::pair{"max_long_gap_angle_deg", max_long_gap_angle_deg}}) {
    if (!(value > 0.0 && value < 90.0)) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": must be in (0, 90), is ", value));
    }
  }
  if (max_long_gap_m < max_gap_m) {
    return absl::InvalidArgumentError(absl::StrCat("max_long_gap_m: must be >= max_gap_m (",
                                                   max_gap_m, "), is ", max_long_gap_m));
  }
  if (!(max_radius_ratio >= 1.0 && std::isfinite(max_radius_ratio))) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_radius_ratio: must be finite and >= 1, is ", max_radius_ratio));
  }
  if (!(min_piece_probability >= 0.0 && min_piece_probability <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "min_piece_probability: must be in [0, 1], is ", min_piece_probability));
  }
  return absl::OkStatus();
}

}  // namespace vb::reconstruct
