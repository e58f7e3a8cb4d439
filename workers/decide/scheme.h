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
  int side = 0;                   // -1 base left of the head centre (x smaller), +1 right;
                                  // 0 (hand-made candidates only) counts on neither side
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
// spurs), in model order. The head centre is the mean of the head spheres' centres (the trunk's
// top if there is no head). Origin: a cane whose parent is the trunk or an old spur is kHead when
// its base lies within 0.03 m of a head sphere (0.10 m of the trunk's top without spheres) or
// above the head's lowest point, else kTrunk; a cane whose parent is a cane is kCane. The wire
// height is policy.fruiting_wire_z_m, else the lowest wire's height at the head centre's x
// (nearest end if the wire does not span it), else 0.95 m. side is +1 when base x equals the
// head centre's. INVALID_ARGUMENT if the policy or the model is invalid (VineModel::Validate) or
// the model has no trunk ("model: no trunk").
absl::StatusOr<std::vector<Candidate>> FindCandidates(const VineModel& model,
                                                      const PruningPolicy& policy);

// How many canes a scheme keeps and how many spurs it leaves.
struct SchemeSize {
  int keep = 0;
  int spurs = 0;
  auto operator<=>(const SchemeSize&) const = default;
};

// The size every feasible scheme has: the largest (keep first, then spurs) that some scheme
// obeying the rules of IsFeasible can reach, at most (policy.canes_to_keep, policy.spurs). It is
// (min(canes_to_keep, canes long enough), min(spurs, the rest)) unless ancestry forbids that
// (e.g. the only long canes grow from one another); then it is smaller, down to (0, 0).
SchemeSize FeasibleSchemeSize(const std::vector<Candidate>& candidates,
                              const PruningPolicy& policy);

// Whether a scheme is allowed: its ids are candidates, each listed once (order does not matter);
// kept canes at least min_kept_length_m long; no cane both kept and spurred; no kept cane or spur
// descending from another kept cane or spur (one would fall with the other's cut); and exactly
// FeasibleSchemeSize() kept canes and spurs.
bool IsFeasible(const std::vector<Candidate>& candidates, const PruningPolicy& policy,
                const Scheme& scheme);

// Per-cane features: what one kept cane (or one spur) adds to a scheme's feature vector.
FeatureVector KeepFeatures(const Candidate& candidate, const PruningPolicy& policy);
FeatureVector SpurFeatures(const Candidate& candidate, const PruningPolicy& policy);

// Sum of KeepFeatures over scheme.keep and SpurFeatures over scheme.spurs (in the order listed),
// plus kImbalance. Ids that are not candidates are ignored.
FeatureVector SchemeFeatures(const std::vector<Candidate>& candidates,
                             const PruningPolicy& policy, const Scheme& scheme);

struct SearchStats {
  long long schemes_visited = 0;  // nodes of the search tree expanded (both passes)
  int candidates = 0;
  double best_cost = 0.0;         // w . f of the scheme returned
};

// The feasible scheme (IsFeasible, so of size FeasibleSchemeSize) of minimum cost
// w . SchemeFeatures, exactly; costs within 1e-9 x (1 + sum over candidates and features of
// |w_f f_f| for keeping and for spurring + |w_imbalance| x keep) of the minimum are ties, broken
// by the smaller Scheme (keep ids compared first).
// Branch and bound (Land & Doig 1960): a first pass over candidates sorted by their own cost finds
// the minimum; a second pass in id order returns the first scheme within the tie tolerance, so the
// result does not depend on the order the candidates are given in. Both bound a partial scheme by
// its cost + the cheapest completions per side of the head (sorted per-cane costs, sound for
// weights of any sign) + the least imbalance term they allow + the cheapest spurs still free.
// DEADLINE_EXCEEDED / CANCELLED from `deadline`; INVALID_ARGUMENT for invalid policy or weights,
// or duplicate candidate ids. With no candidates the scheme is empty.
absl::StatusOr<Scheme> FindBestScheme(const std::vector<Candidate>& candidates,
                                      const PruningPolicy& policy, const SchemeWeights& weights,
                                      const Deadline& deadline = Deadline::Infinite(),
                                      SearchStats* stats = nullptr);

}  // namespace vb::decide
