// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/primitive_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

namespace vb::plan {
namespace {

// Four float lanes: SSE2 on x86-64, NEON on arm64, scalar code elsewhere. Leaves hold 8
// obstacles, processed as two halves.
typedef float F4 __attribute__((vector_size(16)));
typedef int32_t I4 __attribute__((vector_size(16)));
constexpr int kLeaf = 8;
constexpr int kHalves = kLeaf / 4;
// Padding lanes sit here with radius 0: never within reach of the arm.
constexpr float kFarAway = 1e6f;
// Coarse spheres are inflated by this so that float rounding never culls a real contact.
constexpr double kCoarseSlackM = 1e-4;

inline F4 Splat(float v) { return F4{v, v, v, v}; }
inline F4 Min(F4 a, F4 b) { return a < b ? a : b; }
inline F4 Max(F4 a, F4 b) { return a > b ? a : b; }
inline F4 Clamp01(F4 x) { return Min(Max(x, Splat(0.f)), Splat(1.f)); }
inline unsigned Bits(I4 m) {
  return (m[0] ? 1u : 0u) | (m[1] ? 2u : 0u) | (m[2] ? 4u : 0u) | (m[3] ? 8u : 0u);
}

// Eight obstacle capsules, SoA: q0 + t d for t in [0, 1], e = |d|^2, inv_e = 1/e (0 for a
// sphere), rad = radius + margin.
struct Leaf {
  F4 q0x[kHalves], q0y[kHalves], q0z[kHalves];
  F4 dx[kHalves], dy[kHalves], dz[kHalves];
  F4 e[kHalves], inv_e[kHalves], rad[kHalves];
};

// Eight bounding spheres (of a node's leaves, or of a group of nodes).
struct SphereSet {
  F4 cx[kHalves], cy[kHalves], cz[kHalves], r[kHalves];
};

// One arm capsule in the base frame, prepared for the lanes.
struct ArmSeg {
  F4 p0x, p0y, p0z, d1x, d1y, d1z, a, inv_a, r;
};

ArmSeg PrepareSeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  return ArmSeg{Splat(a.x()), Splat(a.y()), Splat(a.z()),
                Splat(d.x()), Splat(d.y()), Splat(d.z()),
                Splat(len2),  Splat(len2 > 0 ? 1.0 / len2 : 0.0), Splat(r)};
}

// Bit k set if arm segment s comes within s.r + r_k of sphere centre k.
inline unsigned SegVsSpheres(const ArmSeg& s, const SphereSet& set) {
  unsigned bits = 0;
  for (int h = 0; h < kHalves; ++h) {
    const F4 wx = set.cx[h] - s.p0x, wy = set.cy[h] - s.p0y, wz = set.cz[h] - s.p0z;
    const F4 t = Clamp01((wx * s.d1x + wy * s.d1y + wz * s.d1z) * s.inv_a);
    const F4 ex = wx - s.d1x * t, ey = wy - s.d1y * t, ez = wz - s.d1z * t;
    const F4 rr = s.r + set.r[h];
    bits |= Bits(ex * ex + ey * ey + ez * ez < rr * rr) << (4 * h);
  }
  return bits;
}

// True if arm segment s touches any of the leaf's capsules: closest points of two segments
// (Ericson, Real-Time Collision Detection, 5.1.9), branch-free over the lanes.
inline bool SegVsLeaf(const ArmSeg& s, const Leaf& l) {
  for (int h = 0; h < kHalves; ++h) {
    const F4 rx = s.p0x - l.q0x[h], ry = s.p0y - l.q0y[h], rz = s.p0z - l.q0z[h];
    const F4 b = s.d1x * l.dx[h] + s.d1y * l.dy[h] + s.d1z * l.dz[h];
    const F4 c = s.d1x * rx + s.d1y * ry + s.d1z * rz;
    const F4 f = l.dx[h] * rx + l.dy[h] * ry + l.dz[h] * rz;
    const F4 e = l.e[h];
    const F4 denom = s.a * e - b * b;
    const F4 safe = denom > Splat(1e-12f) ? denom : Splat(1.f);
    F4 sp = denom > Splat(1e-12f) ? Clamp01((b * f - c * e) / safe) : Splat(0.f);
    // Obstacle spheres (e = 0): the closest point of the arm segment to the centre.
    sp = e > Splat(0.f) ? sp : Clamp01(-c * s.inv_a);
    const F4 tn = (b * sp + f) * l.inv_e[h];
    const F4 s_lo = Clamp01(-c * s.inv_a), s_hi = Clamp01((b - c) * s.inv_a);
    sp = tn < Splat(0.f) ? s_lo : (tn > Splat(1.f) ? s_hi : sp);
    const F4 t = Clamp01(tn);
    const F4 ex = rx + s.d1x * sp - l.dx[h] * t;
    const F4 ey = ry + s.d1y * sp - l.dy[h] * t;
    const F4 ez = rz + s.d1z * sp - l.dz[h] * t;
    const F4 rr = s.r + l.rad[h];
    if (Bits(ex * ex + ey * ey + ez * ez < rr * rr)) return true;
  }
  return false;
}

struct Piece {
  Eigen::Vector3d a, b;
  double rad;  // radius + margin
};

struct Bound {
  Eigen::Vector3d center;
  double radius;
};

struct ArmCapsule {
  int frame;
  int body;
  Eigen::Vector3d a, b;  // in the link frame
  double radius;
};

// A link frame as columns and origin (the rotation is never needed as a matrix).
struct Frame {
  Eigen::Vector3d x, y, z, p;
};

Bound BoundPieces(const std::vector<Piece>& pieces, int begin, int end) {
  Eigen::AlignedBox3d box;
  for (int i = begin; i < end; ++i) {
    box.extend(pieces[i].a);
    box.extend(pieces[i].b);
  }
  Bound out{box.center(), 0.0};
  for (int i = begin; i < end; ++i) {
    out.radius = std::max(out.radius, std::max((pieces[i].a - out.center).norm(),
                                               (pieces[i].b - out.center).norm()) +
                                          pieces[i].rad);
  }
  return out;
}

Bound BoundBounds(const std::vector<Bound>& bounds, int begin, int end) {
  Eigen::AlignedBox3d box;
  for (int i = begin; i < end; ++i) {
    box.extend(bounds[i].center - Eigen::Vector3d::Constant(bounds[i].radius));
    box.extend(bounds[i].center + Eigen::Vector3d::Constant(bounds[i].radius));
  }
  Bound out{box.center(), 0.0};
  for (int i = begin; i < end; ++i) {
    out.radius = std::max(out.radius, (bounds[i].center - out.center).norm() + bounds[i].radius);
  }
  return out;
}

void SetLane(F4* v, int lane, float value) { v[lane / 4][lane % 4] = value; }

SphereSet MakeSphereSet(const std::vector<Bound>& bounds, int begin, int end) {
  SphereSet set;
  for (int k = 0; k < kLeaf; ++k) {
    const bool real = begin + k < end;
    const Bound& b = real ? bounds[begin + k] : bounds[begin];
    SetLane(set.cx, k, real ? b.center.x() : kFarAway);
    SetLane(set.cy, k, real ? b.center.y() : kFarAway);
    SetLane(set.cz, k, real ? b.center.z() : kFarAway);
    SetLane(set.r, k, real ? b.radius + kCoarseSlackM : 0.f);
  }
  return set;
}

// Orders pieces [begin, end) by recursive median splits along the longest axis of their
// centres, splitting at multiples of 64 (a node) or 8 (a leaf) so that consecutive runs of 8 and
// 64 pieces are spatially compact.
void SplitOrder(std::vector<Piece>& pieces, int begin, int end) {
  const int n = end - begin;
  if (n <= kLeaf) return;
  const int unit = n > kLeaf * kLeaf ? kLeaf * kLeaf : kLeaf;
  const int half_units = ((n + unit - 1) / unit + 1) / 2;
  const int mid = begin + std::min(n - 1, half_units * unit);
  Eigen::AlignedBox3d box;
  for (int i = begin; i < end; ++i) box.extend(0.5 * (pieces[i].a + pieces[i].b));
  int axis = 0;
  box.sizes().maxCoeff(&axis);
  std::nth_element(pieces.begin() + begin, pieces.begin() + mid, pieces.begin() + end,
                   [axis](const Piece& p, const Piece& q) {
                     return p.a[axis] + p.b[axis] < q.a[axis] + q.b[axis];
                   });
  SplitOrder(pieces, begin, mid);
  SplitOrder(pieces, mid, end);
}

double CapsuleCapsuleGap(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, double ra,
                         const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, double rb) {
  const double d = (b0 == b1) ? PointSegmentDistance(b0, a0, a1) : SegmentSegmentDistance(a0, a1, b0, b1);
  return d - ra - rb;
}

}  // namespace

