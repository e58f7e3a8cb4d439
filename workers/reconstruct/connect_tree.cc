// SPDX-License-Identifier: Apache-2.0
// Connection, steps 3-6 (connect.h, BuildTree): parents chosen as a maximum spanning
// arborescence, canes kept near the vine, neighbours' leaves dropped, continuations merged,
// bases bridged to their parents.
#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/arborescence.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/connect_internal.h"

namespace vb::reconstruct {

using connect_internal::Reverse;
using connect_internal::EndOutward;
using connect_internal::DistanceToHead;
using connect_internal::WhollyWithin;

namespace {

// Marks kept (1) every left-out cane (0) whose chosen parent is kept, until none changes: the
// canes that hung on a cane now hung on the tree come with it. Returns how many.
int FollowParents(const std::vector<int>& parent, std::vector<int>* kept) {
  int count = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 0; i < parent.size(); ++i) {
      if ((*kept)[i] != 0 || parent[i] < 0 || (*kept)[parent[i]] != 1) continue;
      (*kept)[i] = 1;
      ++count;
      changed = true;
    }
  }
  return count;
}

// The likeliest join whose child is left out (kept 0) and whose parent is in the tree (kept 1,
// or the trunk or head), among those `admit(k, join)` accepts; -1 if there is none.
template <typename Admit>
int LikeliestJoinToTree(const std::vector<JoinCandidate>& joins,
                        const std::vector<double>& probability, const std::vector<int>& kept,
                        Admit admit) {
  int best = -1;
  for (size_t k = 0; k < joins.size(); ++k) {
    const JoinCandidate& c = joins[k];
    if (kept[c.child] != 0 || (c.parent >= 0 && kept[c.parent] != 1)) continue;
    if (!admit(k, c)) continue;
    if (best < 0 || probability[k] > probability[best]) best = static_cast<int>(k);
  }
  return best;
}

// Keeps the child of joins[best], hung on that join's parent.
void TakeJoin(const std::vector<JoinCandidate>& joins, int best, std::vector<int>* kept,
              std::vector<int>* parent, std::vector<int>* join) {
  const int child = joins[best].child;
  (*kept)[child] = 1;
  (*parent)[child] = joins[best].parent;
  (*join)[child] = best;
}

// Step 3b: while a left-out cane has a candidate join to the tree (a kept cane, the trunk or
// the head) at least rescue_min_probability likely, the likeliest such join of all is taken, and
// the canes that hung on that cane follow it (FollowParents). A cane reaching beyond
// keep_within_m must taper toward the vine's centre by at least rescue_min_taper.
void RescueLeftOut(const std::vector<Polyline3>& canes, double centre_x,
                   const std::vector<JoinCandidate>& joins, const std::vector<double>& probability,
                   const ConnectOptions& options, std::vector<int>* kept, std::vector<int>* parent,
                   std::vector<int>* join, ConnectSummary* sum) {
  // A cane reaching beyond keep_within_m that thickens away from the vine's centre is more
  // likely a neighbour's, entering the view tip first (step 6): it is not rescued.
  std::vector<char> eligible(canes.size(), 1);
  if (options.rescue_min_taper > 0.0 && options.keep_within_m > 0.0) {
    for (size_t i = 0; i < canes.size(); ++i) {
      eligible[i] = WhollyWithin(canes[i], centre_x, options.keep_within_m) ||
                    TaperTowardCentre(canes[i], centre_x) >= options.rescue_min_taper;
    }
  }
  const auto admit = [&](size_t k, const JoinCandidate& c) {
    return eligible[c.child] && probability[k] >= options.rescue_min_probability;
  };
  while (true) {
    const int best = LikeliestJoinToTree(joins, probability, *kept, admit);
    if (best < 0) return;
    TakeJoin(joins, best, kept, parent, join);
    sum->rescued += 1 + FollowParents(*parent, kept);
  }
}

