// SPDX-License-Identifier: Apache-2.0
// Candidates, features and weights of pruning schemes. The search is in scheme_search.cc.
#include "workers/decide/scheme.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::decide {

namespace {

constexpr const char* kFeatureNames[kSchemeFeatureCount] = {
    "keep_length_shortfall_m", "keep_diameter_outside_mm", "keep_from_trunk",
    "keep_from_cane",          "keep_base_distance_m",     "keep_angle_rad",
    "keep_below_wire_m",       "keep_above_wire_m",        "spur_base_distance_m",
    "spur_from_trunk",         "spur_from_cane",           "spur_diameter_outside_mm",
    "imbalance",
};

// Base measurements (diameter, initial direction) look at this much of the cane.
constexpr double kBaseSpanM = 0.10;
// A cane from the trunk counts as from the head when its base is this close to a head sphere
// (the reconstructed head is a rough union of spheres).
constexpr double kHeadMarginM = 0.03;
// Without head spheres, the head is the trunk's top and this is its reach.
constexpr double kTrunkTopHeadRadiusM = 0.10;
constexpr double kDefaultWireZM = 0.95;

}  // namespace

std::string_view SchemeFeatureName(int feature) {
  if (feature < 0 || feature >= kSchemeFeatureCount) return "unknown";
  return kFeatureNames[feature];
}

absl::Status SchemeWeights::Validate() const {
  if (version != kVersion) {
    return absl::InvalidArgumentError(absl::StrCat("weights.version: ", version,
                                                   " is not supported (expected ", kVersion, ")"));
  }
  for (int f = 0; f < kSchemeFeatureCount; ++f) {
    if (!std::isfinite(w[f])) {
      return absl::InvalidArgumentError(
          absl::StrCat("weights.", kFeatureNames[f], ": not finite"));
    }
  }
  return absl::OkStatus();
}

SchemeWeights DefaultSchemeWeights() {
  // Rationale for each value: docs/decide.md "Features and default weights". Units: cost per unit
  // of the feature; one unit of cost is roughly "a pruner would notice".
  SchemeWeights weights;
  FeatureVector& w = weights.w;
  w[kKeepLengthShortfallM] = 2.0;
  w[kKeepDiameterOutsideMm] = 0.3;
  w[kKeepFromTrunk] = 1.5;
  w[kKeepFromCane] = 1.0;
  w[kKeepBaseDistanceM] = 6.0;
  w[kKeepAngleRad] = 0.4;
  w[kKeepBelowWireM] = 1.0;
  w[kKeepAboveWireM] = 4.0;
  w[kSpurBaseDistanceM] = 8.0;
  w[kSpurFromTrunk] = 0.5;
  w[kSpurFromCane] = 1.5;
  w[kSpurDiameterOutsideMm] = 0.1;
  w[kImbalance] = 1.0;
  return weights;
}

nlohmann::json SchemeWeightsToJson(const SchemeWeights& weights) {
  nlohmann::json w = nlohmann::json::object();
  for (int f = 0; f < kSchemeFeatureCount; ++f) w[std::string(SchemeFeatureName(f))] = weights.w[f];
  return {{"version", weights.version}, {"weights", w}};
}

absl::StatusOr<SchemeWeights> SchemeWeightsFromJson(const nlohmann::json& json) {
  if (!json.is_object()) return absl::InvalidArgumentError("weights: not a JSON object");
  for (const auto& [key, value] : json.items()) {
    if (key != "version" && key != "weights") {
      return absl::InvalidArgumentError(absl::StrCat(key, ": unknown field"));
    }
  }
  SchemeWeights weights;
  auto version = json.find("version");
  if (version == json.end()) return absl::InvalidArgumentError("version: missing");
  if (!version->is_number_integer()) return absl::InvalidArgumentError("version: not an integer");
  weights.version = static_cast<int>(version->get<int64_t>());
  auto w = json.find("weights");
  if (w == json.end()) return absl::InvalidArgumentError("weights: missing");
  if (!w->is_object()) return absl::InvalidArgumentError("weights: not an object");
  for (const auto& [key, value] : w->items()) {
    const auto* it = std::find(std::begin(kFeatureNames), std::end(kFeatureNames), key);
    if (it == std::end(kFeatureNames)) {
      return absl::InvalidArgumentError(absl::StrCat("weights.", key, ": unknown feature"));
    }
    if (!value.is_number()) {
      return absl::InvalidArgumentError(absl::StrCat("weights.", key, ": not a number"));
    }
    weights.w[it - std::begin(kFeatureNames)] = value.get<double>();
  }
  for (int f = 0; f < kSchemeFeatureCount; ++f) {
    if (!w->contains(kFeatureNames[f])) {
      return absl::InvalidArgumentError(
          absl::StrCat("weights.", kFeatureNames[f], ": missing (a weight file must be complete)"));
    }
  }
  VB_RETURN_IF_ERROR(weights.Validate());
  return weights;
}

