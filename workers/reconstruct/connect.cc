// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/connect.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Distance from p to the polyline's axis and the closest point on it.
double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& line, Eigen::Vector3d* at) {
  double best = kInf;
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    double t = 0.0;
    const double d = PointSegmentDistance(p, line.points[i], line.points[i + 1], &t);
    if (d < best) {
      best = d;
      if (at) *at = line.points[i] + t * (line.points[i + 1] - line.points[i]);
    }
  }
  return best;
}

// Signed distance from p to the surface of the union of spheres (negative inside), and the
// nearest surface point of the sphere that gives it.
double DistanceToHead(const Eigen::Vector3d& p, const HeadModel& head, Eigen::Vector3d* at) {
  double best = kInf;
  for (const Sphere& s : head.spheres) {
    const Eigen::Vector3d d = p - s.center;
    const double n = d.norm();
    const double signed_distance = n - s.radius;
    if (signed_distance < best) {
      best = signed_distance;
      if (at) *at = n > 1e-12 ? Eigen::Vector3d(s.center + d * (s.radius / n)) : p;
    }
  }
  return best;
}

void Reverse(Polyline3* line) {
  std::reverse(line->points.begin(), line->points.end());
  std::reverse(line->radii.begin(), line->radii.end());
}

// An arc of the join graph: node 0 is the trunk and head, node i + 1 the prepared cane i.
struct Arc {
  int from = 0;
  int to = 0;
  double weight = 0.0;
};

// Maximum-weight spanning arborescence rooted at `root` over nodes [0, n) (Chu and Liu 1965;
// Edmonds 1967), contracting one cycle per level. Every node but the root must have an incoming
// arc. Returns per node the index of its chosen incoming arc (-1 for the root).
std::vector<int> MaxArborescence(int n, int root, const std::vector<Arc>& arcs) {
  std::vector<int> in(n, -1);
  for (size_t k = 0; k < arcs.size(); ++k) {
    const Arc& a = arcs[k];
    if (a.to == root || a.from == a.to) continue;
    if (in[a.to] < 0 || a.weight > arcs[in[a.to]].weight) in[a.to] = static_cast<int>(k);
  }
  std::vector<int> seen(n, -1), cycle;
  for (int v = 0; v < n && cycle.empty(); ++v) {
    int u = v;
    while (u != root && seen[u] < 0 && in[u] >= 0) {
      seen[u] = v;
      u = arcs[in[u]].from;
    }
    if (u != root && seen[u] == v && in[u] >= 0) {
      int x = u;
      do {
        cycle.push_back(x);
        x = arcs[in[x]].from;
      } while (x != u);
    }
  }
  if (cycle.empty()) return in;
  // Contract the cycle into one node; arcs entering it are charged the cycle arc they replace.
  std::vector<char> on_cycle(n, 0);
  for (int x : cycle) on_cycle[x] = 1;
  std::vector<int> label(n, -1);
  int m = 0;
  for (int v = 0; v < n; ++v)
    if (!on_cycle[v]) label[v] = m++;
  const int contracted = m++;
  for (int x : cycle) label[x] = contracted;
  std::vector<Arc> sub;
  std::vector<int> origin;
  for (size_t k = 0; k < arcs.size(); ++k) {
    const Arc& a = arcs[k];
    const int u = label[a.from], v = label[a.to];
    if (u == v) continue;
    const double w = on_cycle[a.to] ? a.weight - arcs[in[a.to]].weight : a.weight;
    sub.push_back({u, v, w});
    origin.push_back(static_cast<int>(k));
  }
  const std::vector<int> sub_in = MaxArborescence(m, label[root], sub);
  std::vector<int> chosen(n, -1);
  for (int v = 0; v < m; ++v) {
    if (sub_in[v] < 0) continue;
    const int k = origin[sub_in[v]];
    chosen[arcs[k].to] = k;
  }
  for (int x : cycle)
    if (chosen[x] < 0) chosen[x] = in[x];
  return chosen;
}

