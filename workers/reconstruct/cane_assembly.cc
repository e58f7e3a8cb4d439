// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/cane_assembly.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Node weights never drop below this, so that bridged gaps stay well defined in averages.
constexpr double kMinWeight = 1e-3;

// A cane in the making: nodes roughly `step` apart, each with the summed weight of the samples
// averaged into it.
struct Track {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> radii;
  std::vector<double> weights;
  int pieces = 1;
  bool alive = true;

  size_t size() const { return points.size(); }
  double Evidence(double step) const {
    return step * std::accumulate(weights.begin(), weights.end(), 0.0);
  }
};

std::vector<double> ArcLengths(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> s(points.size(), 0.0);
  for (size_t i = 1; i < points.size(); ++i) s[i] = s[i - 1] + (points[i] - points[i - 1]).norm();
  return s;
}

// Unit tangent at node i from the chord over +-half_span nodes (noise-robust).
Eigen::Vector3d TangentAt(const std::vector<Eigen::Vector3d>& points, size_t i, int half_span) {
  const size_t a = i >= static_cast<size_t>(half_span) ? i - half_span : 0;
  const size_t b = std::min(points.size() - 1, i + half_span);
  const Eigen::Vector3d d = points[b] - points[a];
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitX();
}

Eigen::AlignedBox3d BoxOf(const Track& t, double inflate) {
  Eigen::AlignedBox3d box;
  for (const auto& p : t.points) box.extend(p);
  box.min().array() -= inflate;
  box.max().array() += inflate;
  return box;
}

// How track b runs alongside track a: the contiguous stretch [b_begin, b_end] of b's nodes that
// lie close to a with parallel tangents, and where they project on a (arc length).
struct Overlap {
  bool reversed = false;
  int b_begin = 0;
  int b_end = -1;
  std::vector<double> s_on_a;  // per node of b (meaningful in [b_begin, b_end])
};

class Assembler {
 public:
  explicit Assembler(const AssemblyOptions& options)
      : options_(options),
        half_span_(std::max(1, static_cast<int>(std::lround(0.5 * options.tangent_baseline_m /
                                                            options.step_m)))),
        cos_merge_(std::cos(options.merge_angle_deg * kPi / 180.0)),
        cos_chain_(std::cos(options.max_chain_angle_deg * kPi / 180.0)),
        tan_chain_(std::tan(options.max_chain_angle_deg * kPi / 180.0)),
        cos_long_chain_(std::cos(options.max_long_gap_angle_deg * kPi / 180.0)),
        tan_long_chain_(std::tan(options.max_long_gap_angle_deg * kPi / 180.0)) {}

  // Resamples a piece into a one-piece track; nullopt-like empty track if degenerate.
  Track FromPiece(const Piece3D& piece) const {
    Track t;
    const double length = piece.polyline.Length();
    if (!(length > 1e-6)) return t;
    const int n = std::max(2, static_cast<int>(std::ceil(length / options_.step_m)) + 1);
    const double w = std::max(kMinWeight, piece.probability * piece.support);
    for (int k = 0; k < n; ++k) {
      const double s = length * k / (n - 1);
      t.points.push_back(piece.polyline.PointAt(s));
      t.radii.push_back(piece.polyline.RadiusAt(s));
      t.weights.push_back(w);
    }
    return t;
  }