// Which canes step 6 may keep: 1 wholly within keep_within_m of the vine's centre along the
// row; 2 farther, but thinning away from the centre (this vine's), to hang by its thicker end
// only (the one nearer the centre); 0 neither (or shorter than keep_min_length_m, or already
// in the tree).
std::vector<char> KeptNearKinds(const std::vector<Polyline3>& canes, double centre_x,
                                const std::vector<int>& kept, const ConnectOptions& options) {
  std::vector<char> near(canes.size(), 0);
  if (options.keep_within_m <= 0.0) return near;
  for (size_t i = 0; i < canes.size(); ++i) {
    if (kept[i] != 0 || canes[i].Length() < options.keep_min_length_m) continue;
    near[i] = WhollyWithin(canes[i], centre_x, options.keep_within_m);
    if (!near[i] && options.keep_taper_ratio > 0.0 &&
        TaperTowardCentre(canes[i], centre_x) >= options.keep_taper_ratio) {
      near[i] = 2;
    }
  }
  return near;
}

// Step 6: while a left-out cane that `near` marks has a candidate join to the tree (by its
// inner end if marked 2), the likeliest such join of all is taken, however unlikely; the canes
// that hung on it by their chosen joins follow it when rescuing is on.
void KeepNear(const std::vector<Polyline3>& canes, double centre_x, const std::vector<char>& near,
              const std::vector<JoinCandidate>& joins, const std::vector<double>& probability,
              const ConnectOptions& options, std::vector<int>* kept, std::vector<int>* parent,
              std::vector<int>* join, ConnectSummary* sum) {
  auto inner_is_last = [&](int i) {
    return std::abs(canes[i].points.back().x() - centre_x) <
           std::abs(canes[i].points.front().x() - centre_x);
  };
  const auto admit = [&](size_t, const JoinCandidate& c) {
    return near[c.child] == 1 || (near[c.child] == 2 && c.base_is_last == inner_is_last(c.child));
  };
  while (true) {
    const int best = LikeliestJoinToTree(joins, probability, *kept, admit);
    if (best < 0) return;
    TakeJoin(joins, best, kept, parent, join);
    ++sum->kept_near;
    if (options.rescue_min_probability > 0.0) sum->rescued += FollowParents(*parent, kept);
  }
}

// Whether join `c` of a cane to another continues that cane from one of its ends (within
// continuation_gap_m of it, tangents within continuation_angle_deg either way): the same cane
// broken in the images. Looser than step 4, which appends a cane only at its parent's tip and in
// the same direction: this also spares a cane hung at the base of a parallel cane.
bool IsContinuation(const std::vector<Polyline3>& canes, const JoinCandidate& c,
                    const ConnectOptions& options) {
  if (c.parent < 0) return false;
  const Polyline3& parent = canes[c.parent];
  const double length = parent.Length();
  const double s = parent.Project(c.point);
  if (std::min(s, length - s) > options.continuation_gap_m) return false;
  const double cos_max = std::cos(options.continuation_angle_deg * 3.14159265358979323846 / 180);
  return std::abs(EndOutward(canes[c.child], c.base_is_last).dot(parent.TangentAt(s))) >= cos_max;
}