// Unit tangent pointing out of the polyline at its first or last point, over ~3 cm.
Eigen::Vector3d EndOutward(const Polyline3& line, bool last) {
  const double length = line.Length();
  const double s = std::min(0.03, length);
  const Eigen::Vector3d end = last ? line.points.back() : line.points.front();
  const Eigen::Vector3d d = end - line.PointAt(last ? length - s : s);
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitZ();
}

// Mean radius over arc lengths [from, to] of the polyline, at evenly spaced samples about
// 5 mm apart (the same samples read from either end).
double MeanRadius(const Polyline3& line, double from, double to) {
  const int n = std::max(2, static_cast<int>(std::ceil((to - from) / 0.005)) + 1);
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += line.RadiusAt(from + (to - from) * k / (n - 1));
  return sum / n;
}

// Whether every point of the cane lies within `within_m` of the vine's centre along the row:
// what keeping near the vine takes as this vine's, and what dropping a far leaf does not.
bool WhollyWithin(const Polyline3& cane, double centre_x, double within_m) {
  return std::all_of(cane.points.begin(), cane.points.end(), [&](const Eigen::Vector3d& p) {
    return std::abs(p.x() - centre_x) <= within_m;
  });
}

}  // namespace

double TaperTowardCentre(const Polyline3& cane, double centre_x) {
  const double length = cane.Length();
  if (!(length >= 0.03)) return 1.0;
  const double third = length / 3.0;
  const double front = MeanRadius(cane, 0.0, third);
  const double back = MeanRadius(cane, length - third, length);
  const bool front_inner = std::abs(cane.points.front().x() - centre_x) <
                           std::abs(cane.points.back().x() - centre_x);
  const double inner = front_inner ? front : back, outer = front_inner ? back : front;
  return outer > 0.0 ? inner / outer : 1.0;
}

CrossingEvidence MeasureCrossing(const Polyline3& child, bool base_is_last,
                                 const Polyline3& parent, const Eigen::Vector3d& point,
                                 const ConnectOptions& options, const GapSupportFn& gap_support) {
  CrossingEvidence e;
  if (child.points.size() < 2 || parent.points.size() < 2) return e;
  const Eigen::Vector3d base = base_is_last ? child.points.back() : child.points.front();
  const Eigen::Vector3d out = EndOutward(child, base_is_last);
  // Past the parent along the child's own line, not past the join point: a crossing child
  // passes in front of or behind the parent's axis.
  const double along = std::max(0.0, (point - base).dot(out));
  const double radius = parent.RadiusAt(parent.Project(point));
  e.miss_m = kInf;
  const int steps = 20;
  for (int k = 0; k <= steps; ++k) {
    const double t = (along + radius + options.crossing_clearance_m) * k / steps;
    e.miss_m = std::min(e.miss_m, DistanceToPolyline(base + out * t, parent, nullptr));
  }
  const Eigen::Vector3d from = base + out * (along + radius + options.crossing_clearance_m);
  const Eigen::Vector3d to = from + out * options.crossing_reach_m;
  // A stretch that ends on the parent runs along it (the child continues the parent from its
  // tip): the wood there is the parent's, not the child's going on.
  if (gap_support &&
      DistanceToPolyline(to, parent, nullptr) > radius + options.crossing_clearance_m) {
    e.past_support = gap_support(from, to);
  }
  return e;
}

