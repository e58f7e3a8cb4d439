// SPDX-License-Identifier: Apache-2.0
// The primitive checker's obstacle hierarchy: the scene's obstacles cut into pieces, ordered by
// median splits into leaves of 8 and nodes of 8 leaves with their boxes and bounding capsules
// (Impl::BuildObstacles, run once by the constructor), and Exclude, which turns an obstacle's
// pieces into padding lanes and refits the bounds above them. The checks that walk it are in
// primitive_checker.cc (one configuration) and primitive_checker_batch.cc (lanes).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "workers/plan/primitive_checker.h"

#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#include "workers/plan/primitive_checker_internal.h"

namespace vb::plan {
namespace {

using namespace prim;

// The capsule around spheres (centre, radius) and capsules given by their end spheres (a capsule
// lies inside a capsule that holds both its end spheres: the distance to a segment is convex).
// The axis joins the two points found by two farthest-point sweeps.
Bound Enclose(const std::vector<std::pair<Eigen::Vector3d, double>>& balls) {
  auto farthest = [&](const Eigen::Vector3d& from) {
    Eigen::Vector3d best = from;
    double best_d = -1;
    for (const auto& [c, r] : balls) {
      if ((c - from).squaredNorm() > best_d) best_d = (c - from).squaredNorm(), best = c;
    }
    return best;
  };
  const Eigen::Vector3d p1 = farthest(balls.front().first);
  const Eigen::Vector3d p2 = farthest(p1);
  Eigen::Vector3d axis = p2 - p1;
  const double length = axis.norm();
  if (length <= 1e-9) {
    double r = 0;
    for (const auto& [c, rr] : balls) r = std::max(r, (c - p1).norm() + rr);
    return Bound{p1, p1, r};
  }
  axis /= length;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& [c, r] : balls) {
    lo = std::min(lo, (c - p1).dot(axis));
    hi = std::max(hi, (c - p1).dot(axis));
  }
  Bound out{p1 + lo * axis, p1 + hi * axis, 0.0};
  for (const auto& [c, r] : balls) {
    out.radius = std::max(out.radius, PointSegmentDistance(c, out.a, out.b) + r);
  }
  return out;
}

Bound BoundPieces(const std::vector<Piece>& pieces, int begin, int end) {
  std::vector<std::pair<Eigen::Vector3d, double>> balls;
  for (int i = begin; i < end; ++i) {
    balls.emplace_back(pieces[i].a, pieces[i].rad);
    balls.emplace_back(pieces[i].b, pieces[i].rad);
  }
  return Enclose(balls);
}

void SetLane(F4* v, int lane, float value) { v[lane / 4][lane % 4] = value; }

// Lane k of `set` := capsule (a, b, rad); lanes past the end are far away and empty.
void SetCapsule(CapsuleSet& set, int k, bool real, const Eigen::Vector3d& a,
                const Eigen::Vector3d& b, double rad) {
  const Eigen::Vector3d d = real ? Eigen::Vector3d(b - a) : Eigen::Vector3d::Zero();
  const double e = d.squaredNorm();
  SetLane(set.q0x, k, real ? a.x() : kFarAway);
  SetLane(set.q0y, k, real ? a.y() : kFarAway);
  SetLane(set.q0z, k, real ? a.z() : kFarAway);
  SetLane(set.dx, k, d.x());
  SetLane(set.dy, k, d.y());
  SetLane(set.dz, k, d.z());
  SetLane(set.e, k, e);
  SetLane(set.inv_e, k, e > 0 ? 1.0 / e : 0.0);
  SetLane(set.rad, k, real ? rad : 0.0);
}

using Box = Eigen::AlignedBox3d;

Box BoxOfPieces(const std::vector<Piece>& pieces, int begin, int end) {
  Box box;
  for (int i = begin; i < end; ++i) {
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(pieces[i].rad + kCoarseSlackM);
    box.extend(pieces[i].a - r).extend(pieces[i].a + r).extend(pieces[i].b - r).extend(pieces[i].b + r);
  }
  return box;
}

// A leaf's bounding capsule for the lanes (float, inflated by kCoarseSlackM).
std::array<float, 9> LeafCap(const Bound& b) {
  const Eigen::Vector3d d = b.b - b.a;
  const double e = d.squaredNorm();
  return {static_cast<float>(b.a.x()), static_cast<float>(b.a.y()), static_cast<float>(b.a.z()),
          static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z()),
          static_cast<float>(e), e > 0 ? static_cast<float>(1.0 / e) : 0.f,
          static_cast<float>(b.radius + kCoarseSlackM)};
}

// Lane k of a BoxSet := box (an empty box is inverted: it overlaps nothing).
void SetBoxLane(BoxSet& set, int k, const Box& b) {
  SetLane(set.lox, k, b.min().x());
  SetLane(set.loy, k, b.min().y());
  SetLane(set.loz, k, b.min().z());
  SetLane(set.hix, k, b.max().x());
  SetLane(set.hiy, k, b.max().y());
  SetLane(set.hiz, k, b.max().z());
}

