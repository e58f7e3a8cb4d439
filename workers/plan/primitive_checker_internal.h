// SPDX-License-Identifier: Apache-2.0
// Internal to the primitive checker (primitive_checker.cc builds the arm and checks one
// configuration; primitive_checker_hierarchy.cc builds the obstacle hierarchy and excludes
// obstacles; primitive_checker_batch.cc checks configurations in SIMD lanes): the float lanes,
// the exact capsule test, the lane sincos, and PrimitiveChecker::Impl. Not for other users.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "Eigen/Geometry"

#include "workers/plan/primitive_checker.h"

namespace vb::plan::prim {

// Four float lanes: SSE2 on x86-64, NEON on arm64, scalar code elsewhere. Leaves hold 8
// obstacles, processed as two halves.
typedef float F4 __attribute__((vector_size(16)));
typedef int32_t I4 __attribute__((vector_size(16)));
// Eight float lanes: only computed in code compiled for AVX2 (primitive_checker_batch.cc). The
// alignment is explicit: without AVX, GCC would align them to 16 bytes only, and the AVX2 code
// loads them with aligned 32-byte moves.
typedef float F8 __attribute__((vector_size(32), aligned(32)));
typedef int32_t I8 __attribute__((vector_size(32), aligned(32)));
constexpr int kLeaf = 8;
constexpr int kHalves = kLeaf / 4;
// Padding lanes sit here with radius 0: never within reach of the arm.
constexpr float kFarAway = 1e6f;
// Coarse spheres are inflated by this so that float rounding never culls a real contact.
constexpr double kCoarseSlackM = 1e-4;
// Every float test against the exact geometry (arm capsule against obstacle piece or plane, self
// pairs in lanes) pads the arm's radius by this, so that float rounding can only make a check
// conservative. The rounding it covers: positions < 2 m from the base carry ~1e-7 m per float
// operation, a few 1e-7 m after the six frames of forward kinematics plus ~1.3e-7 m per joint from
// the float sincos (error ~1e-7 rad, lever < 1.3 m); the squared distance of two segments
// (terms < 4 m^2) carries ~2.4e-7 m^2, i.e. ~1.2e-6 m at a contact distance of 0.1 m. Together
// < 3e-6 m; PrimitiveChecker.NeverFreeInContact checks configurations bisected to within 1e-9 m
// of contact.
constexpr double kFloatPadM = 1e-5;

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

inline ArmSeg PrepareSeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) {
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

// V splatted from a float, and clamped to [0, 1], for any lane count.
template <class V>
inline V SplatV(float v) {
  return V{} + v;
}
template <class V>
inline V Clamp01V(V x) {
  const V zero = SplatV<V>(0.f), one = SplatV<V>(1.f);
  x = x > zero ? x : zero;
  return x < one ? x : one;
}

// Lanes where capsule (p0 + s d1, s in [0, 1]) comes within rr of capsule (q0 + t d2): closest
// points of two segments (Ericson, Real-Time Collision Detection, 5.1.9), branch-free. a = |d1|^2,
// e = |d2|^2, inv_* their inverses or 0 for a sphere. V: F4 or F8 (8 lanes, in AVX2 code).
template <class V, class M>
inline M CapsulesTouchT(V p0x, V p0y, V p0z, V d1x, V d1y, V d1z, V a, V inv_a, V q0x, V q0y,
                        V q0z, V d2x, V d2y, V d2z, V e, V inv_e, V rr) {
  const V rx = p0x - q0x, ry = p0y - q0y, rz = p0z - q0z;
  const V b = d1x * d2x + d1y * d2y + d1z * d2z;
  const V c = d1x * rx + d1y * ry + d1z * rz;
  const V f = d2x * rx + d2y * ry + d2z * rz;
  const V denom = a * e - b * b;
  const M skew = denom > SplatV<V>(1e-12f);
  V sp = skew ? Clamp01V((b * f - c * e) / (skew ? denom : SplatV<V>(1.f))) : SplatV<V>(0.f);
  // A sphere second (e = 0): the closest point of the first segment to its centre.
  sp = e > SplatV<V>(0.f) ? sp : Clamp01V(-c * inv_a);
  const V tn = (b * sp + f) * inv_e;
  const V s_lo = Clamp01V(-c * inv_a), s_hi = Clamp01V((b - c) * inv_a);
  sp = tn < SplatV<V>(0.f) ? s_lo : (tn > SplatV<V>(1.f) ? s_hi : sp);
  const V t = Clamp01V(tn);
  const V ex = rx + d1x * sp - d2x * t;
  const V ey = ry + d1y * sp - d2y * t;
  const V ez = rz + d1z * sp - d2z * t;
  return ex * ex + ey * ey + ez * ez < rr * rr;
}

inline I4 CapsulesTouch(F4 p0x, F4 p0y, F4 p0z, F4 d1x, F4 d1y, F4 d1z, F4 a, F4 inv_a, F4 q0x,
                        F4 q0y, F4 q0z, F4 d2x, F4 d2y, F4 d2z, F4 e, F4 inv_e, F4 rr) {
  return CapsulesTouchT<F4, I4>(p0x, p0y, p0z, d1x, d1y, d1z, a, inv_a, q0x, q0y, q0z, d2x, d2y,
                                d2z, e, inv_e, rr);
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

// Whether arm segment s touches any capsule of `set`, the 8 in one 8-lane test: one AVX stream in
// code compiled for AVX2 (IsFree's AVX2 variant), two SSE halves otherwise.
inline bool SegTouchesSet8(const ArmSeg& s, const CapsuleSet& l) {
  const auto wide = [](F4 x) { return F8(__builtin_shufflevector(x, x, 0, 1, 2, 3, 0, 1, 2, 3)); };
  const auto load = [](const F4* v) {
    F8 out;
    __builtin_memcpy(&out, v, sizeof(out));
    return out;
  };
  const I8 touch = CapsulesTouchT<F8, I8>(
      wide(s.p0x), wide(s.p0y), wide(s.p0z), wide(s.d1x), wide(s.d1y), wide(s.d1z), wide(s.a),
      wide(s.inv_a), load(l.q0x), load(l.q0y), load(l.q0z), load(l.dx), load(l.dy), load(l.dz),
      load(l.e), load(l.inv_e), wide(s.r) + load(l.rad));
  const I4 any = __builtin_shufflevector(touch, touch, 0, 1, 2, 3) |
                 __builtin_shufflevector(touch, touch, 4, 5, 6, 7);
  return Bits(any) != 0;
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

// An obstacle piece (a capsule; a sphere when a == b).
struct Piece {
  Eigen::Vector3d a, b;
  double rad;  // radius + margin
};

// A bounding capsule (a sphere when a == b).
struct Bound {
  Eigen::Vector3d a, b;
  double radius;
};

// The ball about a capsule's centre that holds it (reach = half its axis + its radius): Clearance
// skips a capsule pair without their segment distance when the balls are far enough apart.
struct Ball {
  Eigen::Vector3d centre;
  double reach;
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

// Per capsule of PrimitiveChecker::Impl::all, across 4 or 8 lanes (configurations): start
// point, axis, bounding box (inflated by kCoarseSlackM), midpoint.
struct PlacedLanes4 {
  F4 p[3], d[3], lo[3], hi[3], mid[3];
};
struct alignas(32) PlacedLanes8 {
  F8 p[3], d[3], lo[3], hi[3], mid[3];
};

}  // namespace vb::plan::prim

namespace vb::plan {

// The checker's state, built once by the constructor (primitive_checker.cc, the obstacles by
// BuildObstacles) and read by every check; the scratch members make it thread-compatible only.
struct PrimitiveChecker::Impl {
  using ArmCapsule = prim::ArmCapsule;
  using Frame = prim::Frame;
  std::array<double, 6> dh_a{}, dh_d{}, dh_ca{}, dh_sa{};
  std::vector<ArmCapsule> moving;   // frame > 0, distal first (most likely to touch the vine)
  std::vector<ArmCapsule> fixed;    // frame 0
  // Capsule pairs (indices into `all`, the capsules in body order) that must not touch.
  std::vector<ArmCapsule> all;
  std::vector<std::pair<int, int>> self_pairs;
  std::vector<HalfSpace> planes;
  // planes_of[c]: the planes capsule c of `all` can reach in some configuration (per-link reach
  // culling, Botterill et al. 2017 section 3.4: the others are never tested for it).
  std::vector<std::vector<HalfSpace>> planes_of;
  bool base_blocked = false;
  double base_clearance = 0;  // the base's (frame 0) gap to the obstacles and planes

  // The obstacle hierarchy below from `scene`'s obstacles (primitive_checker_hierarchy.cc): its
  // pieces, their leaf order, bounds, balls and boxes, obstacle_pieces; nothing excluded.
  void BuildObstacles(const CollisionScene& scene);
  std::vector<prim::Piece> pieces;        // in leaf order
  // Exclude(): the pieces of each obstacle of the scene, which pieces are left out, and which
  // obstacles (their lanes in `leaves` are padding lanes while they are).
  std::vector<std::vector<int>> obstacle_pieces;
  std::vector<char> piece_excluded;
  std::vector<int> excluded;
  std::vector<Eigen::AlignedBox3d> leaf_boxes;  // the leaves' boxes (double), for refitting
  void UpdateBaseBlocked();  // base_blocked for the obstacles not excluded
  std::vector<prim::Bound> leaf_bounds;   // one per leaf
  std::vector<prim::Ball> piece_balls, leaf_balls;  // about pieces and leaf_bounds (Clearance)
  std::vector<prim::CapsuleSet> leaves;
  std::vector<prim::BoxSet> node_children;  // per node: its leaves' boxes
  std::vector<prim::BoxSet> top;            // per group of 8 nodes: the nodes' boxes

  // Per-configuration scratch: the base-frame ends of every capsule in `all`.
  std::vector<Eigen::Vector3d> world_a, world_b;

  // One configuration, in double (primitive_checker.cc).
  // `float_trig`: sines and cosines from SinCos4 (error ~1e-7, for IsFree, whose obstacle tests
  // are in float anyway) instead of libm's (for Clearance, exact in double).
  void Fk(const Joints& q, std::array<Frame, 7>& f, bool float_trig) const;
  void Place(const Joints& q, bool float_trig);
  // kWide: leaves tested 8 pieces at once (SegTouchesSet8; for the AVX2 variant).
  template <bool kWide>
  bool SegHitsObstacles(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) const;
  bool SegHitsPlanes(size_t c, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                     double r) const;
  template <bool kWide>
  bool Free(const Joints& q);
  // *nearest (if given) receives the piece that lowered `best` last (unchanged if none did).
  double SegClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                      double best, int* nearest = nullptr) const;
  // min(cap, clearance at q) if above `floor`, else some value <= floor (returns early).
  double Clearance(const Joints& q, double floor, double cap);
  // The arm capsule and piece that gave a recent Clearance its value, or -1 (none found below
  // the cap yet, or the piece was excluded). When a plane or self pair is nearest, or a query
  // ends early, the previous pair may stay: it is only a warm start. Consecutive queries are mostly nearby configurations with the same nearest pair:
  // its gap, computed first, starts the branch-and-bound low (an exact upper bound either way).
  int last_capsule = -1, last_piece = -1;

  // Batched checks (primitive_checker_batch.cc; VAMP's idea: configurations in SIMD lanes).
  std::vector<float> leaf_lo, leaf_hi;  // leaf boxes, 3 floats per leaf
  // Leaf bounding capsules: q0 xyz, d xyz, |d|^2, 1/|d|^2 (0 for a sphere), radius + slack.
  std::vector<std::array<float, 9>> leaf_caps;
  std::vector<float> cap_half_reach;  // per capsule: half its length plus its radius
  std::vector<float> cap_len2, cap_inv_len2;  // per capsule of `all` (rigid: configuration-free)
  // Scratch: the capsules of `all` placed in 4 or 8 lanes.
  std::vector<prim::PlacedLanes4> lanes4;
  std::vector<prim::PlacedLanes8> lanes8;

  // The lanes (of the first `count` configurations q[0..count), count <= lane_width) that are
  // not free. `coherent`: the configurations are close together (consecutive samples of a
  // motion), so the obstacle hierarchy is walked once for all lanes; otherwise once per lane.
  // `stop_at_first`: return as soon as one lane is known to collide (the others are then
  // unspecified). Compiled for the running CPU: 8 lanes with AVX2 and FMA where it has them
  // (x86-64, checked at run time; the library itself is built for the baseline ISA), else 4 lanes
  // of the baseline (SSE2 on x86-64, NEON on arm64). Set by the constructor (SelectLanes).
  using LanesFn = unsigned (*)(Impl&, const Joints*, int, bool, bool);
  LanesFn colliding_lanes = nullptr;
  int lane_width = 4;
  // Free compiled the same two ways (primitive_checker.cc, SelectFree).
  using FreeFn = bool (*)(Impl&, const Joints&);
  FreeFn free_fn = nullptr;
  bool lanes_avx2 = false;
  void SelectLanes(bool allow_avx2);
  void SelectFree(bool allow_avx2);
};

// True on an x86-64 CPU with AVX2 and FMA (the checker's fast code paths).
inline bool CpuHasAvx2Fma() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();  // a checker may be built before libgcc's own initialiser has run
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

// Non-finite or absurd joint values are never free (the float lanes would wrap them silently).
inline bool SaneJoints(const Joints& q) { return q.allFinite() && !(q.array().abs() > 1e6).any(); }

}  // namespace vb::plan