absl::Status ConnectOptions::Validate() const {
  for (auto [v, name] : {std::pair{max_attach_m, "max_attach_m"}, {sample_step_m, "sample_step_m"},
                         {inside_fraction, "inside_fraction"},
                         {max_bridge_m, "max_bridge_m"},
                         {continuation_gap_m, "continuation_gap_m"},
                         {continuation_angle_deg, "continuation_angle_deg"},
                         {crossing_reach_m, "crossing_reach_m"},
                         {crossing_clearance_m, "crossing_clearance_m"},
                         {crossing_factor, "crossing_factor"}}) {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("connect options: ", name, " must be > 0"));
  }
  if (!std::isfinite(keep_within_m) || keep_within_m < 0) {
    return absl::InvalidArgumentError("connect options: keep_within_m must be >= 0");
  }
  if (!std::isfinite(keep_min_length_m) || keep_min_length_m < 0) {
    return absl::InvalidArgumentError("connect options: keep_min_length_m must be >= 0");
  }
  if (!std::isfinite(keep_taper_ratio) || keep_taper_ratio < 0 ||
      (keep_taper_ratio > 0 && keep_taper_ratio <= 1)) {
    return absl::InvalidArgumentError(
        "connect options: keep_taper_ratio must be 0 (off) or > 1 (a cane of even thickness "
        "would pass any ratio <= 1)");
  }
  if (!std::isfinite(drop_thickening_ratio) || drop_thickening_ratio < 0 ||
      (drop_thickening_ratio > 0 && drop_thickening_ratio <= 1)) {
    return absl::InvalidArgumentError(
        "connect options: drop_thickening_ratio must be 0 (off) or > 1");
  }
  if (!(crossing_factor > 0.0 && crossing_factor <= 1.0)) {
    return absl::InvalidArgumentError("connect options: crossing_factor must be in (0, 1]");
  }
  if (!std::isfinite(crossing_min_miss_m) || crossing_min_miss_m < 0) {
    return absl::InvalidArgumentError("connect options: crossing_min_miss_m must be >= 0");
  }
  if (!(crossing_min_support >= 0.0 && crossing_min_support <= 1.0)) {
    return absl::InvalidArgumentError("connect options: crossing_min_support must be in [0, 1]");
  }
  if (!(min_gap_support >= 0.0 && min_gap_support <= 1.0)) {
    return absl::InvalidArgumentError("connect options: min_gap_support must be in [0, 1]");
  }
  if (!std::isfinite(head_margin_m) || head_margin_m < 0 || !std::isfinite(spur_length_m) ||
      spur_length_m < 0) {
    return absl::InvalidArgumentError(
        "connect options: head_margin_m and spur_length_m must be >= 0");
  }
  if (!(min_join_probability > 0 && min_join_probability < 1)) {
    return absl::InvalidArgumentError("connect options: min_join_probability must be in (0, 1)");
  }
  for (double w : join_weights.cane) {
    if (!std::isfinite(w))
      return absl::InvalidArgumentError("connect options: join_weights must be finite");
  }
  for (double w : join_weights.root) {
    if (!std::isfinite(w))
      return absl::InvalidArgumentError("connect options: join_weights must be finite");
  }
  return absl::OkStatus();
}

