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
#if defined(__SSE__)
  return static_cast<unsigned>(__builtin_ia32_movmskps((F4)m));
#else
  return (m[0] ? 1u : 0u) | (m[1] ? 2u : 0u) | (m[2] ? 4u : 0u) | (m[3] ? 8u : 0u);
#endif
}

// Eight capsules, SoA: q0 + t d for t in [0, 1], e = |d|^2, inv_e = 1/e (0 for a sphere),
// rad = radius (+ margin). Obstacle pieces in a leaf, or the bounding capsules of a node's leaves
// or of a group of nodes: long thin canes are bounded far more tightly by capsules than by spheres.
struct CapsuleSet {
  F4 q0x[kHalves], q0y[kHalves], q0z[kHalves];
  F4 dx[kHalves], dy[kHalves], dz[kHalves];
  F4 e[kHalves], inv_e[kHalves], rad[kHalves];
};

// Eight axis-aligned boxes, SoA: the coarse levels. A box test is a handful of compares, several
// times cheaper than a capsule test, and canes (mostly along x or z) fill their boxes well.
struct BoxSet {
  F4 lox[kHalves], loy[kHalves], loz[kHalves], hix[kHalves], hiy[kHalves], hiz[kHalves];
};

// An axis-aligned box splatted over the lanes (a query against a BoxSet).
struct QueryBox {
  F4 lox, loy, loz, hix, hiy, hiz;
};

// One arm capsule in the base frame, prepared for the lanes.
struct ArmSeg {
  F4 p0x, p0y, p0z, d1x, d1y, d1z, a, inv_a, r;
  QueryBox box;  // its bounding box
};

ArmSeg PrepareSeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  const Eigen::Vector3d lo = a.cwiseMin(b).array() - r, hi = a.cwiseMax(b).array() + r;
  return ArmSeg{Splat(a.x()), Splat(a.y()), Splat(a.z()),
                Splat(d.x()), Splat(d.y()), Splat(d.z()),
                Splat(len2),  Splat(len2 > 0 ? 1.0 / len2 : 0.0), Splat(r),
                QueryBox{Splat(lo.x()), Splat(lo.y()), Splat(lo.z()),
                         Splat(hi.x()), Splat(hi.y()), Splat(hi.z())}};
}

// Lanes of `set` whose box overlaps the query box.
inline unsigned SegVsBoxes(const QueryBox& s, const BoxSet& set) {
  unsigned bits = 0;
  for (int h = 0; h < kHalves; ++h) {
    const I4 overlap = (set.lox[h] <= s.hix) & (set.hix[h] >= s.lox) & (set.loy[h] <= s.hiy) &
                       (set.hiy[h] >= s.loy) & (set.loz[h] <= s.hiz) & (set.hiz[h] >= s.loz);
    bits |= Bits(overlap) << (4 * h);
  }
  return bits;
}

// Lanes where capsule (p0 + s d1, s in [0, 1]) comes within rr of capsule (q0 + t d2): closest
// points of two segments (Ericson, Real-Time Collision Detection, 5.1.9), branch-free. a = |d1|^2,
// e = |d2|^2, inv_* their inverses or 0 for a sphere.
inline I4 CapsulesTouch(F4 p0x, F4 p0y, F4 p0z, F4 d1x, F4 d1y, F4 d1z, F4 a, F4 inv_a, F4 q0x,
                        F4 q0y, F4 q0z, F4 d2x, F4 d2y, F4 d2z, F4 e, F4 inv_e, F4 rr) {
  const F4 rx = p0x - q0x, ry = p0y - q0y, rz = p0z - q0z;
  const F4 b = d1x * d2x + d1y * d2y + d1z * d2z;
  const F4 c = d1x * rx + d1y * ry + d1z * rz;
  const F4 f = d2x * rx + d2y * ry + d2z * rz;
  const F4 denom = a * e - b * b;
  const I4 skew = denom > Splat(1e-12f);
  F4 sp = skew ? Clamp01((b * f - c * e) / (skew ? denom : Splat(1.f))) : Splat(0.f);
  // A sphere second (e = 0): the closest point of the first segment to its centre.
  sp = e > Splat(0.f) ? sp : Clamp01(-c * inv_a);
  const F4 tn = (b * sp + f) * inv_e;
  const F4 s_lo = Clamp01(-c * inv_a), s_hi = Clamp01((b - c) * inv_a);
  sp = tn < Splat(0.f) ? s_lo : (tn > Splat(1.f) ? s_hi : sp);
  const F4 t = Clamp01(tn);
  const F4 ex = rx + d1x * sp - d2x * t;
  const F4 ey = ry + d1y * sp - d2y * t;
  const F4 ez = rz + d1z * sp - d2z * t;
  return ex * ex + ey * ey + ez * ez < rr * rr;
}