struct PrimitiveChecker::Impl {
  std::array<double, 6> dh_a{}, dh_d{}, dh_ca{}, dh_sa{};
  std::vector<ArmCapsule> moving;   // frame > 0, distal first (most likely to touch the vine)
  std::vector<ArmCapsule> fixed;    // frame 0
  // Capsule pairs (indices into `all`, the capsules in body order) that must not touch.
  std::vector<ArmCapsule> all;
  std::vector<std::pair<int, int>> self_pairs;
  std::vector<HalfSpace> planes;
  bool base_blocked = false;

  std::vector<Piece> pieces;        // in leaf order
  std::vector<Bound> leaf_bounds;   // one per leaf
  std::vector<Bound> node_bounds;   // one per node (8 leaves)
  std::vector<Leaf> leaves;
  std::vector<SphereSet> node_children;  // per node: its leaves' spheres
  std::vector<SphereSet> top;            // per group of 8 nodes: the nodes' spheres

  // Per-configuration scratch: the base-frame ends of every capsule in `all`.
  std::vector<Eigen::Vector3d> world_a, world_b;

  void Fk(const Joints& q, std::array<Frame, 7>& f) const {
    f[0] = Frame{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                 Eigen::Vector3d::Zero()};
    // Standard DH, Rz(q) Tz(d) Tx(a) Rx(alpha), applied to the columns of the previous frame.
    for (int i = 0; i < 6; ++i) {
      const double ct = std::cos(q[i]), st = std::sin(q[i]);
      const Frame& in = f[i];
      Frame& out = f[i + 1];
      out.x = ct * in.x + st * in.y;
      const Eigen::Vector3d w = ct * in.y - st * in.x;
      out.y = dh_ca[i] * w + dh_sa[i] * in.z;
      out.z = dh_ca[i] * in.z - dh_sa[i] * w;
      out.p = in.p + dh_a[i] * out.x + dh_d[i] * in.z;
    }
  }

