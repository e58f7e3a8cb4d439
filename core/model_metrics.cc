// SPDX-License-Identifier: Apache-2.0
#include "core/model_metrics.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb {
namespace {

// A segment of some polyline, with the index of the structure it belongs to.
struct IndexedSegment {
  Eigen::Vector3d a;
  Eigen::Vector3d b;
  int owner;
};

// Uniform grid over segments for "nearest segment within r" queries. Each segment is entered in
// every cell its bounding box (grown by r) touches, so one cell lookup answers a query.
class SegmentGrid {
 public:
  SegmentGrid(std::vector<IndexedSegment> segments, double r)
      : segments_(std::move(segments)), r_(r), cell_(std::max(4.0 * r, 0.02)) {
    for (size_t i = 0; i < segments_.size(); ++i) {
      const Eigen::Vector3d lo = segments_[i].a.cwiseMin(segments_[i].b).array() - r_;
      const Eigen::Vector3d hi = segments_[i].a.cwiseMax(segments_[i].b).array() + r_;
      const Eigen::Vector3i c0 = Cell(lo);
      const Eigen::Vector3i c1 = Cell(hi);
      for (int x = c0.x(); x <= c1.x(); ++x)
        for (int y = c0.y(); y <= c1.y(); ++y)
          for (int z = c0.z(); z <= c1.z(); ++z) cells_[Key({x, y, z})].push_back(i);
    }
  }

  // Owner of the nearest segment within r of p, or -1.
  int Nearest(const Eigen::Vector3d& p) const {
    const auto it = cells_.find(Key(Cell(p)));
    if (it == cells_.end()) return -1;
    int best = -1;
    double best_d = r_;
    for (size_t i : it->second) {
      const double d = PointSegmentDistance(p, segments_[i].a, segments_[i].b);
      if (d <= best_d) {
        best_d = d;
        best = segments_[i].owner;
      }
    }
    return best;
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const {
    return (p / cell_).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (static_cast<int64_t>(c.x() & 0x1FFFFF) << 42) |
           (static_cast<int64_t>(c.y() & 0x1FFFFF) << 21) | static_cast<int64_t>(c.z() & 0x1FFFFF);
  }

  std::vector<IndexedSegment> segments_;
  double r_;
  double cell_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

void AddPolyline(const std::vector<Eigen::Vector3d>& points, int owner,
                 std::vector<IndexedSegment>* out) {
  for (size_t i = 0; i + 1 < points.size(); ++i) out->push_back({points[i], points[i + 1], owner});
}

// Samples every `step` along the polyline, with the length each sample stands for.
void SampleWithWeights(const std::vector<Eigen::Vector3d>& points, double step,
                       std::vector<Eigen::Vector3d>* samples, std::vector<double>* weights) {
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const double length = (points[i + 1] - points[i]).norm();
    if (length <= 0) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
    for (int k = 0; k < n; ++k) {
      samples->push_back(points[i] + (points[i + 1] - points[i]) * ((k + 0.5) / n));
      weights->push_back(length / n);
    }
  }
}

std::vector<Eigen::Vector3d> ClipToSpan(const std::vector<Eigen::Vector3d>& points,
                                        double half_span, double step) {
  std::vector<Eigen::Vector3d> samples;
  std::vector<double> weights;
  SampleWithWeights(points, step, &samples, &weights);
  std::vector<Eigen::Vector3d> kept;
  for (const Eigen::Vector3d& p : samples)
    if (std::abs(p.x()) <= half_span) kept.push_back(p);
  return kept;
}

// Marks the cells of a grid (spacing h, origin lo, n cells a side) whose centres lie inside any
// of `spheres`.
std::vector<uint8_t> Rasterise(const std::vector<Sphere>& spheres, const Eigen::Vector3d& lo,
                               const Eigen::Vector3i& n, double h) {
  std::vector<uint8_t> inside(static_cast<size_t>(n.prod()), 0);
  for (const Sphere& s : spheres) {
    const Eigen::Vector3i a =
        ((s.center.array() - s.radius - lo.array()) / h - 0.5).floor().cast<int>().max(0);
    const Eigen::Vector3i b = ((s.center.array() + s.radius - lo.array()) / h - 0.5)
                                  .ceil()
                                  .cast<int>()
                                  .min(n.array() - 1);
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) {
          const Eigen::Vector3d p = lo + (Eigen::Vector3d(x, y, z).array() + 0.5).matrix() * h;
          if ((p - s.center).squaredNorm() <= s.radius * s.radius)
            inside[(static_cast<size_t>(z) * n.y() + y) * n.x() + x] = 1;
        }
  }
  return inside;
}

// Volume of the union of `spheres` (grid integral) and the part of it inside `other`.
std::pair<double, double> UnionVolume(const std::vector<Sphere>& spheres,
                                      const std::vector<Sphere>& other, double h) {
  if (spheres.empty()) return {0.0, 0.0};
  Eigen::Vector3d lo = spheres[0].center, hi = spheres[0].center;
  for (const Sphere& s : spheres) {
    lo = lo.cwiseMin((s.center.array() - s.radius).matrix());
    hi = hi.cwiseMax((s.center.array() + s.radius).matrix());
  }
  // At most ~200 cells along the longest side, so a huge (wrong) model head stays cheap.
  h = std::max(h, (hi - lo).maxCoeff() / 200.0);
  const Eigen::Vector3i n = ((hi - lo) / h).array().ceil().cast<int>().max(1);
  const std::vector<uint8_t> in_self = Rasterise(spheres, lo, n, h);
  const std::vector<uint8_t> in_other = Rasterise(other, lo, n, h);
  size_t total = 0, inside = 0;
  for (size_t i = 0; i < in_self.size(); ++i) {
    total += in_self[i];
    inside += in_self[i] & in_other[i];
  }
  const double cell = h * h * h;
  return {total * cell, inside * cell};
}

}  // namespace