  // Callers check the tracks' boxes (inflated by merge_distance_m) intersect first.
  std::optional<Overlap> FindOverlap(const Track& a, const Track& b) const {
    const std::vector<double> arc_a = ArcLengths(a.points);
    const std::vector<double> arc_b = ArcLengths(b.points);
    const double length_a = arc_a.back();
    Overlap ov;
    ov.s_on_a.assign(b.size(), 0.0);
    std::vector<char> close(b.size(), 0);
    std::vector<double> orientation(b.size(), 0.0);
    // Samples far outside a's box cannot be close, nor inside a run of close ones.
    const Eigen::AlignedBox3d reach = BoxOf(a, options_.merge_distance_m + 4 * options_.step_m);
    for (size_t j = 0; j < b.size(); ++j) {
      if (!reach.contains(b.points[j])) continue;
      double best = std::numeric_limits<double>::infinity();
      size_t best_k = 0;
      double best_t = 0.0;
      for (size_t k = 0; k + 1 < a.size(); ++k) {
        double t = 0.0;
        const double d = PointSegmentDistance(b.points[j], a.points[k], a.points[k + 1], &t);
        if (d < best) {
          best = d;
          best_k = k;
          best_t = t;
        }
      }
      ov.s_on_a[j] = arc_a[best_k] + best_t * (arc_a[best_k + 1] - arc_a[best_k]);
      if (best > options_.merge_distance_m) continue;
      const size_t node = best_t < 0.5 ? best_k : best_k + 1;
      const double c = TangentAt(a.points, node, half_span_).dot(TangentAt(b.points, j, half_span_));
      if (std::abs(c) < cos_merge_) continue;
      close[j] = 1;
      orientation[j] = c;
    }
    // Longest run (by arc length) of close nodes, bridging up to two outliers.
    int best_begin = 0, best_end = -1, run_begin = -1, last_close = -1;
    for (int j = 0; j < static_cast<int>(b.size()); ++j) {
      if (!close[j]) continue;
      if (run_begin < 0 || j - last_close > 3) run_begin = j;
      last_close = j;
      if (best_end < 0 || arc_b[j] - arc_b[run_begin] > arc_b[best_end] - arc_b[best_begin]) {
        best_begin = run_begin;
        best_end = j;
      }
    }
    if (best_end < 0 || arc_b[best_end] - arc_b[best_begin] < options_.min_overlap_m) {
      return std::nullopt;
    }
    double orient = 0.0;
    for (int j = best_begin; j <= best_end; ++j) orient += orientation[j];
    ov.reversed = orient < 0.0;
    ov.b_begin = best_begin;
    ov.b_end = best_end;
    // b may only leave a where a ends (or where b itself ends): otherwise the two merely touch
    // or cross over a stretch, and are different canes.
    const double tol = options_.end_tolerance_m;
    const double s_first = ov.s_on_a[best_begin];
    const double s_last = ov.s_on_a[best_end];
    const bool b_has_before = arc_b[best_begin] > tol;
    const bool b_has_after = arc_b.back() - arc_b[best_end] > tol;
    const bool near_start_first = s_first <= tol, near_end_first = s_first >= length_a - tol;
    const bool near_start_last = s_last <= tol, near_end_last = s_last >= length_a - tol;
    if (!ov.reversed) {
      if (b_has_before && !near_start_first) return std::nullopt;
      if (b_has_after && !near_end_last) return std::nullopt;
    } else {
      if (b_has_before && !near_end_first) return std::nullopt;
      if (b_has_after && !near_start_last) return std::nullopt;
    }
    return ov;
  }

  // Averages the nodes of b, at arc lengths s_b along a (outside [0, length of a] they extend a),
  // into a's nodes with linear (tent) weights. Keeps a's nodes where they are and adds nodes
  // every step_m beyond a's ends; nodes no sample reaches (a bridged gap) are interpolated.
  void FuseInto(Track* a, const Track& b, const std::vector<double>& s_b) const {
    const double step = options_.step_m;
    std::vector<double> grid = ArcLengths(a->points);
    const double length_a = grid.back();
    const double s_min = *std::min_element(s_b.begin(), s_b.end());
    const double s_max = *std::max_element(s_b.begin(), s_b.end());
    const int before = s_min < -0.5 * step ? static_cast<int>(std::ceil(-s_min / step - 0.5)) : 0;
    const int after =
        s_max > length_a + 0.5 * step ? static_cast<int>(std::ceil((s_max - length_a) / step - 0.5))
                                      : 0;
    std::vector<double> s(before, 0.0);
    for (int i = 0; i < before; ++i) s[i] = -step * (before - i);
    s.insert(s.end(), grid.begin(), grid.end());
    for (int i = 1; i <= after; ++i) s.push_back(length_a + step * i);
    const size_t n = s.size();
    std::vector<Eigen::Vector3d> sum_p(n, Eigen::Vector3d::Zero());
    std::vector<double> sum_r(n, 0.0), sum_w(n, 0.0);
    for (size_t k = 0; k < a->size(); ++k) {
      sum_p[before + k] = a->weights[k] * a->points[k];
      sum_r[before + k] = a->weights[k] * a->radii[k];
      sum_w[before + k] = a->weights[k];
    }
    for (size_t j = 0; j < b.size(); ++j) {
      const double sj = std::clamp(s_b[j], s.front(), s.back());
      size_t hi = static_cast<size_t>(std::upper_bound(s.begin(), s.end(), sj) - s.begin());
      hi = std::clamp<size_t>(hi, 1, n - 1);
      const size_t lo = hi - 1;
      const double span = s[hi] - s[lo];
      const double t = span > 1e-12 ? std::clamp((sj - s[lo]) / span, 0.0, 1.0) : 0.0;
      for (const auto& [k, c] : {std::pair{lo, 1.0 - t}, std::pair{hi, t}}) {
        sum_p[k] += c * b.weights[j] * b.points[j];
        sum_r[k] += c * b.weights[j] * b.radii[j];
        sum_w[k] += c * b.weights[j];
      }
    }
    // Trim unreached extension nodes, then interpolate interior ones.
    size_t first = 0, last = n - 1;
    while (first < last && sum_w[first] <= 0.0) ++first;
    while (last > first && sum_w[last] <= 0.0) --last;
    Track out;
    out.pieces = a->pieces + b.pieces;
    for (size_t k = first; k <= last; ++k) {
      if (sum_w[k] > 0.0) {
        out.points.push_back(sum_p[k] / sum_w[k]);
        out.radii.push_back(sum_r[k] / sum_w[k]);
        out.weights.push_back(sum_w[k]);
        continue;
      }
      size_t next = k + 1;
      while (sum_w[next] <= 0.0) ++next;  // last has weight > 0
      const Eigen::Vector3d p_next = sum_p[next] / sum_w[next];
      const double r_next = sum_r[next] / sum_w[next];
      const double t = (s[k] - s[k - 1]) / (s[next] - s[k - 1]);
      out.points.push_back(out.points.back() + t * (p_next - out.points.back()));
      out.radii.push_back(out.radii.back() + t * (r_next - out.radii.back()));
      out.weights.push_back(kMinWeight);
      sum_p[k] = out.points.back();  // so that the next gap node interpolates from here
      sum_r[k] = out.radii.back();
      sum_w[k] = 1.0;
    }
    *a = std::move(out);
  }