  void Place(const Joints& q) {
    std::array<Frame, 7> f;
    Fk(q, f);
    for (size_t i = 0; i < all.size(); ++i) {
      const Frame& fr = f[all[i].frame];
      const Eigen::Vector3d& a = all[i].a;
      const Eigen::Vector3d& b = all[i].b;
      world_a[i] = fr.p + a.x() * fr.x + a.y() * fr.y + a.z() * fr.z;
      world_b[i] = fr.p + b.x() * fr.x + b.y() * fr.y + b.z() * fr.z;
    }
  }

  bool SegHitsObstacles(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) const {
    const ArmSeg s = PrepareSeg(a, b, r);
    for (size_t g = 0; g < top.size(); ++g) {
      unsigned nodes = SegVsSpheres(s, top[g]);
      while (nodes) {
        const int n = static_cast<int>(g) * kLeaf + __builtin_ctz(nodes);
        nodes &= nodes - 1;
        unsigned ls = SegVsSpheres(s, node_children[n]);
        while (ls) {
          const int l = n * kLeaf + __builtin_ctz(ls);
          ls &= ls - 1;
          if (SegVsLeaf(s, leaves[l])) return true;
        }
      }
    }
    return false;
  }

  bool SegHitsPlanes(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) const {
    for (const HalfSpace& h : planes) {
      if (std::max(h.normal.dot(a), h.normal.dot(b)) + r + h.margin_m > h.offset) return true;
    }
    return false;
  }