namespace {

Eigen::Vector3d HeadCentre(const VineModel& model, const Cane& trunk) {
  if (model.head.spheres.empty()) return trunk.polyline.points.back();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Sphere& s : model.head.spheres) sum += s.center;
  return sum / static_cast<double>(model.head.spheres.size());
}

// Height of a wire at x (linear between its points; the nearest end outside its span).
double WireZAt(const Wire& wire, double x) {
  const auto& p = wire.points;
  for (size_t i = 0; i + 1 < p.size(); ++i) {
    const double x0 = std::min(p[i].x(), p[i + 1].x());
    const double x1 = std::max(p[i].x(), p[i + 1].x());
    if (x < x0 || x > x1) continue;
    const double dx = p[i + 1].x() - p[i].x();
    const double f = std::abs(dx) > 1e-12 ? (x - p[i].x()) / dx : 0.0;
    return p[i].z() + f * (p[i + 1].z() - p[i].z());
  }
  const auto nearest = std::min_element(p.begin(), p.end(), [x](const auto& a, const auto& b) {
    return std::abs(a.x() - x) < std::abs(b.x() - x);
  });
  return nearest->z();
}

double FruitingWireZ(const VineModel& model, const PruningPolicy& policy, double head_x) {
  if (policy.fruiting_wire_z_m.has_value()) return *policy.fruiting_wire_z_m;
  double z = std::numeric_limits<double>::infinity();
  for (const Wire& wire : model.wires) z = std::min(z, WireZAt(wire, head_x));
  return std::isfinite(z) ? z : kDefaultWireZM;
}

bool NearHead(const VineModel& model, const Cane& trunk, const Eigen::Vector3d& p) {
  if (model.head.spheres.empty()) {
    return (p - trunk.polyline.points.back()).norm() <= kTrunkTopHeadRadiusM;
  }
  double lowest = std::numeric_limits<double>::infinity();
  for (const Sphere& s : model.head.spheres) {
    if ((p - s.center).norm() <= s.radius + kHeadMarginM) return true;
    lowest = std::min(lowest, s.center.z() - s.radius);
  }
  return p.z() >= lowest;
}

}  // namespace