  // Arc lengths along a for the nodes of b given an overlap (b already in a's orientation).
  static std::vector<double> ParamsFromOverlap(const Track& b, const Overlap& ov) {
    const std::vector<double> arc_b = ArcLengths(b.points);
    std::vector<double> s(b.size());
    for (int j = 0; j < static_cast<int>(b.size()); ++j) {
      if (j < ov.b_begin) {
        s[j] = ov.s_on_a[ov.b_begin] - (arc_b[ov.b_begin] - arc_b[j]);
      } else if (j > ov.b_end) {
        s[j] = ov.s_on_a[ov.b_end] + (arc_b[j] - arc_b[ov.b_end]);
      } else {
        s[j] = ov.s_on_a[j];
      }
    }
    return s;
  }

  static void Reverse(Track* t) {
    std::reverse(t->points.begin(), t->points.end());
    std::reverse(t->radii.begin(), t->radii.end());
    std::reverse(t->weights.begin(), t->weights.end());
  }

  // One sweep of duplicate fusion; true if anything was fused.
  bool FuseDuplicates(std::vector<Track>* tracks) const {
    bool changed = false;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (const Track& t : *tracks) boxes.push_back(BoxOf(t, options_.merge_distance_m));
    for (size_t i = 0; i < tracks->size(); ++i) {
      if (!(*tracks)[i].alive) continue;
      for (size_t j = 0; j < tracks->size(); ++j) {
        Track& a = (*tracks)[i];
        Track& b = (*tracks)[j];
        if (j == i || !b.alive || !boxes[i].intersects(boxes[j])) continue;
        std::optional<Overlap> ov = FindOverlap(a, b);
        if (!ov) continue;
        Track oriented = b;
        if (ov->reversed) {
          Reverse(&oriented);
          std::reverse(ov->s_on_a.begin(), ov->s_on_a.end());
          const int n = static_cast<int>(b.size());
          const int begin = n - 1 - ov->b_end;
          ov->b_end = n - 1 - ov->b_begin;
          ov->b_begin = begin;
        }
        FuseInto(&a, oriented, ParamsFromOverlap(oriented, *ov));
        boxes[i] = BoxOf(a, options_.merge_distance_m);
        b.alive = false;
        changed = true;
      }
    }
    return changed;
  }

  struct End {
    Eigen::Vector3d point;
    Eigen::Vector3d outward;  // unit tangent pointing away from the track
    double radius = 0.0;
  };

  End EndOf(const Track& t, int which) const {
    const size_t n = t.size();
    const size_t k = std::min(n - 1, static_cast<size_t>(2 * half_span_));
    End e;
    double rw = 0.0, r = 0.0;
    if (which == 0) {
      e.point = t.points[0];
      e.outward = t.points[0] - t.points[k];
      for (size_t i = 0; i <= k; ++i) r += t.weights[i] * t.radii[i], rw += t.weights[i];
    } else {
      e.point = t.points[n - 1];
      e.outward = t.points[n - 1] - t.points[n - 1 - k];
      for (size_t i = n - 1 - k; i < n; ++i) r += t.weights[i] * t.radii[i], rw += t.weights[i];
    }
    const double len = e.outward.norm();
    e.outward = len > 1e-12 ? Eigen::Vector3d(e.outward / len) : Eigen::Vector3d::UnitX();
    e.radius = r / rw;
    return e;
  }

