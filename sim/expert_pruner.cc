// SPDX-License-Identifier: Apache-2.0
#include "sim/expert_pruner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "absl/strings/str_cat.h"

namespace vb::sim {
namespace {

int OriginRank(ExpertOrigin origin) { return static_cast<int>(origin); }

Eigen::Vector3d HeadCentre(const VineModel& model, const Cane& trunk) {
  if (model.head.spheres.empty()) return trunk.polyline.points.back();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Sphere& s : model.head.spheres) sum += s.center;
  return sum / static_cast<double>(model.head.spheres.size());
}

// Whether a base on the trunk (or an old spur) is on the head: within kExpertHeadContactM of a
// head sphere or above the head's lowest point; without spheres, within kExpertTrunkTopHeadM of
// the trunk's top.
bool OnHead(const VineModel& model, const Cane& trunk, const Eigen::Vector3d& p) {
  if (model.head.spheres.empty()) {
    return (p - trunk.polyline.points.back()).norm() <= kExpertTrunkTopHeadM;
  }
  double lowest = std::numeric_limits<double>::infinity();
  for (const Sphere& s : model.head.spheres) {
    if ((p - s.center).norm() - s.radius <= kExpertHeadContactM) return true;
    lowest = std::min(lowest, s.center.z() - s.radius);
  }
  return p.z() >= lowest;
}

// Height at `x` of the lowest wire spanning x (linear between wire points), if any.
std::optional<double> LowestWireAt(const VineModel& model, double x) {
  std::optional<double> lowest;
  for (const Wire& wire : model.wires) {
    for (size_t i = 0; i + 1 < wire.points.size(); ++i) {
      const Eigen::Vector3d& a = wire.points[i];
      const Eigen::Vector3d& b = wire.points[i + 1];
      if (x < std::min(a.x(), b.x()) || x > std::max(a.x(), b.x())) continue;
      const double t = std::abs(b.x() - a.x()) > 1e-12 ? (x - a.x()) / (b.x() - a.x()) : 0.0;
      const double z = a.z() + t * (b.z() - a.z());
      if (!lowest || z < *lowest) lowest = z;
      break;
    }
  }
  return lowest;
}

double DiameterOutsideMm(double diameter_m, const PruningPolicy& policy) {
  if (diameter_m < policy.cane_diameter_min_m) return 1e3 * (policy.cane_diameter_min_m - diameter_m);
  if (diameter_m > policy.cane_diameter_max_m) return 1e3 * (diameter_m - policy.cane_diameter_max_m);
  return 0.0;
}

// Lexicographic rank keys (smaller is better); K3 for kept canes, the spur rule for spurs.
using KeepKey = std::tuple<int, double, double, double, double, int64_t>;
using SpurKey = std::tuple<int, double, double, int64_t>;

KeepKey KeepRank(const ExpertCaneView& c, const PruningPolicy& policy) {
  return {OriginRank(c.origin), c.diameter_outside_mm,
          std::max(0.0, policy.max_kept_length_m - c.length_m), std::max(0.0, -c.base_below_wire_m),
          c.placement_rad, c.id.value};
}

SpurKey SpurRank(const ExpertCaneView& c) {
  return {OriginRank(c.origin), c.diameter_outside_mm, c.base_distance_from_head_m, c.id.value};
}

// Rule K4: `c` is related (ancestor or descendant) to a cane already chosen.
bool Related(const ExpertCaneView& c, const std::unordered_set<int64_t>& chosen,
             const std::unordered_map<int64_t, const ExpertCaneView*>& by_id) {
  for (CaneId a : c.ancestors) {
    if (chosen.contains(a.value)) return true;
  }
  for (int64_t id : chosen) {
    const ExpertCaneView* other = by_id.at(id);
    if (std::find(other->ancestors.begin(), other->ancestors.end(), c.id) != other->ancestors.end()) {
      return true;
    }
  }
  return false;
}

std::string SideName(int side) { return side < 0 ? "left" : "right"; }

}  // namespace

