// SPDX-License-Identifier: Apache-2.0
// The primitive checker's batched checks (VAMP, Thomason, Kingston, Kavraki ICRA 2024:
// configurations in SIMD lanes): AreFree and IsMotionFree, W configurations at a time. The code
// is written once for W lanes and compiled twice: W = 4 for the baseline ISA (SSE2 / NEON) and
// W = 8 for AVX2 + FMA, chosen at run time (SelectLanes).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "workers/plan/primitive_checker.h"

// The 8-lane functions are only ever inlined into the AVX2 entry point (flatten), so the note
// that passing 32-byte vectors without AVX changes the ABI does not apply.
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#include "workers/plan/primitive_checker_internal.h"

namespace vb::plan {
namespace {

using namespace prim;
using Impl = PrimitiveChecker::Impl;

template <int W>
struct Lanes;
template <>
struct Lanes<4> {
  using V = F4;
  using M = I4;
  using Placed = PlacedLanes4;
  static Placed* Scratch(Impl& m) { return m.lanes4.data(); }
  static unsigned ToBits(M m) { return Bits(m); }
  // Half h (0 or 1) of 8 leaf lanes.
  static V Leaf(const F4* v, int h) { return v[h]; }
};
template <>
struct Lanes<8> {
  using V = F8;
  using M = I8;
  using Placed = PlacedLanes8;
  static Placed* Scratch(Impl& m) { return m.lanes8.data(); }
  static unsigned ToBits(M m) {
    const I4 lo = __builtin_shufflevector(m, m, 0, 1, 2, 3);
    const I4 hi = __builtin_shufflevector(m, m, 4, 5, 6, 7);
    return Bits(lo) | Bits(hi) << 4;
  }
  static V Leaf(const F4* v, int /*h*/) {
    V out;
    __builtin_memcpy(&out, v, sizeof(out));
    return out;
  }
};

// SinCos4 of primitive_checker_internal.h, for any lane count.
template <class V, class M>
inline void SinCosV(V x, V* s, V* c) {
  const V jf = __builtin_convertvector(
      __builtin_convertvector(x * SplatV<V>(0.63661977236758134f) +
                                  (x >= SplatV<V>(0.f) ? SplatV<V>(0.5f) : SplatV<V>(-0.5f)), M),
      V);
  const M quadrant = __builtin_convertvector(jf, M) & (M{} + 3);
  const V y = ((x - jf * SplatV<V>(1.5703125f)) - jf * SplatV<V>(4.837512969970703125e-4f)) -
              jf * SplatV<V>(7.54978995489188216e-8f);
  const V z = y * y;
  const V sy = y + y * z * (SplatV<V>(-1.6666654611e-1f) +
                            z * (SplatV<V>(8.3321608736e-3f) + z * SplatV<V>(-1.9515295891e-4f)));
  const V cy = SplatV<V>(1.f) - SplatV<V>(0.5f) * z +
               z * z * (SplatV<V>(4.166664568298827e-2f) +
                        z * (SplatV<V>(-1.388731625493765e-3f) + z * SplatV<V>(2.443315711809948e-5f)));
  const M swap = (quadrant & (M{} + 1)) != M{};
  const M neg_s = (quadrant == (M{} + 2)) | (quadrant == (M{} + 3));
  const M neg_c = (quadrant == (M{} + 1)) | (quadrant == (M{} + 2));
  const V ss = swap ? cy : sy, cc = swap ? sy : cy;
  *s = neg_s ? -ss : ss;
  *c = neg_c ? -cc : cc;
}

// Forward kinematics of q[0..count) in W lanes (lanes past count repeat the last configuration),
// and every capsule of `all` placed.
template <int W>
void PlaceLanes(Impl& m, const Joints* q, int count) {
  using V = typename Lanes<W>::V;
  using M = typename Lanes<W>::M;
  V ct[6], st[6];
  for (int i = 0; i < 6; ++i) {
    V v;
    for (int l = 0; l < W; ++l) v[l] = static_cast<float>(q[std::min(l, count - 1)][i]);
    SinCosV<V, M>(v, &st[i], &ct[i]);
  }
  struct FrameW {
    V x[3], y[3], z[3], p[3];
  };
  std::array<FrameW, 7> f;
  for (int k = 0; k < 3; ++k) {
    f[0].x[k] = SplatV<V>(k == 0), f[0].y[k] = SplatV<V>(k == 1), f[0].z[k] = SplatV<V>(k == 2);
    f[0].p[k] = SplatV<V>(0.f);
  }
  for (int i = 0; i < 6; ++i) {
    const FrameW& in = f[i];
    FrameW& out = f[i + 1];
    const V ca = SplatV<V>(static_cast<float>(m.dh_ca[i]));
    const V sa = SplatV<V>(static_cast<float>(m.dh_sa[i]));
    const V a = SplatV<V>(static_cast<float>(m.dh_a[i])), d = SplatV<V>(static_cast<float>(m.dh_d[i]));
    for (int k = 0; k < 3; ++k) {
      out.x[k] = ct[i] * in.x[k] + st[i] * in.y[k];
      const V w = ct[i] * in.y[k] - st[i] * in.x[k];
      out.y[k] = ca * w + sa * in.z[k];
      out.z[k] = ca * in.z[k] - sa * w;
      out.p[k] = in.p[k] + a * out.x[k] + d * in.z[k];
    }
  }
  typename Lanes<W>::Placed* placed = Lanes<W>::Scratch(m);
  for (size_t c = 0; c < m.all.size(); ++c) {
    const ArmCapsule& cap = m.all[c];
    const FrameW& fr = f[cap.frame];
    const V ax = SplatV<V>(cap.a.x()), ay = SplatV<V>(cap.a.y()), az = SplatV<V>(cap.a.z());
    const V bx = SplatV<V>(cap.b.x()), by = SplatV<V>(cap.b.y()), bz = SplatV<V>(cap.b.z());
    const V r = SplatV<V>(cap.radius + kCoarseSlackM);
    auto& out = placed[c];
    for (int k = 0; k < 3; ++k) {
      const V pa = fr.p[k] + ax * fr.x[k] + ay * fr.y[k] + az * fr.z[k];
      const V pb = fr.p[k] + bx * fr.x[k] + by * fr.y[k] + bz * fr.z[k];
      out.p[k] = pa;
      out.d[k] = pb - pa;
      out.lo[k] = (pa < pb ? pa : pb) - r;
      out.hi[k] = (pa > pb ? pa : pb) + r;
      out.mid[k] = SplatV<V>(0.5f) * (pa + pb);
    }
  }
}

// Lane `lane` of capsule c against the 8 pieces of leaf `leaf`.
template <int W>
struct LaneSeg {
  using V = typename Lanes<W>::V;
  V p0x, p0y, p0z, d1x, d1y, d1z, a, inv_a, r;
};

template <int W>
inline bool SegTouchesLeaf(const LaneSeg<W>& s, const CapsuleSet& l) {
  using V = typename Lanes<W>::V;
  using M = typename Lanes<W>::M;
  for (int h = 0; h < 8 / W; ++h) {
    if (Lanes<W>::ToBits(CapsulesTouchT<V, M>(s.p0x, s.p0y, s.p0z, s.d1x, s.d1y, s.d1z, s.a, s.inv_a,
                                     Lanes<W>::Leaf(l.q0x, h), Lanes<W>::Leaf(l.q0y, h),
                                     Lanes<W>::Leaf(l.q0z, h), Lanes<W>::Leaf(l.dx, h),
                                     Lanes<W>::Leaf(l.dy, h), Lanes<W>::Leaf(l.dz, h),
                                     Lanes<W>::Leaf(l.e, h), Lanes<W>::Leaf(l.inv_e, h),
                                     s.r + Lanes<W>::Leaf(l.rad, h)))) {
      return true;
    }
  }
  return false;
}

// Lanes (of `lanes`) where capsule c touches an obstacle piece. The hierarchy is walked once
// with the union of the lanes' boxes (lanes should be nearby configurations); leaves are then
// culled per lane by box, across the lanes by the leaf's bounding capsule, and tested per lane.
// With `stop_at_first`, returns after the first colliding lane.
template <int W>
unsigned CapsuleLanesHit(Impl& m, size_t c, unsigned lanes, bool stop_at_first) {
  using V = typename Lanes<W>::V;
  using M = typename Lanes<W>::M;
  const auto& pl = Lanes<W>::Scratch(m)[c];
  float lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<float>::infinity(), hi[k] = -lo[k];
    for (unsigned bits = lanes; bits; bits &= bits - 1) {
      const int l = __builtin_ctz(bits);
      lo[k] = std::min(lo[k], pl.lo[k][l]);
      hi[k] = std::max(hi[k], pl.hi[k][l]);
    }
  }
  const QueryBox box{Splat(lo[0]), Splat(lo[1]), Splat(lo[2]),
                     Splat(hi[0]), Splat(hi[1]), Splat(hi[2])};
  const float radius = static_cast<float>(m.all[c].radius + kFloatPadM);
  const V len2 = SplatV<V>(m.cap_len2[c]), inv_len2 = SplatV<V>(m.cap_inv_len2[c]);
  unsigned hit = 0;
  for (size_t g = 0; g < m.top.size(); ++g) {
    unsigned nodes = SegVsBoxes(box, m.top[g]);
    while (nodes) {
      const int n = static_cast<int>(g) * kLeaf + __builtin_ctz(nodes);
      nodes &= nodes - 1;
      unsigned ls = SegVsBoxes(box, m.node_children[n]);
      while (ls) {
        const int leaf = n * kLeaf + __builtin_ctz(ls);
        ls &= ls - 1;
        const float* blo = &m.leaf_lo[3 * leaf];
        const float* bhi = &m.leaf_hi[3 * leaf];
        unsigned todo =
            Lanes<W>::ToBits((pl.lo[0] <= SplatV<V>(bhi[0])) & (pl.hi[0] >= SplatV<V>(blo[0])) &
                             (pl.lo[1] <= SplatV<V>(bhi[1])) & (pl.hi[1] >= SplatV<V>(blo[1])) &
                             (pl.lo[2] <= SplatV<V>(bhi[2])) & (pl.hi[2] >= SplatV<V>(blo[2]))) &
            lanes & ~hit;
        if (!todo) continue;
        // The leaf's bounding capsule against all lanes at once.
        const std::array<float, 9>& lb = m.leaf_caps[leaf];
        todo &= Lanes<W>::ToBits(CapsulesTouchT<V, M>(
            pl.p[0], pl.p[1], pl.p[2], pl.d[0], pl.d[1], pl.d[2], len2, inv_len2,
            SplatV<V>(lb[0]), SplatV<V>(lb[1]), SplatV<V>(lb[2]), SplatV<V>(lb[3]),
            SplatV<V>(lb[4]), SplatV<V>(lb[5]), SplatV<V>(lb[6]), SplatV<V>(lb[7]),
            SplatV<V>(lb[8] + radius)));
        while (todo) {
          const int l = __builtin_ctz(todo);
          todo &= todo - 1;
          const LaneSeg<W> s{SplatV<V>(pl.p[0][l]), SplatV<V>(pl.p[1][l]), SplatV<V>(pl.p[2][l]),
                             SplatV<V>(pl.d[0][l]), SplatV<V>(pl.d[1][l]), SplatV<V>(pl.d[2][l]),
                             len2, inv_len2, SplatV<V>(radius)};
          if (SegTouchesLeaf<W>(s, m.leaves[leaf])) {
            hit |= 1u << l;
            if (stop_at_first || hit == lanes) return hit;
          }
        }
      }
    }
  }
  return hit;
}

template <int W>
unsigned CollidingLanes(Impl& m, const Joints* q, int count, bool coherent, bool stop_at_first) {
  using V = typename Lanes<W>::V;
  using M = typename Lanes<W>::M;
  const unsigned all_lanes = (1u << count) - 1;
  if (m.base_blocked) return all_lanes;
  PlaceLanes<W>(m, q, count);
  const auto* placed = Lanes<W>::Scratch(m);
  unsigned hit = 0;
  for (size_t c = 0; c < m.moving.size(); ++c) {
    const auto& pl = placed[c];
    const V r = SplatV<V>(m.all[c].radius + kFloatPadM);
    for (const HalfSpace& h : m.planes_of[c]) {
      const V nx = SplatV<V>(h.normal.x()), ny = SplatV<V>(h.normal.y());
      const V nz = SplatV<V>(h.normal.z());
      const V da = nx * pl.p[0] + ny * pl.p[1] + nz * pl.p[2];
      const V db = da + nx * pl.d[0] + ny * pl.d[1] + nz * pl.d[2];
      hit |= Lanes<W>::ToBits((da > db ? da : db) + r + SplatV<V>(h.margin_m) >
                              SplatV<V>(h.offset)) &
             all_lanes;
    }
    if (hit && stop_at_first) return hit;
  }
  for (size_t c = 0; c < m.moving.size(); ++c) {
    const unsigned open = all_lanes & ~hit;
    if (!open) return hit;
    if (coherent) {
      hit |= CapsuleLanesHit<W>(m, c, open, stop_at_first);
    } else {
      for (unsigned bits = open; bits; bits &= bits - 1) {
        hit |= CapsuleLanesHit<W>(m, c, bits & (~bits + 1), stop_at_first);
        if (hit && stop_at_first) return hit;
      }
    }
    if (hit && stop_at_first) return hit;
  }
  // Self-collision pairs, one pair at a time across the lanes; bounding spheres about the
  // midpoints first (most pairs are far apart).
  for (const auto& [i, j] : m.self_pairs) {
    const auto& x = placed[i];
    const auto& y = placed[j];
    const V gx = x.mid[0] - y.mid[0], gy = x.mid[1] - y.mid[1], gz = x.mid[2] - y.mid[2];
    const V reach = SplatV<V>(m.cap_half_reach[i] + m.cap_half_reach[j]);
    if (!(Lanes<W>::ToBits(gx * gx + gy * gy + gz * gz < reach * reach) & all_lanes & ~hit)) {
      continue;
    }
    hit |= Lanes<W>::ToBits(CapsulesTouchT<V, M>(
               x.p[0], x.p[1], x.p[2], x.d[0], x.d[1], x.d[2], SplatV<V>(m.cap_len2[i]),
               SplatV<V>(m.cap_inv_len2[i]), y.p[0], y.p[1], y.p[2], y.d[0], y.d[1], y.d[2],
               SplatV<V>(m.cap_len2[j]), SplatV<V>(m.cap_inv_len2[j]),
               SplatV<V>(m.all[i].radius + m.all[j].radius + kFloatPadM))) &
           all_lanes;
    if (hit && stop_at_first) return hit;
  }
  return hit;
}

// The entry points, every call inlined (flatten). FMA changes the rounding of the float tests by
// an ulp or so, far below the 1e-5 m the float lanes are allowed.
__attribute__((flatten)) unsigned LanesBaseline(Impl& m, const Joints* q, int count,
                                                bool coherent, bool stop_at_first) {
  return CollidingLanes<4>(m, q, count, coherent, stop_at_first);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define VB_PRIM_HAVE_AVX2 1
__attribute__((target("avx2,fma"), flatten)) unsigned LanesAvx2(Impl& m, const Joints* q,
                                                               int count, bool coherent,
                                                               bool stop_at_first) {
  return CollidingLanes<8>(m, q, count, coherent, stop_at_first);
}
#endif

}  // namespace

void PrimitiveChecker::Impl::SelectLanes(bool allow_avx2) {
  colliding_lanes = &LanesBaseline;
  lane_width = 4;
  lanes_avx2 = false;
#if defined(VB_PRIM_HAVE_AVX2)
  if (allow_avx2 && CpuHasAvx2Fma()) {
    colliding_lanes = &LanesAvx2;
    lane_width = 8;
    lanes_avx2 = true;
  }
#else
  (void)allow_avx2;
#endif
}

void PrimitiveChecker::UseBaselineSimd() {
  impl_->SelectLanes(/*allow_avx2=*/false);
  impl_->SelectFree(/*allow_avx2=*/false);
}
bool PrimitiveChecker::uses_avx2() const { return impl_->lanes_avx2; }

void PrimitiveChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  const size_t n = std::min(qs.size(), out.size());
  checks_ += static_cast<int64_t>(n);
  const size_t width = static_cast<size_t>(impl_->lane_width);
  // Arbitrary configurations: forward kinematics in lanes, the hierarchy walked per lane.
  for (size_t i = 0; i < n; i += width) {
    const int count = static_cast<int>(std::min(width, n - i));
    const unsigned hit = impl_->colliding_lanes(*impl_, &qs[i], count, /*coherent=*/false,
                                                /*stop_at_first=*/false);
    for (int l = 0; l < count; ++l) out[i + l] = !(hit >> l & 1u) && SaneJoints(qs[i + l]);
  }
}