absl::StatusOr<PreparedCanes> PrepareCanes(const std::vector<Polyline3>& input,
                                           const std::optional<Polyline3>& trunk_in,
                                           const HeadModel& head, const ConnectOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  for (size_t i = 0; i < input.size(); ++i) {
    if (absl::Status s = input[i].Validate(absl::StrCat("canes[", i, "]")); !s.ok()) return s;
  }
  if (trunk_in) {
    if (absl::Status s = trunk_in->Validate("trunk"); !s.ok()) return s;
  }
  PreparedCanes out;
  std::vector<Polyline3> canes = input;
  std::optional<Polyline3> trunk = trunk_in;
  if (!trunk) {
    // No trunk from the silhouettes: the thick cane reaching lowest stands in for it.
    int best = -1;
    double best_score = kInf;
    for (size_t i = 0; i < canes.size(); ++i) {
      double low = kInf, radius = 0;
      for (size_t k = 0; k < canes[i].points.size(); ++k) {
        low = std::min(low, canes[i].points[k].z());
        radius = std::max(radius, canes[i].radii[k]);
      }
      const double score = low - 10.0 * radius;
      if (score < best_score) {
        best_score = score;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) return out;
    trunk = canes[best];
    canes.erase(canes.begin() + best);
    if (trunk->points.front().z() > trunk->points.back().z()) Reverse(&*trunk);
  }
  const double trunk_radius = *std::max_element(trunk->radii.begin(), trunk->radii.end());

  // Drop canes that mostly lie inside the trunk or head: they are those structures seen again.
  // The longest of them inside the trunk, triangulated from the trunk's centre lines, is a more
  // accurate axis than the silhouettes' slab centres: it becomes the trunk, reaching the ground
  // along the silhouette trunk's base.
  const Polyline3 silhouette_trunk = *trunk;
  double best_trunk_length = options.trunk_axis_min_fraction * silhouette_trunk.Length();
  for (const Polyline3& cane : canes) {
    const std::vector<Eigen::Vector3d> samples = cane.Sample(options.sample_step_m);
    size_t inside = 0;
    for (const Eigen::Vector3d& p : samples) {
      if (DistanceToPolyline(p, *trunk, nullptr) <= trunk_radius + 0.01 ||
          DistanceToHead(p, head, nullptr) <= 0.0) {
        ++inside;
      }
    }
    if (!samples.empty() && inside >= options.inside_fraction * samples.size()) {
      ++out.inside_trunk_or_head;
      size_t in_trunk = 0;
      for (const Eigen::Vector3d& p : samples)
        in_trunk += DistanceToPolyline(p, silhouette_trunk, nullptr) <= trunk_radius + 0.01;
      if (in_trunk >= options.inside_fraction * samples.size() && trunk_in &&
          cane.Length() > best_trunk_length) {
        best_trunk_length = cane.Length();
        Polyline3 axis = cane;
        if (axis.points.front().z() > axis.points.back().z()) Reverse(&axis);
        if (silhouette_trunk.points.front().z() < axis.points.front().z() - 0.02) {
          axis.points.insert(axis.points.begin(), silhouette_trunk.points.front());
          axis.radii.insert(axis.radii.begin(), axis.radii.front());
        }
        axis.radii.assign(axis.points.size(), trunk_radius);
        trunk = axis;
      }
      continue;
    }
    out.canes.push_back(cane);
  }
  out.trunk = trunk;
  return out;
}

std::vector<JoinCandidate> FindJoins(const PreparedCanes& prepared, const HeadModel& head,
                                     const ConnectOptions& options) {
  std::vector<JoinCandidate> joins;
  if (!prepared.trunk) return joins;
  const Polyline3& trunk = *prepared.trunk;
  const std::vector<Polyline3>& canes = prepared.canes;
  const double trunk_radius = *std::max_element(trunk.radii.begin(), trunk.radii.end());
  // The head's centre and surface; a trunk without a head ends in its top point.
  Eigen::Vector3d centre = trunk.points.back();
  if (!head.spheres.empty()) {
    centre.setZero();
    for (const Sphere& s : head.spheres) centre += s.center;
    centre /= static_cast<double>(head.spheres.size());
  }
  auto to_head = [&](const Eigen::Vector3d& p) {
    if (head.spheres.empty()) return std::max(0.0, (p - centre).norm() - trunk_radius);
    return std::max(0.0, DistanceToHead(p, head, nullptr));
  };
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Polyline3& c : canes) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : c.points) box.extend(p);
    box.min().array() -= options.max_attach_m;
    box.max().array() += options.max_attach_m;
    boxes.push_back(box);
  }
  for (size_t i = 0; i < canes.size(); ++i) {
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d& p = end == 0 ? canes[i].points.front() : canes[i].points.back();
      JoinGeometry g;
      g.child = &canes[i];
      g.base_is_last = end == 1;
      g.head_centre = centre;
      g.base_to_head_m = to_head(p);
      auto add = [&](int parent, JoinTarget target, const Eigen::Vector3d& at, double gap) {
        if (gap > options.max_attach_m) return;
        g.target = target;
        g.parent = parent >= 0 ? &canes[parent] : (target == JoinTarget::kTrunk ? &trunk : nullptr);
        g.point = at;
        g.gap_m = std::max(0.0, gap);
        g.point_to_head_m = to_head(at);
        JoinCandidate c;
        c.child = static_cast<int>(i);
        c.base_is_last = end == 1;
        c.parent = parent;
        c.target = target;
        c.point = at;
        c.features = ComputeJoinFeatures(g);
        c.probability = JoinProbability(c.features, options.join_weights);
        joins.push_back(c);
      };
      Eigen::Vector3d at = p;
      const double d_trunk = DistanceToPolyline(p, trunk, &at) - trunk_radius;
      add(-1, JoinTarget::kTrunk, at, d_trunk);
      if (!head.spheres.empty()) {
        const double d_head = DistanceToHead(p, head, &at) - options.head_margin_m;
        add(-1, JoinTarget::kHead, at, d_head);
      }
      for (size_t j = 0; j < canes.size(); ++j) {
        if (j == i || !boxes[j].contains(p)) continue;
        const double d = DistanceToPolyline(p, canes[j], &at);
        add(static_cast<int>(j), JoinTarget::kCane, at, d);
      }
    }
  }
  return joins;
}