  bool Free(const Joints& q) {
    if (base_blocked) return false;
    Place(q);
    // `all` lists moving capsules first (distal first), then fixed ones; see the constructor.
    for (size_t i = 0; i < moving.size(); ++i) {
      if (SegHitsPlanes(world_a[i], world_b[i], all[i].radius)) return false;
    }
    for (size_t i = 0; i < moving.size(); ++i) {
      if (SegHitsObstacles(world_a[i], world_b[i], all[i].radius)) return false;
    }
    for (const auto& [i, j] : self_pairs) {
      // Bounding spheres first: most pairs are far apart.
      const Eigen::Vector3d mi = 0.5 * (world_a[i] + world_b[i]);
      const Eigen::Vector3d mj = 0.5 * (world_a[j] + world_b[j]);
      const double reach = 0.5 * ((world_b[i] - world_a[i]).norm() +
                                  (world_b[j] - world_a[j]).norm()) +
                           all[i].radius + all[j].radius;
      if ((mi - mj).squaredNorm() >= reach * reach) continue;
      if (CapsuleCapsuleGap(world_a[i], world_b[i], all[i].radius, world_a[j], world_b[j],
                            all[j].radius) < 0) {
        return false;
      }
    }
    return true;
  }

  double SegClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                      double best) const {
    for (const HalfSpace& h : planes) {
      best = std::min(best, h.offset - std::max(h.normal.dot(a), h.normal.dot(b)) - r - h.margin_m);
    }
    for (size_t l = 0; l < leaf_bounds.size(); ++l) {
      const double lower = PointSegmentDistance(leaf_bounds[l].center, a, b) - r -
                           leaf_bounds[l].radius;
      if (lower >= best) continue;
      const int end = std::min<int>(pieces.size(), (l + 1) * kLeaf);
      for (int k = l * kLeaf; k < end; ++k) {
        best = std::min(best, CapsuleCapsuleGap(a, b, r, pieces[k].a, pieces[k].b, pieces[k].rad));
      }
    }
    return best;
  }

  double Clearance(const Joints& q) {
    Place(q);
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < all.size(); ++i) {
      best = SegClearance(world_a[i], world_b[i], all[i].radius, best);
    }
    for (const auto& [i, j] : self_pairs) {
      best = std::min(best, CapsuleCapsuleGap(world_a[i], world_b[i], all[i].radius, world_a[j],
                                              world_b[j], all[j].radius));
    }
    return best;
  }
};

