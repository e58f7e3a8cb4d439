// SPDX-License-Identifier: Apache-2.0
#include "core/vine_model.h"

#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "absl/strings/str_cat.h"

namespace vb {

std::string_view CaneKindName(CaneKind kind) {
  switch (kind) {
    case CaneKind::kTrunk:
      return "trunk";
    case CaneKind::kCane:
      return "cane";
    case CaneKind::kSpur:
      return "spur";
  }
  return "cane";
}

absl::StatusOr<CaneKind> ParseCaneKind(std::string_view name) {
  if (name == "trunk") return CaneKind::kTrunk;
  if (name == "cane") return CaneKind::kCane;
  if (name == "spur") return CaneKind::kSpur;
  return absl::InvalidArgumentError(
      absl::StrCat("kind: unknown cane kind '", std::string(name), "' (expected trunk, cane or spur)"));
}

absl::Status VineModel::Validate() const {
  std::unordered_map<int64_t, size_t> index;
  int trunks = 0;
  for (size_t i = 0; i < canes.size(); ++i) {
    const Cane& cane = canes[i];
    const std::string what = absl::StrCat("canes[", i, "] (id ", cane.id.value, ")");
    if (!index.emplace(cane.id.value, i).second) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": duplicate id"));
    }
    if (absl::Status s = cane.polyline.Validate(what); !s.ok()) return s;
    if (cane.kind == CaneKind::kTrunk) ++trunks;
    if (!cane.parent_id.has_value() && cane.kind != CaneKind::kTrunk) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ": parent_id is null but kind is ", std::string(CaneKindName(cane.kind))));
    }
  }
  if (trunks > 1) {
    return absl::InvalidArgumentError(absl::StrCat("canes: ", trunks, " trunks, at most 1 allowed"));
  }
  for (size_t i = 0; i < canes.size(); ++i) {
    const Cane& cane = canes[i];
    if (cane.parent_id.has_value() && !index.contains(cane.parent_id->value)) {
      return absl::InvalidArgumentError(absl::StrCat("canes[", i, "] (id ", cane.id.value,
                                                     "): parent_id ", cane.parent_id->value,
                                                     " is not a cane in this model"));
    }
  }
  // Cycle check: walk up from every cane; a walk longer than the cane count is a cycle.
  for (size_t i = 0; i < canes.size(); ++i) {
    size_t steps = 0;
    std::optional<CaneId> at = canes[i].parent_id;
    while (at.has_value()) {
      if (++steps > canes.size()) {
        return absl::InvalidArgumentError(absl::StrCat("canes[", i, "] (id ", canes[i].id.value,
                                                       "): parent_id chain forms a cycle"));
      }
      at = canes[index.at(at->value)].parent_id;
    }
  }
  for (size_t i = 0; i < head.spheres.size(); ++i) {
    const Sphere& s = head.spheres[i];
    if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat("head.spheres[", i, "]: centre must be finite and radius > 0"));
    }
  }
  std::unordered_set<int64_t> wire_ids;
  for (size_t i = 0; i < wires.size(); ++i) {
    const Wire& w = wires[i];
    const std::string what = absl::StrCat("wires[", i, "] (id ", w.id.value, ")");
    if (!wire_ids.insert(w.id.value).second) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": duplicate id"));
    }
    if (w.points.size() < 2) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".points: needs at least 2 points"));
    }
    for (size_t k = 0; k < w.points.size(); ++k) {
      if (!w.points[k].allFinite()) {
        return absl::InvalidArgumentError(absl::StrCat(what, ".points[", k, "] is not finite"));
      }
    }
    if (!std::isfinite(w.radius) || w.radius <= 0.0) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".radius must be finite and > 0"));
    }
  }
  std::unordered_set<int64_t> post_ids;
  for (size_t i = 0; i < posts.size(); ++i) {
    const Post& p = posts[i];
    const std::string what = absl::StrCat("posts[", i, "] (id ", p.id.value, ")");
    if (!post_ids.insert(p.id.value).second) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": duplicate id"));
    }
    if (!p.base.allFinite() || !p.top.allFinite()) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": base and top must be finite"));
    }
    if (!std::isfinite(p.radius) || p.radius <= 0.0) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".radius must be finite and > 0"));
    }
  }
  for (size_t i = 0; i < obstacles.size(); ++i) {
    if (absl::Status s = obstacles[i].polyline.Validate(absl::StrCat("obstacles[", i, "]"));
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

std::optional<size_t> VineModel::IndexOf(CaneId id) const {
  for (size_t i = 0; i < canes.size(); ++i) {
    if (canes[i].id == id) return i;
  }
  return std::nullopt;
}

std::vector<CaneId> VineModel::ChildrenOf(CaneId id) const {
  std::vector<CaneId> children;
  for (const Cane& c : canes) {
    if (c.parent_id == id) children.push_back(c.id);
  }
  return children;
}

std::vector<CaneId> VineModel::DescendantsOf(CaneId id) const {
  std::vector<CaneId> out;
  std::vector<CaneId> frontier = ChildrenOf(id);
  // Bounded by the cane count so a malformed (cyclic) model cannot loop forever.
  while (!frontier.empty() && out.size() <= canes.size()) {
    const CaneId next = frontier.back();
    frontier.pop_back();
    out.push_back(next);
    for (CaneId c : ChildrenOf(next)) frontier.push_back(c);
  }
  return out;
}

}  // namespace vb
