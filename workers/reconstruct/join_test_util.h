// SPDX-License-Identifier: Apache-2.0
// Test support for connection: labelling candidate joins (connect.h) against the true vine, for
// training the join classifier and for diagnosis. Header-only; tests and training only.
#pragma once

#include <algorithm>
#include <vector>

#include "core/vine_model.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/match_classifier.h"

namespace vb::reconstruct {

// The true cane (index into truth.canes) most of `line` lies within 1 cm of, if at least half
// of it does; -1 otherwise (a ghost or a neighbour's cane).
inline int MajorityCane(const Polyline3& line, const VineModel& truth) {
  const std::vector<Eigen::Vector3d> samples = line.Sample(0.005);
  std::vector<int> votes(truth.canes.size(), 0);
  for (const Eigen::Vector3d& p : samples) {
    int best = -1;
    double best_d = 0.01;
    for (size_t g = 0; g < truth.canes.size(); ++g) {
      const double d = DistanceToPolyline(p, truth.canes[g].polyline);
      if (d <= best_d) best_d = d, best = static_cast<int>(g);
    }
    if (best >= 0) ++votes[best];
  }
  const auto it = std::max_element(votes.begin(), votes.end());
  if (it == votes.end() || 2 * *it < static_cast<int>(samples.size())) return -1;
  return static_cast<int>(it - votes.begin());
}

inline int TrueParent(const VineModel& truth, int g) {
  const auto& id = truth.canes[g].parent_id;
  return id ? static_cast<int>(*truth.IndexOf(*id)) : -1;
}

// Right iff the child's base is the end nearer its true cane's base and the target is where it
// grows from: the true parent (the trunk or head for canes growing from them), or an earlier
// piece of the same true cane. A piece whose base part was not reconstructed may hang on the true
// parent across the gap: that is where it grows from. `kBaseReach` (diagnosis) can require the
// child's base to lie this near (arc length) its true base for joins to the parent.
inline double kBaseReach = 1e9;
inline std::vector<LabelledJoin> LabelJoins(const PreparedCanes& prepared,
                                     const std::vector<JoinCandidate>& joins,
                                     const VineModel& truth) {
  std::vector<int> majority;
  for (const Polyline3& c : prepared.canes) majority.push_back(MajorityCane(c, truth));
  std::vector<LabelledJoin> out;
  for (const JoinCandidate& j : joins) {
    LabelledJoin e{j.features, false};
    const int g = majority[j.child];
    if (g >= 0) {
      const Polyline3& true_cane = truth.canes[g].polyline;
      const Polyline3& child = prepared.canes[j.child];
      const double s_first = true_cane.Project(child.points.front());
      const double s_last = true_cane.Project(child.points.back());
      const double s_base = j.base_is_last ? s_last : s_first;
      const double s_tip = j.base_is_last ? s_first : s_last;
      const bool base_right = g == 0 || s_base <= s_tip;
      const int true_parent = TrueParent(truth, g);
      if (base_right) {
        if (j.parent < 0) {
          e.right = g == 0 || (true_parent == 0 && s_base < kBaseReach);
        } else {
          const int h = majority[j.parent];
          e.right = (h == true_parent && h >= 0 && s_base < kBaseReach) ||
                    (h == g && true_cane.Project(j.point) <= s_base + 0.02);
        }
      }
    }
    out.push_back(e);
  }
  return out;
}

}  // namespace vb::reconstruct