double SphereUnionVolume(const std::vector<Sphere>& spheres, double grid_m) {
  return UnionVolume(spheres, {}, grid_m).first;
}

absl::StatusOr<ReconstructionMetrics> EvaluateReconstruction(const VineModel& model,
                                                             const VineModel& truth,
                                                             const MetricsOptions& options) {
  for (const auto& [v, field] : {std::pair{options.sample_step_m, "sample_step_m"},
                                 {options.match_distance_m, "match_distance_m"},
                                 {options.wire_half_span_m, "wire_half_span_m"},
                                 {options.head_grid_m, "head_grid_m"},
                                 {options.near_head_m, "near_head_m"}}) {
    if (!std::isfinite(v) || v <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("metrics options: ", field, " must be positive and finite, is ", v));
    }
  }
  if (absl::Status s = model.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("model: ", std::string(s.message())));
  if (absl::Status s = truth.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("truth: ", std::string(s.message())));

  const double r = options.match_distance_m;
  ReconstructionMetrics m;

  std::vector<IndexedSegment> model_segments, truth_segments;
  for (size_t i = 0; i < model.canes.size(); ++i)
    AddPolyline(model.canes[i].polyline.points, static_cast<int>(i), &model_segments);
  for (size_t i = 0; i < truth.canes.size(); ++i)
    AddPolyline(truth.canes[i].polyline.points, static_cast<int>(i), &truth_segments);
  const SegmentGrid model_grid(std::move(model_segments), r);
  const SegmentGrid truth_grid(std::move(truth_segments), r);

  // The true cane each model cane mostly reconstructs (-1 if none), and its length.
  std::vector<int> majority(model.canes.size(), -1);
  double precise = 0.0;
  for (size_t i = 0; i < model.canes.size(); ++i) {
    ++m.model_canes;
    std::vector<Eigen::Vector3d> samples;
    std::vector<double> weights;
    SampleWithWeights(model.canes[i].polyline.points, options.sample_step_m, &samples, &weights);
    std::unordered_map<int, double> votes;
    for (size_t k = 0; k < samples.size(); ++k) {
      m.model_cane_length_m += weights[k];
      const int owner = truth_grid.Nearest(samples[k]);
      if (owner < 0) continue;
      precise += weights[k];
      votes[owner] += weights[k];
    }
    double best = 0.0;
    for (const auto& [owner, length] : votes)
      if (length > best || (length == best && owner < majority[i])) {
        best = length;
        majority[i] = owner;
      }
  }
  m.cane_precision = m.model_cane_length_m > 0 ? precise / m.model_cane_length_m : 1.0;

  // For true cane g: is model cane i's route to the trunk made of reconstructions of g's
  // ancestors (g excluded: a cane is not its own parent, but a broken cane may hang on its own
  // base piece, so g itself is allowed)? `strict` also asks that the true cane the model cane
  // hung directly on the trunk stands for (g for i itself) be the trunk or grow from it.
  struct Route {
    bool connected = false;
    bool strict = false;
  };
  auto grows_from_trunk = [&](size_t t) {
    if (truth.canes[t].kind == CaneKind::kTrunk) return true;
    if (!truth.canes[t].parent_id) return false;
    const auto parent = truth.IndexOf(*truth.canes[t].parent_id);
    return parent && truth.canes[*parent].kind == CaneKind::kTrunk;
  };
  auto route_of = [&](size_t i, size_t g) -> Route {
    std::vector<int> ancestry = {static_cast<int>(g)};
    for (size_t at = g, hops = 0; truth.canes[at].parent_id && hops <= truth.canes.size(); ++hops) {
      const auto parent = truth.IndexOf(*truth.canes[at].parent_id);
      if (!parent) break;
      ancestry.push_back(static_cast<int>(*parent));
      at = *parent;
    }
    size_t at = i;
    for (size_t hops = 0; hops <= model.canes.size(); ++hops) {
      const Cane& c = model.canes[at];
      if (!c.parent_id) {
        const bool ok = c.kind == CaneKind::kTrunk &&
                        (at == i || std::find(ancestry.begin(), ancestry.end(), majority[at]) !=
                                        ancestry.end());
        return {ok, ok};
      }
      const auto parent = model.IndexOf(*c.parent_id);
      if (!parent) return {};
      const size_t below = at;
      at = *parent;
      // The trunk is the root by definition; its own accuracy is scored by recall.
      if (model.canes[at].kind == CaneKind::kTrunk) {
        return {true, grows_from_trunk(below == i ? g : static_cast<size_t>(majority[below]))};
      }
      if (std::find(ancestry.begin(), ancestry.end(), majority[at]) == ancestry.end()) return {};
    }
    return {};
  };

  // Whether a true sample lies within near_head_m of the true head's surface.
  auto near_head = [&](const Eigen::Vector3d& p) {
    for (const Sphere& s : truth.head.spheres)
      if ((p - s.center).norm() - s.radius <= options.near_head_m) return true;
    return false;
  };
  double recalled = 0.0, connected_length = 0.0, strict_length = 0.0, near_length = 0.0,
         near_recalled = 0.0;
  for (size_t g = 0; g < truth.canes.size(); ++g) {
    const Cane& cane = truth.canes[g];
    if (cane.kind == CaneKind::kSpur) continue;
    ++m.truth_canes;
    std::vector<Eigen::Vector3d> samples;
    std::vector<double> weights;
    SampleWithWeights(cane.polyline.points, options.sample_step_m, &samples, &weights);
    std::unordered_map<int, Route> route_cache;
    for (size_t k = 0; k < samples.size(); ++k) {
      m.truth_cane_length_m += weights[k];
      const bool near = near_head(samples[k]);
      near_length += near ? weights[k] : 0.0;
      const int owner = model_grid.Nearest(samples[k]);
      if (owner < 0) continue;
      recalled += weights[k];
      near_recalled += near ? weights[k] : 0.0;
      auto it = route_cache.find(owner);
      if (it == route_cache.end())
        it = route_cache.emplace(owner, route_of(static_cast<size_t>(owner), g)).first;
      if (it->second.connected) connected_length += weights[k];
      if (it->second.strict) strict_length += weights[k];
    }
  }
  m.cane_recall = m.truth_cane_length_m > 0 ? recalled / m.truth_cane_length_m : 1.0;
  m.connectivity = m.truth_cane_length_m > 0 ? connected_length / m.truth_cane_length_m : 1.0;
  m.connectivity_strict =
      m.truth_cane_length_m > 0 ? strict_length / m.truth_cane_length_m : 1.0;
  m.cane_recall_near_head = near_length > 0 ? near_recalled / near_length : 1.0;
  m.near_head_length_fraction =
      m.truth_cane_length_m > 0 ? near_length / m.truth_cane_length_m : 0.0;

  // Wires: recall and precision over the visible stretch.
  std::vector<IndexedSegment> model_wires, truth_wires;
  for (size_t i = 0; i < model.wires.size(); ++i)
    AddPolyline(model.wires[i].points, static_cast<int>(i), &model_wires);
  for (size_t i = 0; i < truth.wires.size(); ++i)
    AddPolyline(truth.wires[i].points, static_cast<int>(i), &truth_wires);
  const SegmentGrid model_wire_grid(std::move(model_wires), r);
  const SegmentGrid truth_wire_grid(std::move(truth_wires), r);
  size_t wire_total = 0, wire_hit = 0, model_wire_total = 0, model_wire_hit = 0;
  for (const Wire& w : truth.wires)
    for (const Eigen::Vector3d& p : ClipToSpan(w.points, options.wire_half_span_m, options.sample_step_m)) {
      ++wire_total;
      if (model_wire_grid.Nearest(p) >= 0) ++wire_hit;
    }
  for (const Wire& w : model.wires)
    for (const Eigen::Vector3d& p : ClipToSpan(w.points, options.wire_half_span_m, options.sample_step_m)) {
      ++model_wire_total;
      if (truth_wire_grid.Nearest(p) >= 0) ++model_wire_hit;
    }
  m.wire_recall = wire_total > 0 ? static_cast<double>(wire_hit) / wire_total : 1.0;
  m.wire_precision =
      model_wire_total > 0 ? static_cast<double>(model_wire_hit) / model_wire_total : 1.0;

  const auto [true_volume, enclosed] =
      UnionVolume(truth.head.spheres, model.head.spheres, options.head_grid_m);
  m.head_enclosed_fraction = true_volume > 0 ? enclosed / true_volume : 1.0;
  if (true_volume > 0) {
    const double model_volume =
        UnionVolume(model.head.spheres, {}, options.head_grid_m).first;
    m.head_volume_ratio = model_volume / true_volume;
  }
  return m;
}

nlohmann::json MetricsToJson(const ReconstructionMetrics& m) {
  return nlohmann::json{{"cane_recall", m.cane_recall},
                        {"cane_precision", m.cane_precision},
                        {"connectivity", m.connectivity},
                        {"connectivity_strict", m.connectivity_strict},
                        {"cane_recall_near_head", m.cane_recall_near_head},
                        {"near_head_length_fraction", m.near_head_length_fraction},
                        {"wire_recall", m.wire_recall},
                        {"wire_precision", m.wire_precision},
                        {"head_enclosed_fraction", m.head_enclosed_fraction},
                        {"head_volume_ratio", m.head_volume_ratio},
                        {"truth_cane_length_m", m.truth_cane_length_m},
                        {"model_cane_length_m", m.model_cane_length_m},
                        {"truth_canes", m.truth_canes},
                        {"model_canes", m.model_canes}};
}

}  // namespace vb