// Lanes of `set` that arm segment s touches (bit k for lane k).
inline unsigned SegVsSet(const ArmSeg& s, const CapsuleSet& l) {
  unsigned bits = 0;
  for (int h = 0; h < kHalves; ++h) {
    bits |= Bits(CapsulesTouch(s.p0x, s.p0y, s.p0z, s.d1x, s.d1y, s.d1z, s.a, s.inv_a, l.q0x[h],
                               l.q0y[h], l.q0z[h], l.dx[h], l.dy[h], l.dz[h], l.e[h], l.inv_e[h],
                               s.r + l.rad[h]))
            << (4 * h);
  }
  return bits;
}

// sin and cos of four floats (Cephes' sinf/cosf: reduction by pi/2 in three parts, minimax
// polynomials on [-pi/4, pi/4]); absolute error ~1e-7 for |x| < 100, far below the float
// rounding of the positions. Joint values are within +-2 pi.
inline void SinCos4(F4 x, F4* s, F4* c) {
  const F4 jf = __builtin_convertvector(
      __builtin_convertvector(x * Splat(0.63661977236758134f) +
                                  (x >= Splat(0.f) ? Splat(0.5f) : Splat(-0.5f)), I4), F4);
  const I4 quadrant = __builtin_convertvector(jf, I4) & I4{3, 3, 3, 3};
  const F4 y = ((x - jf * Splat(1.5703125f)) - jf * Splat(4.837512969970703125e-4f)) -
               jf * Splat(7.54978995489188216e-8f);
  const F4 z = y * y;
  const F4 sy = y + y * z * (Splat(-1.6666654611e-1f) +
                             z * (Splat(8.3321608736e-3f) + z * Splat(-1.9515295891e-4f)));
  const F4 cy = Splat(1.f) - Splat(0.5f) * z +
                z * z * (Splat(4.166664568298827e-2f) +
                         z * (Splat(-1.388731625493765e-3f) + z * Splat(2.443315711809948e-5f)));
  const I4 swap = (quadrant & I4{1, 1, 1, 1}) != I4{0, 0, 0, 0};
  const I4 neg_s = (quadrant == I4{2, 2, 2, 2}) | (quadrant == I4{3, 3, 3, 3});
  const I4 neg_c = (quadrant == I4{1, 1, 1, 1}) | (quadrant == I4{2, 2, 2, 2});
  const F4 ss = swap ? cy : sy, cc = swap ? sy : cy;
  *s = neg_s ? -ss : ss;
  *c = neg_c ? -cc : cc;
}

// A link frame per lane (columns and origin).
struct Frame4 {
  F4 x[3], y[3], z[3], p[3];
};

// Lanes where the lane boxes (lo, hi per axis) overlap box b (scalars).
inline unsigned LanesOverlap(const F4 lo[3], const F4 hi[3], const float blo[3],
                             const float bhi[3]) {
  return Bits((lo[0] <= Splat(bhi[0])) & (hi[0] >= Splat(blo[0])) & (lo[1] <= Splat(bhi[1])) &
              (hi[1] >= Splat(blo[1])) & (lo[2] <= Splat(bhi[2])) & (hi[2] >= Splat(blo[2])));
}

struct Piece {
  Eigen::Vector3d a, b;
  double rad;  // radius + margin
};