// Step 6c: a cane hung on another cane (not as its continuation) or left out (with
// head_exit_left_out) whose inner end (the one nearer the head's surface) lies within
// head_exit_reach_m of it and points at it (head_exit_min_cos), the straight line to it wood
// enough in the images (head_exit_min_support), thick enough there (head_exit_min_radius_m),
// hangs on the head by that end. Canes leaving the head together in one direction lose their
// inner parts in the thick foreground there, and their outer pieces otherwise hang on a cane they
// pass. Each such join is appended to `joins`.
void HangHeadExits(const std::vector<Polyline3>& canes, const HeadModel& head,
                   const GapSupportFn& gap_support, const ConnectOptions& options,
                   std::vector<JoinCandidate>* joins, std::vector<int>* kept,
                   std::vector<int>* parent, std::vector<int>* join, ConnectSummary* sum) {
  if (options.head_exit_reach_m <= 0.0 || head.spheres.empty()) return;
  for (size_t i = 0; i < canes.size(); ++i) {
    if ((*kept)[i] == 1 && (*parent)[i] < 0) continue;  // on the trunk or head already
    if ((*kept)[i] != 1 && !options.head_exit_left_out) continue;
    const Polyline3& cane = canes[i];
    if ((*kept)[i] == 1 && IsContinuation(canes, (*joins)[(*join)[i]], options)) continue;
    Eigen::Vector3d at_front = Eigen::Vector3d::Zero(), at_back = Eigen::Vector3d::Zero();
    const double d_front = DistanceToHead(cane.points.front(), head, &at_front);
    const double d_back = DistanceToHead(cane.points.back(), head, &at_back);
    const bool last = d_back < d_front;
    const double d = std::min(d_front, d_back);
    if (!(d <= options.head_exit_reach_m)) continue;  // NaN ends too
    const Eigen::Vector3d inner = last ? cane.points.back() : cane.points.front();
    const Eigen::Vector3d at = last ? at_back : at_front;
    if (options.head_exit_min_radius_m > 0.0) {
      const double length = cane.Length(), s = std::min(0.03, length);
      const double radius = last ? connect_internal::MeanRadius(cane, length - s, length)
                                 : connect_internal::MeanRadius(cane, 0.0, s);
      if (!(radius >= options.head_exit_min_radius_m)) continue;  // a fork off a cane
    }
    if (d > 0.0) {
      const Eigen::Vector3d to_head = (at - inner).normalized();
      if (EndOutward(cane, last).dot(to_head) < options.head_exit_min_cos) continue;
      if (options.head_exit_min_support > 0.0 &&
          (!gap_support || gap_support(inner, at) < options.head_exit_min_support)) {
        continue;
      }
    }
    JoinCandidate c;
    c.child = static_cast<int>(i);
    c.base_is_last = last;
    c.parent = -1;
    c.target = JoinTarget::kHead;
    c.point = at;
    c.probability = options.min_join_probability;
    joins->push_back(c);
    const bool was_out = (*kept)[i] != 1;
    (*kept)[i] = 1;
    (*parent)[i] = -1;
    (*join)[i] = static_cast<int>(joins->size()) - 1;
    ++sum->head_exits;
    if (was_out && options.rescue_min_probability > 0.0)
      sum->rescued += FollowParents(*parent, kept);
  }
}

}  // namespace

