// SPDX-License-Identifier: Apache-2.0
// The primitive checker's batched checks (VAMP, Thomason, Kingston, Kavraki ICRA 2024:
// configurations in SIMD lanes): AreFree and IsMotionFree, 4 configurations at a time.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

#include "workers/plan/primitive_checker.h"
#include "workers/plan/primitive_checker_internal.h"

namespace vb::plan {

using namespace prim;

void PrimitiveChecker::Impl::PlaceLanes(const Joints* q, int count) {
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

prim::ArmSeg PrimitiveChecker::Impl::LaneSeg(size_t c, int lane) const {
  const PlacedLanes& pl = lanes_scratch[c];
  return ArmSeg{Splat(pl.p[0][lane]), Splat(pl.p[1][lane]), Splat(pl.p[2][lane]),
                Splat(pl.d[0][lane]), Splat(pl.d[1][lane]), Splat(pl.d[2][lane]),
                Splat(cap_len2[c]), Splat(cap_inv_len2[c]), Splat(all[c].radius), QueryBox{}};
}

unsigned PrimitiveChecker::Impl::CapsuleLanesHit(size_t c, unsigned lanes, bool stop_at_first) const {
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

unsigned PrimitiveChecker::Impl::CollidingLanes(const Joints* q, int count, bool coherent, bool stop_at_first) {
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

namespace {

// The same code twice, every call inlined (flatten): once for the baseline ISA, once for
// AVX2 + FMA (three-operand forms, fused multiply-adds; still 4 lanes). FMA changes the rounding
// of the float tests by an ulp or so, far below the 1e-5 m the float lanes are allowed.
__attribute__((flatten)) unsigned LanesBaseline(PrimitiveChecker::Impl& m, const Joints* q,
                                                int count, bool coherent, bool stop_at_first) {
  return m.CollidingLanes(q, count, coherent, stop_at_first);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define VB_PRIM_HAVE_AVX2 1
__attribute__((target("avx2,fma"), flatten)) unsigned LanesAvx2(
    PrimitiveChecker::Impl& m, const Joints* q, int count, bool coherent, bool stop_at_first) {
  return m.CollidingLanes(q, count, coherent, stop_at_first);
}
#endif

}  // namespace

void PrimitiveChecker::Impl::SelectLanes(bool allow_avx2) {
  colliding_lanes = &LanesBaseline;
  lanes_avx2 = false;
#if defined(VB_PRIM_HAVE_AVX2)
  if (allow_avx2 && CpuHasAvx2Fma()) {
    colliding_lanes = &LanesAvx2;
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
  // Arbitrary configurations: forward kinematics in lanes, the hierarchy walked per lane.
  for (size_t i = 0; i < n; i += 4) {
    const int count = static_cast<int>(std::min<size_t>(4, n - i));
    const unsigned hit = impl_->colliding_lanes(*impl_, &qs[i], count, /*coherent=*/false,
                                               /*stop_at_first=*/false);
    for (int l = 0; l < count; ++l) out[i + l] = !(hit >> l & 1u) && SaneJoints(qs[i + l]);
  }
}

bool PrimitiveChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  if (!SaneJoints(a) || !SaneJoints(b)) return false;
  const int n = MotionSteps(a, b, max_step_m, lever_m_);
  // The ends first (one batch), then the n - 1 interior samples in blocks of 4 consecutive ones
  // (nearby configurations share one walk of the obstacle hierarchy), the blocks in van der
  // Corput order (coarse to fine) so that a colliding motion usually fails early.
  const Joints ends[2] = {a, b};
  checks_ += 2;
  if (impl_->colliding_lanes(*impl_, ends, 2, /*coherent=*/false, /*stop_at_first=*/true)) return false;
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
    if (impl_->colliding_lanes(*impl_, q, count, /*coherent=*/true, /*stop_at_first=*/true)) return false;
  }
  return true;
}

}  // namespace vb::plan