absl::StatusOr<std::vector<Candidate>> FindCandidates(const VineModel& model,
                                                      const PruningPolicy& policy) {
  VB_RETURN_IF_ERROR(policy.Validate());
  VB_RETURN_IF_ERROR(model.Validate());
  const Cane* trunk = nullptr;
  std::unordered_map<int64_t, size_t> index;
  for (size_t i = 0; i < model.canes.size(); ++i) {
    if (model.canes[i].kind == CaneKind::kTrunk) trunk = &model.canes[i];
    index.emplace(model.canes[i].id.value, i);
  }
  if (trunk == nullptr) return absl::InvalidArgumentError("model: no trunk");
  const Eigen::Vector3d head = HeadCentre(model, *trunk);
  const double wire_z = FruitingWireZ(model, policy, head.x());

  std::vector<Candidate> out;
  for (size_t i = 0; i < model.canes.size(); ++i) {
    const Cane& cane = model.canes[i];
    if (cane.kind != CaneKind::kCane) continue;
    const Polyline3& line = cane.polyline;
    Candidate c;
    c.id = cane.id;
    c.cane_index = i;
    const Cane& parent = model.canes[index.at(cane.parent_id->value)];
    if (parent.kind == CaneKind::kCane) {
      c.origin = CaneOrigin::kCane;
    } else {
      c.origin = NearHead(model, *trunk, line.points.front()) ? CaneOrigin::kHead
                                                              : CaneOrigin::kTrunk;
    }
    c.length_m = line.Length();
    c.base_diameter_m = line.MeanBaseDiameter(kBaseSpanM);
    c.base = line.points.front();
    c.base_distance_from_head_m = (c.base - head).norm();
    c.side = c.base.x() < head.x() ? -1 : +1;
    const Eigen::Vector3d initial = line.PointAt(std::min(kBaseSpanM, c.length_m)) - c.base;
    const double n = initial.norm();
    c.angle_from_head_rad =
        n > 0.0 ? std::acos(std::clamp(initial.x() * c.side / n, -1.0, 1.0)) : std::numbers::pi / 2;
    c.wire_z_m = wire_z;
    // Validate() guarantees the chain ends at the trunk without cycles.
    for (std::optional<CaneId> at = cane.parent_id; at.has_value();) {
      const Cane& a = model.canes[index.at(at->value)];
      if (a.kind == CaneKind::kCane) c.ancestors.push_back(a.id);
      at = a.parent_id;
    }
    out.push_back(std::move(c));
  }
  return out;
}

FeatureVector KeepFeatures(const Candidate& c, const PruningPolicy& policy) {
  FeatureVector f = FeatureVector::Zero();
  f[kKeepLengthShortfallM] = std::max(0.0, policy.max_kept_length_m - c.length_m);
  const double d = c.base_diameter_m;
  f[kKeepDiameterOutsideMm] =
      1000.0 * std::max({0.0, policy.cane_diameter_min_m - d, d - policy.cane_diameter_max_m});
  f[kKeepFromTrunk] = c.origin == CaneOrigin::kTrunk ? 1.0 : 0.0;
  f[kKeepFromCane] = c.origin == CaneOrigin::kCane ? 1.0 : 0.0;
  f[kKeepBaseDistanceM] = c.base_distance_from_head_m;
  f[kKeepAngleRad] = c.angle_from_head_rad;
  f[kKeepBelowWireM] = std::max(0.0, c.wire_z_m - c.base.z());
  f[kKeepAboveWireM] = std::max(0.0, c.base.z() - c.wire_z_m);
  return f;
}

FeatureVector SpurFeatures(const Candidate& c, const PruningPolicy& policy) {
  FeatureVector f = FeatureVector::Zero();
  f[kSpurBaseDistanceM] = c.base_distance_from_head_m;
  f[kSpurFromTrunk] = c.origin == CaneOrigin::kTrunk ? 1.0 : 0.0;
  f[kSpurFromCane] = c.origin == CaneOrigin::kCane ? 1.0 : 0.0;
  const double d = c.base_diameter_m;
  f[kSpurDiameterOutsideMm] =
      1000.0 * std::max({0.0, policy.cane_diameter_min_m - d, d - policy.cane_diameter_max_m});
  return f;
}

FeatureVector SchemeFeatures(const std::vector<Candidate>& candidates,
                             const PruningPolicy& policy, const Scheme& scheme) {
  auto find = [&candidates](CaneId id) -> const Candidate* {
    for (const Candidate& c : candidates) {
      if (c.id == id) return &c;
    }
    return nullptr;
  };
  FeatureVector f = FeatureVector::Zero();
  int left = 0;
  int right = 0;
  for (CaneId id : scheme.keep) {
    const Candidate* c = find(id);
    if (c == nullptr) continue;
    f += KeepFeatures(*c, policy);
    left += c->side < 0 ? 1 : 0;
    right += c->side > 0 ? 1 : 0;
  }
  for (CaneId id : scheme.spurs) {
    if (const Candidate* c = find(id); c != nullptr) f += SpurFeatures(*c, policy);
  }
  f[kImbalance] = std::abs(left - right);
  return f;
}