// A bounding capsule (a sphere when a == b).
struct Bound {
  Eigen::Vector3d a, b;
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
  // self_pairs in groups of 4: 4 first capsules then 4 second ones; padded with a pair of far
  // apart capsules.
  std::vector<int> self_lanes;
  std::vector<float> cap_soa;  // scratch, see Free()
  std::vector<HalfSpace> planes;
  // planes_of[c]: the planes capsule c of `all` can reach in some configuration (per-link reach
  // culling, Botterill et al. 2017 section 3.4: the others are never tested for it).
  std::vector<std::vector<HalfSpace>> planes_of;
  bool base_blocked = false;

  std::vector<Piece> pieces;        // in leaf order
  std::vector<Bound> leaf_bounds;   // one per leaf
  std::vector<CapsuleSet> leaves;
  std::vector<BoxSet> node_children;  // per node: its leaves' boxes
  std::vector<BoxSet> top;            // per group of 8 nodes: the nodes' boxes

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
      unsigned nodes = SegVsBoxes(s.box, top[g]);
      while (nodes) {
        const int n = static_cast<int>(g) * kLeaf + __builtin_ctz(nodes);
        nodes &= nodes - 1;
          unsigned ls = SegVsBoxes(s.box, node_children[n]);
        while (ls) {
          const int l = n * kLeaf + __builtin_ctz(ls);
          ls &= ls - 1;
              if (SegVsSet(s, leaves[l])) return true;
        }
      }
    }
    return false;
  }

  bool SegHitsPlanes(size_t c, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                     double r) const {
    for (const HalfSpace& h : planes_of[c]) {
      if (std::max(h.normal.dot(a), h.normal.dot(b)) + r + h.margin_m > h.offset) return true;
    }
    return false;
  }

  bool Free(const Joints& q) {
    if (base_blocked) return false;
    Place(q);
    // `all` lists moving capsules first (distal first), then fixed ones; see the constructor.
    for (size_t i = 0; i < moving.size(); ++i) {
      if (SegHitsPlanes(i, world_a[i], world_b[i], all[i].radius)) return false;
    }
    for (size_t i = 0; i < moving.size(); ++i) {
      if (SegHitsObstacles(world_a[i], world_b[i], all[i].radius)) return false;
    }
    // Self-collision pairs four at a time, gathered from the placed capsules.
    // cap[k * stride + i]: p0 xyz, d xyz, |d|^2, 1/|d|^2, radius of capsule i.
    float* cap = cap_soa.data();
    const size_t stride = all.size() + 2;
    for (size_t i = 0; i < all.size(); ++i) {
      const Eigen::Vector3d d = world_b[i] - world_a[i];
      const double len2 = d.squaredNorm();
      const double v[9] = {world_a[i].x(), world_a[i].y(), world_a[i].z(), d.x(), d.y(), d.z(),
                           len2, len2 > 0 ? 1.0 / len2 : 0.0, all[i].radius};
      for (size_t k = 0; k < 9; ++k) cap[k * stride + i] = static_cast<float>(v[k]);
    }
    for (size_t g = 0; g < self_lanes.size(); g += 8) {
      F4 x[9], y[9];
      for (int k = 0; k < 9; ++k) {
        for (int lane = 0; lane < 4; ++lane) {
          x[k][lane] = cap[k * stride + self_lanes[g + lane]];
          y[k][lane] = cap[k * stride + self_lanes[g + 4 + lane]];
        }
      }
      if (Bits(CapsulesTouch(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], y[0], y[1], y[2],
                             y[3], y[4], y[5], y[6], y[7], x[8] + y[8]))) {
        return false;
      }
    }
    return true;
  }

  // Batched checks (VAMP's idea: configurations in SIMD lanes). Per lane and per capsule of
  // `all`: start point, axis, bounding box; lanes are configurations.
  struct PlacedLanes {
    F4 p[3], d[3], lo[3], hi[3];
  };
  std::vector<PlacedLanes> lanes_scratch;
  std::vector<float> leaf_lo, leaf_hi;  // leaf boxes, 3 floats per leaf
  // Leaf bounding capsules: q0 xyz, d xyz, |d|^2, 1/|d|^2 (0 for a sphere), radius + slack.
  std::vector<std::array<float, 9>> leaf_caps;
  std::vector<float> cap_half_reach;  // per capsule: half its length plus its radius
  std::vector<float> cap_len2, cap_inv_len2;  // per capsule of `all` (rigid: configuration-free)

  void PlaceLanes(const Joints* q, int count) {
    F4 ct[6], st[6];
    for (int i = 0; i < 6; ++i) {
      F4 v;
      for (int l = 0; l < 4; ++l) v[l] = static_cast<float>(q[std::min(l, count - 1)][i]);
      SinCos4(v, &st[i], &ct[i]);
    }
    std::array<Frame4, 7> f;
    for (int k = 0; k < 3; ++k) {
      f[0].x[k] = Splat(k == 0), f[0].y[k] = Splat(k == 1), f[0].z[k] = Splat(k == 2);
      f[0].p[k] = Splat(0.f);
    }
    for (int i = 0; i < 6; ++i) {
      const Frame4& in = f[i];
      Frame4& out = f[i + 1];
      const F4 ca = Splat(static_cast<float>(dh_ca[i])), sa = Splat(static_cast<float>(dh_sa[i]));
      const F4 a = Splat(static_cast<float>(dh_a[i])), d = Splat(static_cast<float>(dh_d[i]));
      for (int k = 0; k < 3; ++k) {
        out.x[k] = ct[i] * in.x[k] + st[i] * in.y[k];
        const F4 w = ct[i] * in.y[k] - st[i] * in.x[k];
        out.y[k] = ca * w + sa * in.z[k];
        out.z[k] = ca * in.z[k] - sa * w;
        out.p[k] = in.p[k] + a * out.x[k] + d * in.z[k];
      }
    }
    for (size_t c = 0; c < all.size(); ++c) {
      const Frame4& fr = f[all[c].frame];
      const F4 ax = Splat(all[c].a.x()), ay = Splat(all[c].a.y()), az = Splat(all[c].a.z());
      const F4 bx = Splat(all[c].b.x()), by = Splat(all[c].b.y()), bz = Splat(all[c].b.z());
      const F4 r = Splat(all[c].radius + kCoarseSlackM);
      PlacedLanes& out = lanes_scratch[c];
      for (int k = 0; k < 3; ++k) {
        const F4 pa = fr.p[k] + ax * fr.x[k] + ay * fr.y[k] + az * fr.z[k];
        const F4 pb = fr.p[k] + bx * fr.x[k] + by * fr.y[k] + bz * fr.z[k];
        out.p[k] = pa;
        out.d[k] = pb - pa;
        out.lo[k] = Min(pa, pb) - r;
        out.hi[k] = Max(pa, pb) + r;
      }
    }
  }

  ArmSeg LaneSeg(size_t c, int lane) const {
    const PlacedLanes& pl = lanes_scratch[c];
    return ArmSeg{Splat(pl.p[0][lane]), Splat(pl.p[1][lane]), Splat(pl.p[2][lane]),
                  Splat(pl.d[0][lane]), Splat(pl.d[1][lane]), Splat(pl.d[2][lane]),
                  Splat(cap_len2[c]), Splat(cap_inv_len2[c]), Splat(all[c].radius), QueryBox{}};
  }

  // Lanes (of `lanes`) where capsule c touches an obstacle piece. The hierarchy is walked once
  // with the union of the lanes' boxes (lanes should be nearby configurations); leaves are then
  // tested per lane. With `stop_at_first`, returns after the first colliding lane.
  unsigned CapsuleLanesHit(size_t c, unsigned lanes, bool stop_at_first) const {
    const PlacedLanes& pl = lanes_scratch[c];
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::numeric_limits<float>::infinity(), hi[k] = -lo[k];
      for (unsigned m = lanes; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        lo[k] = std::min(lo[k], pl.lo[k][l]);
        hi[k] = std::max(hi[k], pl.hi[k][l]);
      }
    }
    const QueryBox box{Splat(lo[0]), Splat(lo[1]), Splat(lo[2]),
                       Splat(hi[0]), Splat(hi[1]), Splat(hi[2])};
    std::array<ArmSeg, 4> segs;
    unsigned prepared = 0, hit = 0;
    for (size_t g = 0; g < top.size(); ++g) {
      unsigned nodes = SegVsBoxes(box, top[g]);
      while (nodes) {
        const int n = static_cast<int>(g) * kLeaf + __builtin_ctz(nodes);
        nodes &= nodes - 1;
        unsigned ls = SegVsBoxes(box, node_children[n]);
        while (ls) {
          const int leaf = n * kLeaf + __builtin_ctz(ls);
          ls &= ls - 1;
          unsigned todo = LanesOverlap(pl.lo, pl.hi, &leaf_lo[3 * leaf], &leaf_hi[3 * leaf]) &
                          lanes & ~hit;
          if (!todo) continue;
          // The leaf's bounding capsule against all lanes at once.
          const std::array<float, 9>& lb = leaf_caps[leaf];
          todo &= Bits(CapsulesTouch(pl.p[0], pl.p[1], pl.p[2], pl.d[0], pl.d[1], pl.d[2],
                                     Splat(cap_len2[c]), Splat(cap_inv_len2[c]), Splat(lb[0]),
                                     Splat(lb[1]), Splat(lb[2]), Splat(lb[3]), Splat(lb[4]),
                                     Splat(lb[5]), Splat(lb[6]), Splat(lb[7]),
                                     Splat(lb[8] + all[c].radius)));
          while (todo) {
            const int l = __builtin_ctz(todo);
            todo &= todo - 1;
            if (!(prepared >> l & 1u)) segs[l] = LaneSeg(c, l), prepared |= 1u << l;
            if (SegVsSet(segs[l], leaves[leaf])) {
              hit |= 1u << l;
              if (stop_at_first || hit == lanes) return hit;
            }
          }
        }
      }
    }
    return hit;
  }

  // Lanes (of the first `count` configurations q[0..count), count <= 4) that are not free.
  // `coherent`: the configurations are close together (consecutive samples of a motion), so the
  // obstacle hierarchy is walked once for all lanes; otherwise once per lane. `stop_at_first`:
  // return as soon as one lane is known to collide (the others are then unspecified).
  unsigned CollidingLanes(const Joints* q, int count, bool coherent, bool stop_at_first) {
    const unsigned all_lanes = (1u << count) - 1;
    if (base_blocked) return all_lanes;
    PlaceLanes(q, count);
    unsigned hit = 0;
    for (size_t c = 0; c < moving.size(); ++c) {
      const PlacedLanes& pl = lanes_scratch[c];
      const F4 r = Splat(all[c].radius);
      for (const HalfSpace& h : planes_of[c]) {
        const F4 nx = Splat(h.normal.x()), ny = Splat(h.normal.y()), nz = Splat(h.normal.z());
        const F4 da = nx * pl.p[0] + ny * pl.p[1] + nz * pl.p[2];
        const F4 db = da + nx * pl.d[0] + ny * pl.d[1] + nz * pl.d[2];
        hit |= Bits(Max(da, db) + r + Splat(h.margin_m) > Splat(h.offset)) & all_lanes;
      }
      if (hit && stop_at_first) return hit;
    }
    for (size_t c = 0; c < moving.size(); ++c) {
      const unsigned open = all_lanes & ~hit;
      if (!open) return hit;
      if (coherent) {
        hit |= CapsuleLanesHit(c, open, stop_at_first);
      } else {
        for (unsigned m = open; m; m &= m - 1) {
          hit |= CapsuleLanesHit(c, m & (~m + 1), stop_at_first);
          if (hit && stop_at_first) return hit;
        }
      }
      if (hit && stop_at_first) return hit;
    }
    // Self-collision pairs, one pair at a time across the lanes.
    for (const auto& [i, j] : self_pairs) {
      const PlacedLanes& x = lanes_scratch[i];
      const PlacedLanes& y = lanes_scratch[j];
      // Bounding spheres about the midpoints first: most pairs are far apart.
      F4 gap2 = Splat(0.f);
      for (int k = 0; k < 3; ++k) {
        const F4 g = (x.p[k] + Splat(0.5f) * x.d[k]) - (y.p[k] + Splat(0.5f) * y.d[k]);
        gap2 += g * g;
      }
      const F4 reach = Splat(cap_half_reach[i] + cap_half_reach[j]);
      if (!(Bits(gap2 < reach * reach) & all_lanes & ~hit)) continue;
      hit |= Bits(CapsulesTouch(x.p[0], x.p[1], x.p[2], x.d[0], x.d[1], x.d[2],
                                Splat(cap_len2[i]), Splat(cap_inv_len2[i]), y.p[0], y.p[1],
                                y.p[2], y.d[0], y.d[1], y.d[2], Splat(cap_len2[j]),
                                Splat(cap_inv_len2[j]), Splat(all[i].radius + all[j].radius))) &
             all_lanes;
      if (hit && stop_at_first) return hit;
    }
    return hit;
  }

  double SegClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                      double best) const {
    for (const HalfSpace& h : planes) {
      best = std::min(best, h.offset - std::max(h.normal.dot(a), h.normal.dot(b)) - r - h.margin_m);
    }
    for (size_t l = 0; l < leaf_bounds.size(); ++l) {
      const double lower = CapsuleCapsuleGap(a, b, r, leaf_bounds[l].a, leaf_bounds[l].b,
                                             leaf_bounds[l].radius);
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
  lever_m_ = JointLeverArms(robot);
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
  m.lanes_scratch.resize(caps.size());
  for (const ArmCapsule& c : caps) {
    const double len2 = (c.b - c.a).squaredNorm();
    m.cap_len2.push_back(static_cast<float>(len2));
    m.cap_inv_len2.push_back(len2 > 0 ? static_cast<float>(1.0 / len2) : 0.f);
    m.cap_half_reach.push_back(static_cast<float>(0.5 * std::sqrt(len2) + c.radius + kCoarseSlackM));
  }
  for (const auto& [bi, bj] : robot.SelfCollisionPairs()) {
    for (int i : capsules_of[bi]) {
      for (int j : capsules_of[bj]) m.self_pairs.emplace_back(i, j);
    }
  }
  // Padding lanes pair two points far apart (the two slots after the real capsules).
  const int n_caps = static_cast<int>(caps.size());
  m.cap_soa.assign(9 * (n_caps + 2), 0.f);
  m.cap_soa[n_caps] = kFarAway;
  m.cap_soa[n_caps + 1] = -kFarAway;
  std::vector<std::pair<int, int>> padded = m.self_pairs;
  while (padded.size() % 4 != 0) padded.emplace_back(n_caps, n_caps + 1);
  for (size_t g = 0; g < padded.size(); g += 4) {
    for (size_t k = 0; k < 4; ++k) m.self_lanes.push_back(padded[g + k].first);
    for (size_t k = 0; k < 4; ++k) m.self_lanes.push_back(padded[g + k].second);
  }
  m.planes = scene.planes;
  // A capsule reaches plane n . x <= offset only if its reach cylinder about the base axis
  // (ReachOfPoint of both ends, plus the radius) does: max over the cylinder of n . x is
  // radius |n_xy| + max(n_z lo, n_z hi).
  for (const ArmCapsule& c : m.all) {
    const ReachCylinder ra = ReachOfPoint(c.frame, c.a), rb = ReachOfPoint(c.frame, c.b);
    const double rho = std::max(ra.radius_m, rb.radius_m);
    const double lo = std::min(ra.lo_z_m, rb.lo_z_m), hi = std::max(ra.hi_z_m, rb.hi_z_m);
    m.planes_of.emplace_back();
    for (const HalfSpace& h : m.planes) {
      const double farthest = rho * std::hypot(h.normal.x(), h.normal.y()) +
                              std::max(h.normal.z() * lo, h.normal.z() * hi);
      if (farthest + c.radius + h.margin_m + kCoarseSlackM > h.offset) m.planes_of.back().push_back(h);
    }
  }

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
    CapsuleSet leaf;
    for (int k = 0; k < kLeaf; ++k) {
      const bool real = begin + k < end;
      const Piece& p = m.pieces[real ? begin + k : begin];
      SetCapsule(leaf, k, real, p.a, p.b, p.rad);
    }
    m.leaves.push_back(leaf);
  }
  std::vector<Box> leaf_boxes, node_boxes;
  for (int l = 0; l < n_leaves; ++l) {
    leaf_boxes.push_back(BoxOfPieces(m.pieces, l * kLeaf, std::min(n_pieces, (l + 1) * kLeaf)));
  }
  for (const Bound& b : m.leaf_bounds) {
    const Eigen::Vector3d d = b.b - b.a;
    const double e = d.squaredNorm();
    m.leaf_caps.push_back({static_cast<float>(b.a.x()), static_cast<float>(b.a.y()),
                           static_cast<float>(b.a.z()), static_cast<float>(d.x()),
                           static_cast<float>(d.y()), static_cast<float>(d.z()),
                           static_cast<float>(e), e > 0 ? static_cast<float>(1.0 / e) : 0.f,
                           static_cast<float>(b.radius + kCoarseSlackM)});
  }
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

  // The base never moves: decide once whether it touches anything.
  for (const ArmCapsule& c : m.fixed) {
    if (m.SegClearance(c.a, c.b, c.radius, std::numeric_limits<double>::infinity()) < 0) {
      m.base_blocked = true;
    }
  }
}