BoxSet MakeBoxSet(const std::vector<Box>& boxes, int begin, int end) {
  BoxSet set;
  for (int k = 0; k < kLeaf; ++k) {
    const bool real = begin + k < end;
    const Box& b = boxes[real ? begin + k : begin];
    // Empty lanes: an inverted box overlaps nothing.
    SetLane(set.lox, k, real ? b.min().x() : kFarAway);
    SetLane(set.loy, k, real ? b.min().y() : kFarAway);
    SetLane(set.loz, k, real ? b.min().z() : kFarAway);
    SetLane(set.hix, k, real ? b.max().x() : -kFarAway);
    SetLane(set.hiy, k, real ? b.max().y() : -kFarAway);
    SetLane(set.hiz, k, real ? b.max().z() : -kFarAway);
  }
  return set;
}

// Orders pieces [begin, end) by recursive median splits along the longest axis of their
// centres, splitting at multiples of 64 (a node) or 8 (a leaf) so that consecutive runs of 8 and
// 64 pieces are spatially compact. Works on indices and the pieces' a + b (twice their centres;
// moving 56-byte pieces at every level cost more than the splits), then permutes once. Which
// pieces share a leaf changes no check's result: every coarse level only culls with slack, and
// each piece is tested on its own (primitive_checker.h).
void SplitOrder(const std::vector<Eigen::Vector3d>& sums, std::vector<int>& order, int begin,
                int end) {
  const int n = end - begin;
  if (n <= kLeaf) return;
  const int unit = n > kLeaf * kLeaf ? kLeaf * kLeaf : kLeaf;
  const int half_units = ((n + unit - 1) / unit + 1) / 2;
  const int mid = begin + std::min(n - 1, half_units * unit);
  Eigen::Vector3d lo = sums[order[begin]], hi = lo;
  for (int i = begin + 1; i < end; ++i) {
    lo = lo.cwiseMin(sums[order[i]]);
    hi = hi.cwiseMax(sums[order[i]]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](int p, int q) { return sums[p][axis] < sums[q][axis]; });
  SplitOrder(sums, order, begin, mid);
  SplitOrder(sums, order, mid, end);
}

// Returns the permutation: the ordered piece k was pieces[order[k]].
std::vector<int> SplitOrder(std::vector<Piece>& pieces) {
  std::vector<Eigen::Vector3d> sums;
  sums.reserve(pieces.size());
  for (const Piece& p : pieces) sums.push_back(p.a + p.b);
  std::vector<int> order(pieces.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  SplitOrder(sums, order, 0, static_cast<int>(order.size()));
  std::vector<Piece> ordered;
  ordered.reserve(pieces.size());
  for (int i : order) ordered.push_back(pieces[i]);
  pieces = std::move(ordered);
  return order;
}

}  // namespace

using namespace prim;

void PrimitiveChecker::Impl::BuildObstacles(const CollisionScene& scene) {
  Impl& m = *this;
  std::vector<int> source;  // the obstacle of each piece
  for (size_t i = 0; i < scene.obstacles.size(); ++i) {
    const Obstacle& o = scene.obstacles[i];
    const double length = (o.capsule.b - o.capsule.a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(length / kMaxPieceM)));
    for (int k = 0; k < n; ++k) {
      source.push_back(static_cast<int>(i));
      m.pieces.push_back(Piece{o.capsule.a + (o.capsule.b - o.capsule.a) * (double(k) / n),
                               o.capsule.a + (o.capsule.b - o.capsule.a) * (double(k + 1) / n),
                               o.capsule.radius + o.margin_m});
    }
  }
  const std::vector<int> order = SplitOrder(m.pieces);
  m.obstacle_pieces.assign(scene.obstacles.size(), {});
  for (size_t k = 0; k < order.size(); ++k)
    m.obstacle_pieces[source[order[k]]].push_back(static_cast<int>(k));
  m.piece_excluded.assign(m.pieces.size(), 0);
  const int n_pieces = static_cast<int>(m.pieces.size());
  const int n_leaves = (n_pieces + kLeaf - 1) / kLeaf;
  for (int l = 0; l < n_leaves; ++l) {
    const int begin = l * kLeaf, end = std::min(n_pieces, begin + kLeaf);
    m.leaf_bounds.push_back(BoundPieces(m.pieces, begin, end));
    CapsuleSet leaf;
    for (int k = 0; k < kLeaf; ++k) {
      const bool real = begin + k < end;
      const Piece& p = m.pieces[real ? begin + k : begin];
      SetCapsule(leaf, k, real, p.a, p.b, p.rad);
    }
    m.leaves.push_back(leaf);
  }
  for (const Piece& p : m.pieces) {
    m.piece_balls.push_back({0.5 * (p.a + p.b), 0.5 * (p.b - p.a).norm() + p.rad});
  }
  for (const Bound& b : m.leaf_bounds) {
    m.leaf_balls.push_back({0.5 * (b.a + b.b), 0.5 * (b.b - b.a).norm() + b.radius});
  }
  std::vector<Box>& leaf_boxes = m.leaf_boxes;
  std::vector<Box> node_boxes;
  for (int l = 0; l < n_leaves; ++l) {
    leaf_boxes.push_back(BoxOfPieces(m.pieces, l * kLeaf, std::min(n_pieces, (l + 1) * kLeaf)));
  }
  for (const Bound& b : m.leaf_bounds) m.leaf_caps.push_back(LeafCap(b));
  for (const Box& box : leaf_boxes) {
    for (int k = 0; k < 3; ++k) {
      m.leaf_lo.push_back(static_cast<float>(box.min()[k]));
      m.leaf_hi.push_back(static_cast<float>(box.max()[k]));
    }
  }
  const int n_nodes = (n_leaves + kLeaf - 1) / kLeaf;
  for (int n = 0; n < n_nodes; ++n) {
    const int begin = n * kLeaf, end = std::min(n_leaves, begin + kLeaf);
    Box box;
    for (int l = begin; l < end; ++l) box.extend(leaf_boxes[l]);
    node_boxes.push_back(box);
    m.node_children.push_back(MakeBoxSet(leaf_boxes, begin, end));
  }
  for (int g = 0; g * kLeaf < n_nodes; ++g) {
    m.top.push_back(MakeBoxSet(node_boxes, g * kLeaf, std::min(n_nodes, (g + 1) * kLeaf)));
  }
}