namespace {

// The candidate forest: index of each candidate's nearest candidate ancestor, or -1.
std::vector<int> CandidateParents(const std::vector<Candidate>& candidates) {
  std::unordered_map<int64_t, int> index;
  for (size_t i = 0; i < candidates.size(); ++i) index.emplace(candidates[i].id.value, i);
  std::vector<int> parent(candidates.size(), -1);
  for (size_t i = 0; i < candidates.size(); ++i) {
    for (CaneId a : candidates[i].ancestors) {
      auto it = index.find(a.value);
      if (it != index.end()) {
        parent[i] = it->second;
        break;
      }
    }
  }
  return parent;
}

int KeepTarget(const PruningPolicy& policy) {
  return policy.style == PruningStyle::kSpur ? 0 : policy.canes_to_keep;
}

}  // namespace

SchemeSize FeasibleSchemeSize(const std::vector<Candidate>& candidates,
                              const PruningPolicy& policy) {
  // An allowed scheme is an antichain of the candidate forest. Tree DP: best[v][l] is the largest
  // antichain in v's subtree holding at least l canes long enough to keep (l capped at the keep
  // target k), or -1 if there is none.
  const int k = std::max(0, KeepTarget(policy));
  const int n = static_cast<int>(candidates.size());
  const std::vector<int> parent = CandidateParents(candidates);
  std::vector<std::vector<int>> children(n);
  std::vector<int> roots;
  for (int i = 0; i < n; ++i) (parent[i] < 0 ? roots : children[parent[i]]).push_back(i);
  using Table = std::vector<int>;
  auto merge = [k](const Table& a, const Table& b) {
    Table out(k + 1, -1);
    for (int i = 0; i <= k; ++i) {
      for (int j = 0; j <= k; ++j) {
        if (a[i] < 0 || b[j] < 0) continue;
        int& slot = out[std::min(k, i + j)];
        slot = std::max(slot, a[i] + b[j]);
      }
    }
    for (int l = k - 1; l >= 0; --l) out[l] = std::max(out[l], out[l + 1]);  // "at least l"
    return out;
  };
  Table empty(k + 1, -1);
  empty[0] = 0;
  // Candidates come in arbitrary order; an explicit post-order walk from the roots.
  std::vector<Table> best(n);
  std::vector<std::pair<int, bool>> stack;
  for (int r : roots) stack.push_back({r, false});
  while (!stack.empty()) {
    auto [v, expanded] = stack.back();
    stack.pop_back();
    if (!expanded) {
      stack.push_back({v, true});
      for (int c : children[v]) stack.push_back({c, false});
      continue;
    }
    Table below = empty;
    for (int c : children[v]) below = merge(below, best[c]);
    Table alone = empty;
    alone[0] = 1;
    if (k > 0 && candidates[v].length_m >= policy.min_kept_length_m) alone[1] = 1;
    for (int l = 0; l <= k; ++l) below[l] = std::max(below[l], alone[l]);
    best[v] = std::move(below);
  }
  Table all = empty;
  for (int r : roots) all = merge(all, best[r]);
  SchemeSize size;
  for (int l = k; l >= 0; --l) {
    if (all[l] >= l) {
      size.keep = l;
      break;
    }
  }
  size.spurs = std::min(policy.spurs, all[size.keep] - size.keep);
  return size;
}

bool IsFeasible(const std::vector<Candidate>& candidates, const PruningPolicy& policy,
                const Scheme& scheme) {
  std::unordered_map<int64_t, const Candidate*> by_id;
  for (const Candidate& c : candidates) by_id.emplace(c.id.value, &c);
  std::set<int64_t> chosen;
  for (const auto* list : {&scheme.keep, &scheme.spurs}) {
    for (CaneId id : *list) {
      auto it = by_id.find(id.value);
      if (it == by_id.end() || !chosen.insert(id.value).second) return false;
      if (list == &scheme.keep && it->second->length_m < policy.min_kept_length_m) return false;
    }
  }
  for (int64_t id : chosen) {
    for (CaneId a : by_id.at(id)->ancestors) {
      if (chosen.contains(a.value)) return false;
    }
  }
  const SchemeSize size = FeasibleSchemeSize(candidates, policy);
  return static_cast<int>(scheme.keep.size()) == size.keep &&
         static_cast<int>(scheme.spurs.size()) == size.spurs;
}

}  // namespace vb::decide