  // How far, along a's end tangent, b's end lies; nullopt if they do not continue each other.
  std::optional<double> ChainGap(const End& a, const End& b) const {
    const Eigen::Vector3d gap = b.point - a.point;
    const double length = gap.norm();
    if (length > options_.max_long_gap_m) return std::nullopt;
    // Beyond max_gap_m only nearly straight continuations (a cane hidden behind a post).
    const bool long_gap = length > options_.max_gap_m;
    const double cos_max = long_gap ? cos_long_chain_ : cos_chain_;
    const double tan_max = long_gap ? tan_long_chain_ : tan_chain_;
    if (-a.outward.dot(b.outward) < cos_max) return std::nullopt;
    const double ratio = std::max(a.radius, b.radius) / std::min(a.radius, b.radius);
    if (!(ratio <= options_.max_radius_ratio)) return std::nullopt;
    const std::pair<Eigen::Vector3d, Eigen::Vector3d> sides[] = {{a.outward, gap},
                                                                 {b.outward, -gap}};
    for (const auto& [dir, g] : sides) {
      const double along = g.dot(dir);
      const double lateral = (g - along * dir).norm();
      if (along < -options_.min_overlap_m) return std::nullopt;
      if (lateral > options_.merge_distance_m + tan_max * std::max(0.0, along)) {
        return std::nullopt;
      }
    }
    return gap.dot(a.outward);
  }

  // Joins track ends that continue each other, best (shortest, straightest) first.
  bool Chain(std::vector<Track>* tracks) const {
    struct Candidate {
      double score;
      size_t a, b;
      int end_a, end_b;
      double along;
    };
    std::vector<size_t> alive;
    for (size_t i = 0; i < tracks->size(); ++i) {
      if ((*tracks)[i].alive) alive.push_back(i);
    }
    std::vector<std::array<End, 2>> ends(tracks->size());
    for (size_t i : alive) ends[i] = {EndOf((*tracks)[i], 0), EndOf((*tracks)[i], 1)};
    std::vector<Candidate> candidates;
    for (size_t x = 0; x < alive.size(); ++x) {
      for (size_t y = x + 1; y < alive.size(); ++y) {
        for (int ea = 0; ea < 2; ++ea) {
          for (int eb = 0; eb < 2; ++eb) {
            const End& a = ends[alive[x]][ea];
            const End& b = ends[alive[y]][eb];
            const std::optional<double> along = ChainGap(a, b);
            if (!along) continue;
            const double bend = std::acos(std::clamp(-a.outward.dot(b.outward), -1.0, 1.0));
            candidates.push_back({(b.point - a.point).norm() + 0.05 * bend, alive[x], alive[y],
                                  ea, eb, *along});
          }
        }
      }
    }
    if (candidates.empty()) return false;
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& l, const Candidate& r) { return l.score < r.score; });
    // Union-find over tracks keeps chains acyclic; each end is used once.
    std::vector<size_t> root(tracks->size());
    std::iota(root.begin(), root.end(), 0);
    auto find = [&](size_t i) {
      while (root[i] != i) i = root[i] = root[root[i]];
      return i;
    };
    std::vector<std::array<std::optional<std::pair<size_t, int>>, 2>> link(tracks->size());
    std::vector<std::array<double, 2>> link_along(tracks->size(), {0.0, 0.0});
    bool any = false;
    for (const Candidate& c : candidates) {
      if (link[c.a][c.end_a] || link[c.b][c.end_b] || find(c.a) == find(c.b)) continue;
      root[find(c.a)] = find(c.b);
      link[c.a][c.end_a] = std::pair{c.b, c.end_b};
      link[c.b][c.end_b] = std::pair{c.a, c.end_a};
      link_along[c.a][c.end_a] = link_along[c.b][c.end_b] = c.along;
      any = true;
    }
    if (!any) return false;
    // Walk each chain from a free end, appending the next track after the gap.
    std::vector<char> visited(tracks->size(), 0);
    for (size_t start : alive) {
      if (visited[start]) continue;
      int free_end = !link[start][0] ? 0 : (!link[start][1] ? 1 : -1);
      if (free_end < 0) continue;  // interior of a chain; reached from its free end
      visited[start] = 1;
      Track chain = (*tracks)[start];
      if (free_end == 1) Reverse(&chain);
      int out_end = 1 - free_end;
      size_t at = start;
      while (link[at][out_end]) {
        const auto [next, next_end] = *link[at][out_end];
        const double along = link_along[at][out_end];
        visited[next] = 1;
        Track piece = (*tracks)[next];
        if (next_end == 1) Reverse(&piece);
        const std::vector<double> arc = ArcLengths(piece.points);
        const double length = ArcLengths(chain.points).back();
        std::vector<double> s(piece.size());
        for (size_t j = 0; j < piece.size(); ++j) s[j] = length + along + arc[j];
        FuseInto(&chain, piece, s);
        (*tracks)[next].alive = false;
        at = next;
        out_end = 1 - next_end;
      }
      (*tracks)[start] = std::move(chain);
    }
    return true;
  }

  bool IsGhost(const Track& t) const {
    const double length = ArcLengths(t.points).back();
    if (length < options_.min_cane_length_m) return true;
    if (t.pieces == 1 && length < options_.min_isolated_length_m) return true;
    return t.Evidence(options_.step_m) < options_.min_evidence_m;
  }

  Polyline3 Finish(const Track& t) const {
    // Radii: weighted mean over +-radius_smoothing_m along the cane.
    const std::vector<double> arc = ArcLengths(t.points);
    Polyline3 dense;
    dense.points = t.points;
    dense.radii.resize(t.size());
    for (size_t i = 0, lo = 0; i < t.size(); ++i) {
      while (arc[i] - arc[lo] > options_.radius_smoothing_m) ++lo;
      double sum = 0.0, w = 0.0;
      for (size_t k = lo; k < t.size() && arc[k] - arc[i] <= options_.radius_smoothing_m; ++k) {
        sum += t.weights[k] * t.radii[k];
        w += t.weights[k];
      }
      dense.radii[i] = sum / w;
    }
    // One [1 2 1] / 4 pass on interior points takes the sample noise down without moving ends.
    for (size_t i = 1; i + 1 < t.size(); ++i) {
      dense.points[i] = 0.25 * (t.points[i - 1] + 2.0 * t.points[i] + t.points[i + 1]);
    }
    return dense.Resampled(options_.step_m);
  }

 private:
  const AssemblyOptions& options_;
  int half_span_;
  double cos_merge_;
  double cos_chain_;
  double tan_chain_;
  double cos_long_chain_;
  double tan_long_chain_;
};