absl::StatusOr<VineModel> ConnectCanes(const std::vector<Polyline3>& input,
                                       const std::optional<Polyline3>& trunk_in,
                                       const HeadModel& head, const ConnectOptions& options,
                                       ConnectSummary* summary,
                                       const GapSupportFn& gap_support) {
  absl::StatusOr<PreparedCanes> prepared = PrepareCanes(input, trunk_in, head, options);
  if (!prepared.ok()) return prepared.status();
  return BuildTree(*prepared, FindJoins(*prepared, head, options), head, options, summary,
                   gap_support);
}

absl::StatusOr<VineModel> BuildTree(const PreparedCanes& prepared_in,
                                    const std::vector<JoinCandidate>& joins,
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
  // Canes left out but lying wholly near the vine's centre along the row are this vine's (a
  // neighbour's canes reach into the view from the sides): hang each on its likeliest join to
  // the tree, the likeliest of all first, so that a cane kept so can take others after it.
  if (options.keep_within_m > 0.0) {
    const double centre_x = prepared->trunk->points.back().x();
    // near: 1 wholly near the centre; 2 farther, but thinning away from the centre (this
    // vine's), to hang by its thicker end, the one nearer the centre (`inner_is_last`).
    std::vector<char> near(n, 0), inner_is_last(n, 0);
    for (int i = 0; i < n; ++i) {
      if (kept[i] != 0 || canes[i].Length() < options.keep_min_length_m) continue;
      near[i] = WhollyWithin(canes[i], centre_x, options.keep_within_m);
      if (!near[i] && options.keep_taper_ratio > 0.0 &&
          TaperTowardCentre(canes[i], centre_x) >= options.keep_taper_ratio) {
        near[i] = 2;
        inner_is_last[i] = std::abs(canes[i].points.back().x() - centre_x) <
                           std::abs(canes[i].points.front().x() - centre_x);
      }
    }
    while (true) {
      int best = -1;
      for (size_t k = 0; k < joins.size(); ++k) {
        const JoinCandidate& c = joins[k];
        if (kept[c.child] != 0 || !near[c.child] || (c.parent >= 0 && kept[c.parent] != 1)) {
          continue;
        }
        if (near[c.child] == 2 && c.base_is_last != static_cast<bool>(inner_is_last[c.child])) {
          continue;
        }
        if (best < 0 || probability[k] > probability[best]) best = static_cast<int>(k);
      }
      if (best < 0) break;
      const int child = joins[best].child;
      kept[child] = 1;
      parent[child] = joins[best].parent;
      join[child] = best;
      ++sum.kept_near;
    }
  }
  // A leaf of the tree that reaches beyond keep_within_m and thickens away from the centre is a
  // neighbour's cane hung on this vine's (by its tip, near a cane it crosses): drop it.
  if (options.drop_thickening_ratio > 0.0 && options.keep_within_m > 0.0) {
    const double centre_x = prepared->trunk->points.back().x();
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