PrimitiveChecker::PrimitiveChecker(const RobotModel& robot, const CollisionScene& scene)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const DhParameters& dh = Ur5Dh();
  for (int i = 0; i < 6; ++i) {
    m.dh_a[i] = dh.a[i];
    m.dh_d[i] = dh.d[i];
    m.dh_ca[i] = std::cos(dh.alpha[i]);
    m.dh_sa[i] = std::sin(dh.alpha[i]);
  }
  // Arm capsules: moving ones first, distal bodies first, then the fixed (frame 0) ones.
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  std::vector<std::vector<int>> capsules_of(bodies.size());
  std::vector<ArmCapsule> caps;
  for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
    for (const Capsule& c : bodies[b].capsules) {
      caps.push_back(ArmCapsule{bodies[b].frame, b, c.a, c.b, c.radius});
    }
  }
  std::stable_sort(caps.begin(), caps.end(),
                   [](const ArmCapsule& x, const ArmCapsule& y) { return x.frame > y.frame; });
  for (int i = 0; i < static_cast<int>(caps.size()); ++i) {
    (caps[i].frame > 0 ? m.moving : m.fixed).push_back(caps[i]);
    capsules_of[caps[i].body].push_back(i);
  }
  m.all = caps;
  m.world_a.resize(caps.size());
  m.world_b.resize(caps.size());
  for (const auto& [bi, bj] : robot.SelfCollisionPairs()) {
    for (int i : capsules_of[bi]) {
      for (int j : capsules_of[bj]) m.self_pairs.emplace_back(i, j);
    }
  }
  m.planes = scene.planes;

  // Obstacle pieces, split so that none is longer than kMaxPieceM (the union is unchanged).
  for (const Obstacle& o : scene.obstacles) {
    const double length = (o.capsule.b - o.capsule.a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(length / kMaxPieceM)));
    for (int k = 0; k < n; ++k) {
      m.pieces.push_back(Piece{o.capsule.a + (o.capsule.b - o.capsule.a) * (double(k) / n),
                               o.capsule.a + (o.capsule.b - o.capsule.a) * (double(k + 1) / n),
                               o.capsule.radius + o.margin_m});
    }
  }
  SplitOrder(m.pieces, 0, static_cast<int>(m.pieces.size()));
  const int n_pieces = static_cast<int>(m.pieces.size());
  const int n_leaves = (n_pieces + kLeaf - 1) / kLeaf;
  for (int l = 0; l < n_leaves; ++l) {
    const int begin = l * kLeaf, end = std::min(n_pieces, begin + kLeaf);
    m.leaf_bounds.push_back(BoundPieces(m.pieces, begin, end));
    Leaf leaf;
    for (int k = 0; k < kLeaf; ++k) {
      const bool real = begin + k < end;
      const Piece& p = m.pieces[real ? begin + k : begin];
      const Eigen::Vector3d d = real ? Eigen::Vector3d(p.b - p.a) : Eigen::Vector3d::Zero();
      const double e = d.squaredNorm();
      SetLane(leaf.q0x, k, real ? p.a.x() : kFarAway);
      SetLane(leaf.q0y, k, real ? p.a.y() : kFarAway);
      SetLane(leaf.q0z, k, real ? p.a.z() : kFarAway);
      SetLane(leaf.dx, k, d.x());
      SetLane(leaf.dy, k, d.y());
      SetLane(leaf.dz, k, d.z());
      SetLane(leaf.e, k, e);
      SetLane(leaf.inv_e, k, e > 0 ? 1.0 / e : 0.0);
      SetLane(leaf.rad, k, real ? p.rad : 0.0);
    }
    m.leaves.push_back(leaf);
  }
  const int n_nodes = (n_leaves + kLeaf - 1) / kLeaf;
  for (int n = 0; n < n_nodes; ++n) {
    const int begin = n * kLeaf, end = std::min(n_leaves, begin + kLeaf);
    m.node_bounds.push_back(BoundBounds(m.leaf_bounds, begin, end));
    m.node_children.push_back(MakeSphereSet(m.leaf_bounds, begin, end));
  }
  for (int g = 0; g * kLeaf < n_nodes; ++g) {
    m.top.push_back(MakeSphereSet(m.node_bounds, g * kLeaf, std::min(n_nodes, (g + 1) * kLeaf)));
  }

  // The base never moves: decide once whether it touches anything.
  for (const ArmCapsule& c : m.fixed) {
    if (m.SegClearance(c.a, c.b, c.radius, std::numeric_limits<double>::infinity()) < 0) {
      m.base_blocked = true;
    }
  }
}

PrimitiveChecker::~PrimitiveChecker() = default;

bool PrimitiveChecker::IsFree(const Joints& q) {
  ++checks_;
  return impl_->Free(q);
}

void PrimitiveChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  const size_t n = std::min(qs.size(), out.size());
  checks_ += static_cast<int64_t>(n);
  for (size_t i = 0; i < n; ++i) out[i] = impl_->Free(qs[i]);
}

double PrimitiveChecker::Clearance(const Joints& q) {
  ++checks_;
  return impl_->Clearance(q);
}

int PrimitiveChecker::pieces() const { return static_cast<int>(impl_->pieces.size()); }
int PrimitiveChecker::leaves() const { return static_cast<int>(impl_->leaves.size()); }

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel& robot,
                                                      const CollisionScene& scene) {
  return std::make_unique<PrimitiveChecker>(robot, scene);
}

}  // namespace vb::plan