absl::StatusOr<VineModel> BuildTree(const PreparedCanes& prepared_in,
                                    const std::vector<JoinCandidate>& candidate_joins,
                                    const HeadModel& head, const ConnectOptions& options,
                                    ConnectSummary* summary, const GapSupportFn& gap_support) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  const PreparedCanes* prepared = &prepared_in;
  ConnectSummary local;
  ConnectSummary& sum = summary ? *summary : local;
  sum = ConnectSummary();
  VineModel model;
  model.head = head;
  if (!prepared->trunk) return model;
  sum.inside_trunk_or_head = prepared->inside_trunk_or_head;
  // Step 6c appends the joins it makes.
  std::vector<JoinCandidate> joins = candidate_joins;
  const int count = static_cast<int>(prepared->canes.size());
  for (size_t k = 0; k < joins.size(); ++k) {
    const JoinCandidate& c = joins[k];
    if (c.child < 0 || c.child >= count || c.parent < -1 || c.parent >= count ||
        c.parent == c.child || !(c.probability >= 0.0 && c.probability <= 1.0)) {
      return absl::InvalidArgumentError(absl::StrCat("joins[", k, "]: invalid"));
    }
  }
  std::vector<Polyline3> canes = prepared->canes;
  const int n = static_cast<int>(canes.size());
  // A join to a cane the child visibly goes on across is a crossing, not a fork (off by
  // default: crossing_factor 1).
  std::vector<double> probability(joins.size());
  for (size_t k = 0; k < joins.size(); ++k) {
    const JoinCandidate& c = joins[k];
    probability[k] = c.probability;
    if (options.crossing_factor >= 1.0 || c.parent < 0 || !gap_support) continue;
    const CrossingEvidence e = MeasureCrossing(canes[c.child], c.base_is_last, canes[c.parent],
                                               c.point, options, gap_support);
    if (e.past_support >= options.crossing_min_support &&
        e.miss_m >= options.crossing_min_miss_m) {
      // Ranked below the other joins, but not below "no parent" if it was above: a cane whose
      // only likely join is a crossing keeps it (its true parent is then mostly not among the
      // candidates, and left out its length would be lost to recall).
      probability[k] = std::max(c.probability * options.crossing_factor,
                                std::min(c.probability, 1.001 * options.min_join_probability));
    }
  }

  // Node 0 is the trunk and head; cane i is node i + 1. Arcs 0 .. n-1 are "no parent" (from the
  // root, marked as such); then one arc per candidate join.
  std::vector<Arc> arcs;
  const double none = std::log(options.min_join_probability);
  for (int i = 0; i < n; ++i) arcs.push_back({0, i + 1, none});
  for (size_t k = 0; k < joins.size(); ++k) {
    arcs.push_back({joins[k].parent + 1, joins[k].child + 1,
                    std::log(std::max(probability[k], 1e-12))});
  }
  const std::vector<int> chosen = MaxArborescence(n + 1, 0, arcs);
  // parent[i]: -1 trunk/head, -2 none, else a cane; join[i]: the chosen candidate.
  std::vector<int> parent(n, -2), join(n, -1);
  for (int i = 0; i < n; ++i) {
    const int k = chosen[i + 1];
    if (k < n) continue;
    join[i] = k - n;
    parent[i] = joins[join[i]].parent;
  }
  // Kept: every join up to the root is a real one.
  std::vector<int> kept(n, -1);  // -1 unknown, 0 no, 1 yes
  for (int i = 0; i < n; ++i) {
    std::vector<int> path;
    int at = i;
    while (at >= 0 && kept[at] < 0 && parent[at] != -2) {
      path.push_back(at);
      at = parent[at];
      if (path.size() > static_cast<size_t>(n)) break;  // cannot happen in an arborescence
    }
    const int verdict = at == -1 ? 1 : (at >= 0 && kept[at] >= 0 ? kept[at] : 0);
    if (at >= 0 && kept[at] < 0) kept[at] = 0;
    for (int x : path) kept[x] = verdict;
  }
  // The arborescence scores a join to a left-out cane as if that cane were in the tree: a cane
  // may take a likely join to a cane left out over a less likely, still better-than-none one to
  // the tree, and be lost with it. Hang such canes on the tree after all (step 3b). Canes left
  // out but lying wholly near the vine's centre along the row are this vine's (a neighbour's
  // canes reach into the view from the sides): hang each on its likeliest join to the tree
  // (step 6). Each step can bring into the tree a cane that the other's candidates hang on:
  // with repeat_rescue (off by default) both are repeated until neither keeps another cane.
  const double centre_x = prepared->trunk->points.back().x();
  const std::vector<char> near = KeptNearKinds(canes, centre_x, kept, options);
  for (int round = 0; round < n + 1; ++round) {
    const int before = static_cast<int>(std::count(kept.begin(), kept.end(), 1));
    if (options.rescue_min_probability > 0.0)
      RescueLeftOut(canes, centre_x, joins, probability, options, &kept, &parent, &join, &sum);
    if (options.keep_within_m > 0.0)
      KeepNear(canes, centre_x, near, joins, probability, options, &kept, &parent, &join, &sum);
    if (!options.repeat_rescue ||
        static_cast<int>(std::count(kept.begin(), kept.end(), 1)) == before) {
      break;
    }
  }
  HangHeadExits(canes, head, gap_support, options, &joins, &kept, &parent, &join, &sum);
  // A leaf of the tree that reaches beyond keep_within_m and thickens away from the centre is a
  // neighbour's cane hung on this vine's (by its tip, near a cane it crosses): drop it.
  if (options.drop_thickening_ratio > 0.0 && options.keep_within_m > 0.0) {
    std::vector<char> has_child(n, 0);
    for (int i = 0; i < n; ++i)
      if (kept[i] == 1 && parent[i] >= 0) has_child[parent[i]] = 1;
    for (int i = 0; i < n; ++i) {
      if (kept[i] != 1 || has_child[i]) continue;
      const bool far = !WhollyWithin(canes[i], centre_x, options.keep_within_m);
      if (far && TaperTowardCentre(canes[i], centre_x) * options.drop_thickening_ratio < 1.0) {
        kept[i] = 0;
        ++sum.dropped_thickening;
      }
    }
  }
  // Orient every kept cane base first, and give it a first point on its parent.
  for (int i = 0; i < n; ++i) {
    if (kept[i] != 1) continue;
    const JoinCandidate& c = joins[join[i]];
    if (c.base_is_last) Reverse(&canes[i]);
  }
  std::vector<std::vector<int>> children(n + 1);
  for (int i = 0; i < n; ++i)
    if (kept[i] == 1) children[parent[i] + 1].push_back(i);

  // Continuations: a child that leaves its parent's tip along the parent's direction is the
  // same cane, broken in the images; append it (best join first), and hand its children over.
  std::vector<char> merged(n, 0);
  if (options.merge_continuations) {
    const double cos_max = std::cos(options.continuation_angle_deg * 3.14159265358979323846 / 180);
    for (int j = 0; j < n; ++j) {
      if (kept[j] != 1 || merged[j]) continue;
      while (true) {
        const Polyline3& line = canes[j];
        const double length = line.Length();
        const Eigen::Vector3d out = EndOutward(line, true);
        int best = -1;
        for (int c : children[j + 1]) {
          const JoinCandidate& jc = joins[join[c]];
          if (length - line.Project(jc.point) > options.continuation_gap_m) continue;
          if (-EndOutward(canes[c], false).dot(out) < cos_max) continue;
          if (best < 0 || jc.probability > joins[join[best]].probability) best = c;
        }
        if (best < 0) break;
        Polyline3& tail = canes[best];
        size_t first = 0;
        while (first + 1 < tail.points.size() &&
               (tail.points[first] - line.points.back()).dot(out) <= 0.0) {
          ++first;  // points of the tail that fold back over the parent's tip
        }
        canes[j].points.insert(canes[j].points.end(), tail.points.begin() + first,
                               tail.points.end());
        canes[j].radii.insert(canes[j].radii.end(), tail.radii.begin() + first, tail.radii.end());
        merged[best] = 1;
        std::erase(children[j + 1], best);
        for (int g : children[best + 1]) {
          parent[g] = j;
          children[j + 1].push_back(g);
        }
        children[best + 1].clear();
      }
    }
  }

  // Emit parents first (breadth first from the root).
  std::vector<Polyline3> tree = {*prepared->trunk};
  std::vector<int> parent_of = {-1};
  std::vector<int> index_of(n, -1);
  std::vector<int> queue = children[0];
  for (size_t q = 0; q < queue.size(); ++q) {
    const int i = queue[q];
    Polyline3 cane = canes[i];
    const Eigen::Vector3d at = joins[join[i]].point;
    const double gap = (cane.points.front() - at).norm();
    // A wider gap is drawn only where the images show wood all along it: the base was there
    // but not matched across the views.
    if (gap > 1e-4 && (gap <= options.max_bridge_m ||
                       (gap_support && gap_support(cane.points.front(), at) >=
                                           options.min_gap_support))) {
      cane.points.insert(cane.points.begin(), at);
      cane.radii.insert(cane.radii.begin(), cane.radii.front());
    }
    index_of[i] = static_cast<int>(tree.size());
    tree.push_back(std::move(cane));
    parent_of.push_back(parent[i] < 0 ? 0 : index_of[parent[i]]);
    for (int c : children[i + 1]) queue.push_back(c);
  }

  for (size_t i = 0; i < tree.size(); ++i) {
    Cane cane;
    cane.id = CaneId(static_cast<int>(i) + 1);
    cane.polyline = tree[i];
    if (i == 0) {
      cane.kind = CaneKind::kTrunk;
    } else {
      cane.parent_id = CaneId(parent_of[i] + 1);
      cane.kind = parent_of[i] == 0 && tree[i].Length() < options.spur_length_m ? CaneKind::kSpur
                                                                                : CaneKind::kCane;
    }
    model.canes.push_back(std::move(cane));
  }
  sum.attached = static_cast<int>(tree.size()) - 1;
  sum.unattached = static_cast<int>(std::count(kept.begin(), kept.end(), 0));
  return model;
}

}  // namespace vb::reconstruct
