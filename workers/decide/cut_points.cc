// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/cut_points.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::decide {
namespace {

// Step of the slide out of the head: the cut lands at most this far beyond the head's surface.
constexpr double kSlideStepM = 0.0005;

enum class Role { kNone, kKeep, kSpur };

// "0.012 m", for notes.
std::string Metres(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3f m", v);
  return buffer;
}

bool InsideHead(const HeadModel& head, const Eigen::Vector3d& p) {
  for (const Sphere& s : head.spheres) {
    if ((p - s.center).norm() < s.radius) return true;
  }
  return false;
}

// Arc length along `cane` where it leaves its parent's wood: the first point (2 mm steps) farther
// from the parent's axis than the parent's radius there; 0 if the base is already outside. The
// simulator and reconstruction both start a cane on its parent's axis, so a cut measured from the
// base alone would land inside a thick trunk.
double ExitFromParent(const Polyline3& cane, const Polyline3& parent) {
  constexpr double kStepM = 0.002;
  const double length = cane.Length();
  for (double s = 0.0; s < length; s += kStepM) {
    const Eigen::Vector3d p = cane.PointAt(s);
    const double on_parent = parent.Project(p);
    if ((p - parent.PointAt(on_parent)).norm() > parent.RadiusAt(on_parent)) return s;
  }
  return length;
}

// The planned cut on one cane, before the head slide and the falling rule.
struct PlannedCut {
  double s = 0.0;
  CutReason reason = CutReason::kRemove;
};

// Checks the scheme against the candidates; fills `role` by model index.
absl::Status CheckScheme(const VineModel& model, const std::vector<Candidate>& candidates,
                         const Scheme& scheme, std::vector<Role>* role) {
  std::unordered_map<int64_t, const Candidate*> by_id;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    if (c.cane_index >= model.canes.size() || model.canes[c.cane_index].id != c.id ||
        model.canes[c.cane_index].kind != CaneKind::kCane) {
      return absl::InvalidArgumentError(absl::StrCat(
          "candidates[", i, "]: cane ", c.id.value, " at index ", c.cane_index,
          " is not a cane of this model (candidates must come from FindCandidates)"));
    }
    by_id.emplace(c.id.value, &c);
  }
  std::map<int64_t, std::string> chosen;  // id -> "scheme.keep[i]"
  for (const auto& [list, name, r] :
       {std::tuple(&scheme.keep, "keep", Role::kKeep), std::tuple(&scheme.spurs, "spurs", Role::kSpur)}) {
    for (size_t i = 0; i < list->size(); ++i) {
      const CaneId id = (*list)[i];
      const std::string what = absl::StrCat("scheme.", name, "[", i, "]");
      auto it = by_id.find(id.value);
      if (it == by_id.end()) {
        return absl::InvalidArgumentError(
            absl::StrCat(what, ": cane ", id.value, " is not a candidate"));
      }
      if (!chosen.emplace(id.value, what).second) {
        return absl::InvalidArgumentError(
            absl::StrCat(what, ": cane ", id.value, " is already ", chosen[id.value]));
      }
      (*role)[it->second->cane_index] = r;
    }
  }
  for (const auto& [id, what] : chosen) {
    for (CaneId a : by_id.at(id)->ancestors) {
      if (auto it = chosen.find(a.value); it != chosen.end()) {
        return absl::InvalidArgumentError(absl::StrCat(what, ": cane ", id, " grows from cane ",
                                                       a.value, " (", it->second, ")"));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<CutPlacement> PlaceCuts(const VineModel& model,
                                       const std::vector<Candidate>& candidates,
                                       const PruningPolicy& policy, const Scheme& scheme,
                                       double max_head_slide_m) {
  VB_RETURN_IF_ERROR(policy.Validate());
  if (!std::isfinite(max_head_slide_m) || max_head_slide_m < 0.0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "options.max_head_slide_m: must be finite and >= 0, is ", max_head_slide_m));
  }
  const size_t n = model.canes.size();
  std::vector<Role> role(n, Role::kNone);
  VB_RETURN_IF_ERROR(CheckScheme(model, candidates, scheme, &role));

  std::unordered_map<int64_t, size_t> index;
  for (size_t i = 0; i < n; ++i) index.emplace(model.canes[i].id.value, i);
  std::vector<int> parent(n, -1);
  std::vector<double> attach(n, 0.0);  // arc length on the parent where the cane grows from it
  std::vector<double> exit(n, 0.0);    // arc length on the cane where it leaves the parent's wood
  std::vector<int> depth(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const Cane& cane = model.canes[i];
    if (!cane.parent_id.has_value()) continue;
    auto it = index.find(cane.parent_id->value);
    if (it == index.end()) {
      return absl::InvalidArgumentError(absl::StrCat("canes[", i, "] (id ", cane.id.value,
                                                     "): parent_id ", cane.parent_id->value,
                                                     " is not a cane in this model"));
    }
    parent[i] = static_cast<int>(it->second);
    attach[i] = model.canes[it->second].polyline.Project(cane.polyline.points.front());
    exit[i] = ExitFromParent(cane.polyline, model.canes[it->second].polyline);
  }
  // Parents before children (depth order); the model is validated, so chains end.
  for (size_t i = 0; i < n; ++i) {
    for (int a = parent[i]; a >= 0 && depth[i] <= static_cast<int>(n); a = parent[a]) ++depth[i];
  }
  std::vector<size_t> top_down(n);
  for (size_t i = 0; i < n; ++i) top_down[i] = i;
  std::stable_sort(top_down.begin(), top_down.end(),
                   [&depth](size_t a, size_t b) { return depth[a] < depth[b]; });

  // Protected canes: kept, spurred, or with such a cane growing from them. A protected cane that
  // is neither must stay up to `hold` (just beyond its farthest protected child).
  std::vector<char> protect(n, 0);
  std::vector<double> hold(n, -1.0);
  std::vector<int> held_for(n, -1);
  for (auto it = top_down.rbegin(); it != top_down.rend(); ++it) {
    const size_t i = *it;
    if (role[i] != Role::kNone) protect[i] = 1;
    if (!protect[i] || parent[i] < 0) continue;
    const int p = parent[i];
    protect[p] = 1;
    const double need =
        attach[i] + model.canes[i].polyline.radii.front() + policy.cut_offset_m;
    if (need > hold[p]) {
      hold[p] = need;
      held_for[p] = static_cast<int>(i);
    }
  }

  CutPlacement out;
  std::vector<std::optional<PlannedCut>> planned(n);
  for (size_t i = 0; i < n; ++i) {
    const Cane& cane = model.canes[i];
    if (cane.kind != CaneKind::kCane) continue;  // trunk and old spurs are never cut
    const double length = cane.polyline.Length();
    const std::string name = absl::StrCat("cane ", cane.id.value);
    switch (role[i]) {
      case Role::kKeep:
        if (length > policy.max_kept_length_m + kMinTrimM) {
          planned[i] = PlannedCut{policy.max_kept_length_m, CutReason::kShorten};
        }
        break;
      case Role::kSpur:
        if (length > exit[i] + policy.spur_length_m + kMinTrimM) {
          planned[i] = PlannedCut{exit[i] + policy.spur_length_m, CutReason::kSpur};
        } else {
          out.notes.push_back(absl::StrCat(name, ": spur left uncut (", Metres(length),
                                           " long, spurs are ", Metres(policy.spur_length_m),
                                           ")"));
        }
        break;
      case Role::kNone:
        if (protect[i]) {
          const std::string child = absl::StrCat("cane ", model.canes[held_for[i]].id.value);
          if (hold[i] < length - kMinTrimM) {
            planned[i] = PlannedCut{hold[i], CutReason::kShorten};
            out.notes.push_back(absl::StrCat(name, ": shortened to ", Metres(hold[i]),
                                             " instead of removed, so that ", child,
                                             " growing from it stays"));
          } else {
            out.notes.push_back(absl::StrCat(name, ": left uncut instead of removed, so that ",
                                             child, " growing from it stays"));
          }
        } else {
          planned[i] = PlannedCut{std::min(exit[i] + policy.cut_offset_m, 0.5 * length),
                                  CutReason::kRemove};
        }
        break;
    }
    if (!planned[i].has_value() || model.head.spheres.empty()) continue;
    // Out of the head: the cutter cannot reach into the knot of old wood, and cutting it would
    // wound the vine's permanent structure.
    double& s = planned[i]->s;
    const double limit = std::min(s + max_head_slide_m, length);
    const double start = s;
    while (InsideHead(model.head, cane.polyline.PointAt(s)) && s < limit) {
      s = std::min(s + kSlideStepM, limit);
    }
    if (InsideHead(model.head, cane.polyline.PointAt(s))) {
      out.notes.push_back(absl::StrCat(name, ": cut still inside the head after sliding ",
                                       Metres(s - start), " toward the tip"));
    } else if (s > start) {
      out.notes.push_back(absl::StrCat(name, ": cut slid ", Metres(s - start), " out of the head"));
    }
  }

  // Canes that fall with a cut ancestor need no cut of their own.
  std::vector<char> falls(n, 0);
  for (size_t i : top_down) {
    const int p = parent[i];
    if (p < 0) continue;
    falls[i] = falls[p] || (planned[p].has_value() && attach[i] > planned[p]->s);
    if (falls[i] && role[i] != Role::kNone) {
      return absl::InternalError(absl::StrCat("decide: cane ", model.canes[i].id.value,
                                              " would fall with an ancestor's cut"));
    }
  }

  std::vector<size_t> by_id;
  for (size_t i = 0; i < n; ++i) {
    if (planned[i].has_value() && !falls[i]) by_id.push_back(i);
  }
  std::sort(by_id.begin(), by_id.end(),
            [&model](size_t a, size_t b) { return model.canes[a].id < model.canes[b].id; });
  for (size_t i : by_id) {
    const Polyline3& line = model.canes[i].polyline;
    Cut cut;
    cut.id = CutId(static_cast<int64_t>(out.cuts.size()) + 1);
    cut.cane_id = model.canes[i].id;
    cut.point = line.PointAt(planned[i]->s);
    cut.direction = line.TangentAt(planned[i]->s);
    cut.diameter_m = 2.0 * line.RadiusAt(planned[i]->s);
    cut.reason = planned[i]->reason;
    out.cuts.push_back(cut);
  }
  return out;
}

}  // namespace vb::decide