absl::StatusOr<std::vector<ExpertCaneView>> AssessCanes(const VineModel& model,
                                                        const PruningPolicy& policy) {
  if (absl::Status s = policy.Validate(); !s.ok()) return s;
  if (absl::Status s = model.Validate(); !s.ok()) return s;
  const Cane* trunk = nullptr;
  for (const Cane& c : model.canes) {
    if (c.kind == CaneKind::kTrunk) trunk = &c;
  }
  if (trunk == nullptr) return absl::InvalidArgumentError("model.canes: no trunk");

  const Eigen::Vector3d head = HeadCentre(model, *trunk);
  const double wire_z = policy.fruiting_wire_z_m.has_value()
                            ? *policy.fruiting_wire_z_m
                            : LowestWireAt(model, head.x()).value_or(kExpertDefaultWireZM);

  std::vector<ExpertCaneView> views;
  for (const Cane& cane : model.canes) {
    if (cane.kind != CaneKind::kCane) continue;
    const Polyline3& line = cane.polyline;
    ExpertCaneView v;
    v.id = cane.id;
    const Cane& parent = model.canes[*model.IndexOf(*cane.parent_id)];
    const Eigen::Vector3d& base = line.points.front();
    if (parent.kind == CaneKind::kCane) {
      v.origin = ExpertOrigin::kCane;
    } else if (OnHead(model, *trunk, base)) {
      v.origin = ExpertOrigin::kHead;
    } else {
      v.origin = parent.kind == CaneKind::kTrunk ? ExpertOrigin::kTrunk : ExpertOrigin::kCane;
    }
    v.length_m = line.Length();
    v.base_diameter_m = line.MeanBaseDiameter(kExpertBaseSpanM);
    v.diameter_outside_mm = DiameterOutsideMm(v.base_diameter_m, policy);
    v.base_distance_from_head_m = (base - head).norm();
    v.base_below_wire_m = wire_z - base.z();
    v.side = base.x() < head.x() ? -1 : 1;
    const Eigen::Vector3d ahead = line.PointAt(std::min(kExpertBaseSpanM, v.length_m)) - base;
    const double n = ahead.norm();
    const double cos_angle = n > 1e-12 ? v.side * ahead.x() / n : 0.0;
    v.angle_from_wire_rad = std::acos(std::clamp(cos_angle, -1.0, 1.0));
    v.placement_rad = v.angle_from_wire_rad + kExpertRadPerMetreFromHead * v.base_distance_from_head_m;
    // Ancestors among canes of kind `cane` (the walk ends at the trunk; Validate excluded cycles).
    for (std::optional<CaneId> p = cane.parent_id; p.has_value();) {
      const Cane& up = model.canes[*model.IndexOf(*p)];
      if (up.kind != CaneKind::kCane) break;
      v.ancestors.push_back(up.id);
      p = up.parent_id;
    }
    views.push_back(std::move(v));
  }
  return views;
}

absl::StatusOr<ExpertDecision> ExpertPrune(const VineModel& model, const PruningPolicy& policy) {
  absl::StatusOr<std::vector<ExpertCaneView>> assessed = AssessCanes(model, policy);
  if (!assessed.ok()) return assessed.status();
  const std::vector<ExpertCaneView>& canes = *assessed;
  std::unordered_map<int64_t, const ExpertCaneView*> by_id;
  for (const ExpertCaneView& c : canes) by_id[c.id.value] = &c;

  ExpertDecision decision;
  std::unordered_set<int64_t> chosen;

  // Kept canes: K1 eligibility, then K2 side alternation over the K3 ranking, skipping K4.
  const int keep_target = policy.style == PruningStyle::kCane ? policy.canes_to_keep : 0;
  int eligible = 0;
  for (const ExpertCaneView& c : canes) eligible += c.length_m >= policy.min_kept_length_m;
  int kept_on[2] = {0, 0};  // left, right
  bool noted_side = false;
  while (static_cast<int>(decision.keep.size()) < keep_target) {
    std::optional<KeepKey> best_key[2];
    const ExpertCaneView* best[2] = {nullptr, nullptr};
    for (const ExpertCaneView& c : canes) {
      if (c.length_m < policy.min_kept_length_m || chosen.contains(c.id.value) ||
          Related(c, chosen, by_id)) {
        continue;
      }
      const int s = c.side < 0 ? 0 : 1;
      const KeepKey key = KeepRank(c, policy);
      if (!best_key[s] || key < *best_key[s]) {
        best_key[s] = key;
        best[s] = &c;
      }
    }
    if (best[0] == nullptr && best[1] == nullptr) break;
    int pick;
    if (best[0] == nullptr || best[1] == nullptr) {
      pick = best[0] != nullptr ? 0 : 1;
      const int missing = 1 - pick;
      if (kept_on[pick] >= kept_on[missing] && !noted_side) {
        noted_side = true;
        decision.notes.push_back(absl::StrCat("no cane left to keep on the ",
                                              SideName(missing ? 1 : -1), " side; cane ",
                                              best[pick]->id.value, " kept on the ",
                                              SideName(pick ? 1 : -1), " instead"));
      }
    } else if (kept_on[0] != kept_on[1]) {
      pick = kept_on[0] < kept_on[1] ? 0 : 1;
    } else {
      pick = *best_key[0] < *best_key[1] ? 0 : 1;
    }
    decision.keep.push_back(best[pick]->id);
    chosen.insert(best[pick]->id.value);
    ++kept_on[pick];
  }
  if (static_cast<int>(decision.keep.size()) < keep_target) {
    decision.notes.push_back(absl::StrCat("only ", decision.keep.size(), " of ", eligible,
                                          " canes at least ", policy.min_kept_length_m,
                                          " m long could be kept; policy asks for ", keep_target));
  }

  // Spurs: the spur ranking over the remaining canes, skipping K4.
  while (static_cast<int>(decision.spurs.size()) < policy.spurs) {
    const ExpertCaneView* best = nullptr;
    std::optional<SpurKey> best_key;
    for (const ExpertCaneView& c : canes) {
      if (c.length_m < policy.spur_length_m || chosen.contains(c.id.value) ||
          Related(c, chosen, by_id)) {
        continue;
      }
      const SpurKey key = SpurRank(c);
      if (!best_key || key < *best_key) {
        best_key = key;
        best = &c;
      }
    }
    if (best == nullptr) {
      decision.notes.push_back(absl::StrCat("only ", decision.spurs.size(),
                                            " spurs could be left; policy asks for ", policy.spurs));
      break;
    }
    decision.spurs.push_back(best->id);
    chosen.insert(best->id.value);
  }
  std::sort(decision.keep.begin(), decision.keep.end());
  std::sort(decision.spurs.begin(), decision.spurs.end());
  return decision;
}

}  // namespace vb::sim
