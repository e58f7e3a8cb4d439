// SPDX-License-Identifier: Apache-2.0
// How a vine is to be pruned: the pruner's instructions, stored (versioned) with every decision
// (ARCHITECTURE.md "Cut plan"). After Botterill et al. 2017 section 3.3: cane pruning keeps a few
// long canes near the head to lay along the fruiting wire and leaves short spurs as next
// season's replacement canes; spur pruning keeps spurs only. Plain value type; thread-compatible.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "nlohmann/json.hpp"

namespace vb {

enum class PruningStyle { kCane, kSpur };

std::string_view PruningStyleName(PruningStyle style);
// INVALID_ARGUMENT for anything but "cane" and "spur".
absl::StatusOr<PruningStyle> ParsePruningStyle(std::string_view name);

struct PruningPolicy {
  static constexpr int kVersion = 1;

  int version = kVersion;                // format version of this policy record
  PruningStyle style = PruningStyle::kCane;
  int canes_to_keep = 2;                 // kept canes, 1-6 (cane style; must be 0 in spur style)
  int spurs = 2;                         // spurs left, 0-6 in cane style, 1-12 in spur style
  double spur_length_m = 0.10;           // a spur is its cane cut this far beyond its parent
  double cane_diameter_min_m = 0.007;    // preferred diameter of a kept cane (at its base)
  double cane_diameter_max_m = 0.012;
  double min_kept_length_m = 0.30;       // shorter canes are never kept
  double max_kept_length_m = 0.90;       // kept canes longer than this are shortened to it
  double cut_offset_m = 0.01;            // removal cuts lie this far along the cane beyond its
                                         // parent's surface
  // Height of the fruiting wire (kept canes are tied down along it); nullopt: the lowest wire of
  // the vine model near the head, or 0.95 m if the model has no wires.
  std::optional<double> fruiting_wire_z_m;
  // Heights of the wires above it (informational; decide does not use them yet).
  std::vector<double> foliage_wire_z_m;

  // INVALID_ARGUMENT naming the field ("policy.canes_to_keep: 9 is outside [1, 6]") for values
  // out of range, non-finite or inconsistent (min > max), or a version other than kVersion.
  absl::Status Validate() const;
};

// {"version":1, "style":"cane", "canes_to_keep":2, ...} with every field; fruiting_wire_z_m is
// null when unset.
nlohmann::json PruningPolicyToJson(const PruningPolicy& policy);
// Fields missing from `json` keep their defaults (so a policy file may name only what differs;
// in spur style a missing canes_to_keep is 0, not 2); unknown fields, wrong types and invalid
// values are INVALID_ARGUMENT naming the field ("policy.spurs: not an integer").
// Valid ranges (Validate): spur_length_m [0.005, 1], diameters [0, 0.05] with min <= max,
// min_kept_length_m [0, 5] <= max_kept_length_m [0.01, 5], cut_offset_m [0.001, 0.2], wire
// heights [0.05, 3] with every foliage wire above the fruiting wire when that is set.
absl::StatusOr<PruningPolicy> PruningPolicyFromJson(const nlohmann::json& json);
// Errors are prefixed with the path.
absl::StatusOr<PruningPolicy> ReadPruningPolicy(const std::string& path);

}  // namespace vb