bool PrimitiveChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  if (!SaneJoints(a) || !SaneJoints(b)) return false;
  const int n = MotionSteps(a, b, max_step_m, lever_m_);
  // The ends first (one batch), then the n - 1 interior samples in blocks of `width`
  // consecutive ones (nearby configurations share one walk of the obstacle hierarchy), the
  // blocks in van der Corput order (coarse to fine) so that a colliding motion usually fails
  // early.
  const Joints ends[2] = {a, b};
  checks_ += 2;
  if (impl_->colliding_lanes(*impl_, ends, 2, /*coherent=*/false, /*stop_at_first=*/true)) {
    return false;
  }
  return InteriorFree(a, b, n);
}

bool PrimitiveChecker::IsMotionInteriorFree(const Joints& a, const Joints& b, double max_step_m) {
  if (!SaneJoints(a) || !SaneJoints(b)) return false;
  return InteriorFree(a, b, MotionSteps(a, b, max_step_m, lever_m_));
}

bool PrimitiveChecker::InteriorFree(const Joints& a, const Joints& b, int n) {
  const int width = impl_->lane_width;
  const int interior = n - 1;
  const int blocks = (interior + width - 1) / width;
  int bits = 0;
  while ((1 << bits) < blocks) ++bits;
  const Joints step = (b - a) / n;
  Joints q[8];
  for (uint32_t i = 0; i < (1u << bits); ++i) {
    uint32_t block = 0;
    for (int k = 0; k < bits; ++k) block |= ((i >> k) & 1u) << (bits - 1 - k);
    if (static_cast<int>(block) >= blocks) continue;
    const int first = width * static_cast<int>(block) + 1;
    const int count = std::min(width, n - first);
    for (int l = 0; l < count; ++l) q[l] = a + step * (first + l);
    checks_ += count;
    if (impl_->colliding_lanes(*impl_, q, count, /*coherent=*/true, /*stop_at_first=*/true)) {
      return false;
    }
  }
  return true;
}

}  // namespace vb::plan
