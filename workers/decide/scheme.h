// SPDX-License-Identifier: Apache-2.0
// Pruning schemes and their cost (Botterill et al. 2017 section 3.3; Corbett-Davies et al. 2012,
// "An expert system for automatically pruning vines"). A scheme is a choice of kept canes and
// spurs among the vine's candidate canes; its feature vector is the sum of per-cane features of
// its kept canes and spurs plus scheme-level features; its cost is a linear function of the
// features, w . f. The cheapest scheme is the decision. Thread-safe (pure functions).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/deadline.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"
#include "Eigen/Core"
#include "nlohmann/json.hpp"

namespace vb::decide {

// Where a cane grows from.
enum class CaneOrigin {
  kHead,   // from the head (or the trunk within the head's extent)
  kTrunk,  // from the trunk below the head (a water shoot)
  kCane,   // from another cane (a secondary cane)
};

// A cane that may be kept or left as a spur, with what the cost needs to know of it.
struct Candidate {
  CaneId id;
  size_t cane_index = 0;          // index into VineModel::canes
  CaneOrigin origin = CaneOrigin::kHead;
  double length_m = 0.0;
  double base_diameter_m = 0.0;   // mean diameter over the first 0.10 m
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  double base_distance_from_head_m = 0.0;  // base to the head centre
  // Angle between the cane's initial direction (base to 0.10 m along it) and the horizontal
  // along-row direction pointing away from the head on the base's side, in [0, pi].
  double angle_from_head_rad = 0.0;
  double wire_z_m = 0.0;          // the fruiting wire height used
  int side = 0;                   // -1 base left of the head centre (x smaller), +1 right
  std::vector<CaneId> ancestors;  // candidate canes this one grows from (nearest first)
};

// Feature indices of a scheme. Keep-features sum over kept canes, spur-features over spurs.
enum SchemeFeature : int {
  kKeepLengthShortfallM = 0,  // max(0, policy.max_kept_length_m - length)
  kKeepDiameterOutsideMm,     // distance of base diameter outside the preferred range, mm
  kKeepFromTrunk,             // 1 per kept water shoot
  kKeepFromCane,              // 1 per kept secondary cane
  kKeepBaseDistanceM,         // base distance from the head centre
  kKeepAngleRad,              // angle from the head (see Candidate)
  kKeepBelowWireM,            // max(0, wire_z - base_z)
  kKeepAboveWireM,            // max(0, base_z - wire_z)
  kSpurBaseDistanceM,
  kSpurFromTrunk,
  kSpurFromCane,
  kSpurDiameterOutsideMm,
  kImbalance,                 // |kept canes left - kept canes right|
  kSchemeFeatureCount
};

std::string_view SchemeFeatureName(int feature);  // e.g. "keep_length_shortfall_m"

using FeatureVector = Eigen::Matrix<double, kSchemeFeatureCount, 1>;

// The weights of the linear cost. Versioned and stored with the decision's provenance.
struct SchemeWeights {
  static constexpr int kVersion = 1;
  int version = kVersion;
  FeatureVector w = FeatureVector::Zero();

  // INVALID_ARGUMENT if any weight is not finite.
  absl::Status Validate() const;
};

// The default weights; each is justified in docs/decide.md.
SchemeWeights DefaultSchemeWeights();
// {"version":1, "weights":{"keep_length_shortfall_m":..., ...}}; missing features are
// INVALID_ARGUMENT naming them (a weight file must be complete), as are unknown ones.
nlohmann::json SchemeWeightsToJson(const SchemeWeights& weights);
absl::StatusOr<SchemeWeights> SchemeWeightsFromJson(const nlohmann::json& json);

struct Scheme {
  std::vector<CaneId> keep;   // sorted by id
  std::vector<CaneId> spurs;  // sorted by id
  auto operator<=>(const Scheme&) const = default;
};

// The candidate canes of `model` under `policy`: every cane of kind kCane (not the trunk, not old
// spurs). The head centre is the mean of the head spheres' centres (the trunk's top if there is
// no head). INVALID_ARGUMENT if the model fails VineModel::Validate or has no trunk.
absl::StatusOr<std::vector<Candidate>> FindCandidates(const VineModel& model,
                                                      const PruningPolicy& policy);

// Whether a scheme is allowed: exactly min(policy count, eligible) kept canes and spurs; kept
// canes at least min_kept_length_m long; no cane both kept and spurred; no kept cane or spur
// descending from another kept cane or spur (one would fall with the other's cut).
bool IsFeasible(const std::vector<Candidate>& candidates, const PruningPolicy& policy,
                const Scheme& scheme);

FeatureVector SchemeFeatures(const std::vector<Candidate>& candidates,
                             const PruningPolicy& policy, const Scheme& scheme);

struct SearchStats {
  long long schemes_visited = 0;  // nodes of the search tree expanded
  int candidates = 0;
};

// The feasible scheme of minimum cost w . f (exact; ties broken by the smaller Scheme). Branch
// and bound over candidates sorted by their own cost, bounding with the cheapest completions.
// DEADLINE_EXCEEDED if `deadline` expires; if no feasible scheme keeps any cane, the scheme with
// the most canes kept that is feasible is searched (down to none).
absl::StatusOr<Scheme> FindBestScheme(const std::vector<Candidate>& candidates,
                                      const PruningPolicy& policy, const SchemeWeights& weights,
                                      const Deadline& deadline = Deadline::Infinite(),
                                      SearchStats* stats = nullptr);

}  // namespace vb::decide