absl::Status ValidatePiece(const Piece3D& piece, size_t i) {
  const std::string what = absl::StrCat("pieces[", i, "]");
  if (absl::Status s = piece.polyline.Validate(what); !s.ok()) return s;
  if (!(piece.probability >= 0.0 && piece.probability <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": probability must be in [0, 1], is ", piece.probability));
  }
  if (!(piece.support >= 0.0 && piece.support <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": support must be in [0, 1], is ", piece.support));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<Polyline3>> AssembleCanes(const std::vector<Piece3D>& pieces,
                                                     const AssemblyOptions& options,
                                                     const Deadline& deadline) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (absl::Status s = ValidatePiece(pieces[i], i); !s.ok()) return s;
  }
  if (absl::Status s = deadline.Check("AssembleCanes"); !s.ok()) return s;

  const Assembler assembler(options);
  std::vector<Track> tracks;
  for (const Piece3D& piece : pieces) {
    if (piece.probability < options.min_piece_probability) continue;
    Track t = assembler.FromPiece(piece);
    if (t.size() >= 2) tracks.push_back(std::move(t));
  }
  // Strongest first: they set the grid the weaker duplicates are averaged onto.
  std::stable_sort(tracks.begin(), tracks.end(), [&](const Track& a, const Track& b) {
    return a.Evidence(options.step_m) > b.Evidence(options.step_m);
  });
  for (int round = 0; round < 8; ++round) {
    bool changed = false;
    while (assembler.FuseDuplicates(&tracks)) {
      changed = true;
      if (absl::Status s = deadline.Check("AssembleCanes"); !s.ok()) return s;
    }
    if (assembler.Chain(&tracks)) changed = true;
    if (absl::Status s = deadline.Check("AssembleCanes"); !s.ok()) return s;
    std::erase_if(tracks, [](const Track& t) { return !t.alive; });
    if (!changed) break;
  }
  std::vector<Polyline3> canes;
  for (const Track& t : tracks) {
    if (!t.alive || assembler.IsGhost(t)) continue;
    canes.push_back(assembler.Finish(t));
  }
  return canes;
}

}  // namespace vb::reconstruct