void PrimitiveChecker::Exclude(std::span<const int> obstacles) {
  Impl& m = *impl_;
  auto set = [&](int obstacle, bool excluded) {
    for (int k : m.obstacle_pieces[obstacle]) {
      m.piece_excluded[k] = excluded;
      const Piece& p = m.pieces[k];
      // An excluded lane is a padding lane: far away, radius 0 (it never touches).
      SetCapsule(m.leaves[k / kLeaf], k % kLeaf, !excluded, p.a, p.b, p.rad);
    }
  };
  std::vector<int> touched;  // leaves whose pieces changed
  for (int o : m.excluded) {
    set(o, false);
    for (int k : m.obstacle_pieces[o]) touched.push_back(k / kLeaf);
  }
  m.excluded.clear();
  for (int o : obstacles) {
    if (o < 0 || o >= static_cast<int>(m.obstacle_pieces.size())) continue;
    set(o, true);
    m.excluded.push_back(o);
    for (int k : m.obstacle_pieces[o]) touched.push_back(k / kLeaf);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  // Refit the bounds of those leaves, their nodes and groups to the pieces left in, as a build
  // on the scene without the excluded obstacles would bound them (a bound that still held the
  // excluded pieces would only cull less, but they lie where the tool works).
  const int n_pieces = static_cast<int>(m.pieces.size());
  const int n_leaves = static_cast<int>(m.leaves.size());
  for (int l : touched) {
    std::vector<Piece> in;
    for (int k = l * kLeaf; k < std::min(n_pieces, (l + 1) * kLeaf); ++k)
      if (!m.piece_excluded[k]) in.push_back(m.pieces[k]);
    const Box box = BoxOfPieces(in, 0, static_cast<int>(in.size()));
    m.leaf_boxes[l] = box;
    m.leaf_bounds[l] = in.empty() ? Bound{Eigen::Vector3d::Constant(kFarAway),
                                          Eigen::Vector3d::Constant(kFarAway), 0.0}
                                  : BoundPieces(in, 0, static_cast<int>(in.size()));
    const Bound& b = m.leaf_bounds[l];
    m.leaf_balls[l] = {0.5 * (b.a + b.b), 0.5 * (b.b - b.a).norm() + b.radius};
    m.leaf_caps[l] = LeafCap(b);
    for (int k = 0; k < 3; ++k) {
      m.leaf_lo[3 * l + k] = static_cast<float>(box.min()[k]);
      m.leaf_hi[3 * l + k] = static_cast<float>(box.max()[k]);
    }
    SetBoxLane(m.node_children[l / kLeaf], l % kLeaf, box);
  }
  for (size_t i = 0; i < touched.size(); ++i) {
    const int node = touched[i] / kLeaf;
    if (i > 0 && touched[i - 1] / kLeaf == node) continue;
    Box box;
    for (int l = node * kLeaf; l < std::min(n_leaves, (node + 1) * kLeaf); ++l)
      box.extend(m.leaf_boxes[l]);
    SetBoxLane(m.top[node / kLeaf], node % kLeaf, box);
  }
  if (m.last_piece >= 0 && m.piece_excluded[m.last_piece]) m.last_capsule = m.last_piece = -1;
  m.UpdateBaseBlocked();
}

}  // namespace vb::plan