PrimitiveChecker::~PrimitiveChecker() = default;

namespace {
// Non-finite or absurd joint values are never free (the float lanes would wrap them silently).
bool Sane(const Joints& q) { return q.allFinite() && !(q.array().abs() > 1e6).any(); }
}  // namespace

bool PrimitiveChecker::IsFree(const Joints& q) {
  ++checks_;
  return Sane(q) && impl_->Free(q);
}

void PrimitiveChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  const size_t n = std::min(qs.size(), out.size());
  checks_ += static_cast<int64_t>(n);
  // Arbitrary configurations: forward kinematics in lanes, the hierarchy walked per lane.
  for (size_t i = 0; i < n; i += 4) {
    const int count = static_cast<int>(std::min<size_t>(4, n - i));
    const unsigned hit = impl_->CollidingLanes(&qs[i], count, /*coherent=*/false,
                                               /*stop_at_first=*/false);
    for (int l = 0; l < count; ++l) out[i + l] = !(hit >> l & 1u) && Sane(qs[i + l]);
  }
}

bool PrimitiveChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  if (!Sane(a) || !Sane(b)) return false;
  const int n = MotionSteps(a, b, max_step_m, lever_m_);
  // The ends first (one batch), then the n - 1 interior samples in blocks of 4 consecutive ones
  // (nearby configurations share one walk of the obstacle hierarchy), the blocks in van der
  // Corput order (coarse to fine) so that a colliding motion usually fails early.
  const Joints ends[2] = {a, b};
  checks_ += 2;
  if (impl_->CollidingLanes(ends, 2, /*coherent=*/false, /*stop_at_first=*/true)) return false;
  const int interior = n - 1;
  const int blocks = (interior + 3) / 4;
  int bits = 0;
  while ((1 << bits) < blocks) ++bits;
  const Joints step = (b - a) / n;
  Joints q[4];
  for (uint32_t i = 0; i < (1u << bits); ++i) {
    uint32_t block = 0;
    for (int k = 0; k < bits; ++k) block |= ((i >> k) & 1u) << (bits - 1 - k);
    if (static_cast<int>(block) >= blocks) continue;
    const int first = 4 * static_cast<int>(block) + 1;
    const int count = std::min(4, n - first);
    for (int l = 0; l < count; ++l) q[l] = a + step * (first + l);
    checks_ += count;
    if (impl_->CollidingLanes(q, count, /*coherent=*/true, /*stop_at_first=*/true)) return false;
  }
  return true;
}

double PrimitiveChecker::Clearance(const Joints& q) {
  ++checks_;
  if (!Sane(q)) return -std::numeric_limits<double>::infinity();
  return impl_->Clearance(q);
}

int PrimitiveChecker::pieces() const { return static_cast<int>(impl_->pieces.size()); }
int PrimitiveChecker::leaves() const { return static_cast<int>(impl_->leaves.size()); }

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel& robot,
                                                      const CollisionScene& scene) {
  return std::make_unique<PrimitiveChecker>(robot, scene);
}

}  // namespace vb::plan
