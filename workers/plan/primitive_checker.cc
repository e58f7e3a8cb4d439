// SPDX-License-Identifier: Apache-2.0
// The primitive checker's construction (the arm's capsules, self-collision pairs and planes; the
// obstacle hierarchy is built in primitive_checker_hierarchy.cc) and the checks of one
// configuration (IsFree in float, Clearance in double). The batched checks are in
// primitive_checker_batch.cc.
#include "workers/plan/primitive_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

// The 8-lane helpers (SegTouchesSet8) are only ever inlined, into IsFree's AVX2 variant or as
// SSE halves, so GCC's note that 32-byte vectors without AVX change the ABI does not apply.
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#include "workers/plan/primitive_checker_internal.h"

namespace vb::plan {
namespace {

using namespace prim;

double CapsuleCapsuleGap(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, double ra,
                         const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, double rb) {
  const double d = (b0 == b1) ? PointSegmentDistance(b0, a0, a1) : SegmentSegmentDistance(a0, a1, b0, b1);
  return d - ra - rb;
}

}  // namespace

using namespace prim;

void PrimitiveChecker::Impl::Fk(const Joints& q, std::array<Frame, 7>& f,
                                bool float_trig) const {
  double c[6], sn[6];
  if (float_trig) {
    F4 s_lo, c_lo, s_hi, c_hi;
    SinCos4(F4{float(q[0]), float(q[1]), float(q[2]), float(q[3])}, &s_lo, &c_lo);
    SinCos4(F4{float(q[4]), float(q[5]), 0.f, 0.f}, &s_hi, &c_hi);
    for (int i = 0; i < 4; ++i) c[i] = c_lo[i], sn[i] = s_lo[i];
    for (int i = 0; i < 2; ++i) c[4 + i] = c_hi[i], sn[4 + i] = s_hi[i];
  } else {
    for (int i = 0; i < 6; ++i) c[i] = std::cos(q[i]), sn[i] = std::sin(q[i]);
  }
  f[0] = Frame{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
               Eigen::Vector3d::Zero()};
  // Standard DH, Rz(q) Tz(d) Tx(a) Rx(alpha), applied to the columns of the previous frame.
  for (int i = 0; i < 6; ++i) {
    const double ct = c[i], st = sn[i];
    const Frame& in = f[i];
    Frame& out = f[i + 1];
    out.x = ct * in.x + st * in.y;
    const Eigen::Vector3d w = ct * in.y - st * in.x;
    out.y = dh_ca[i] * w + dh_sa[i] * in.z;
    out.z = dh_ca[i] * in.z - dh_sa[i] * w;
    out.p = in.p + dh_a[i] * out.x + dh_d[i] * in.z;
  }
}

void PrimitiveChecker::Impl::Place(const Joints& q, bool float_trig) {
  std::array<Frame, 7> f;
  Fk(q, f, float_trig);
  for (size_t i = 0; i < all.size(); ++i) {
    const Frame& fr = f[all[i].frame];
    const Eigen::Vector3d& a = all[i].a;
    const Eigen::Vector3d& b = all[i].b;
    world_a[i] = fr.p + a.x() * fr.x + a.y() * fr.y + a.z() * fr.z;
    world_b[i] = fr.p + b.x() * fr.x + b.y() * fr.y + b.z() * fr.z;
  }
}

template <bool kWide>
bool PrimitiveChecker::Impl::SegHitsObstacles(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) const {
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
            if (kWide ? SegTouchesSet8(s, leaves[l]) : SegVsSet(s, leaves[l]) != 0) return true;
      }
    }
  }
  return false;
}

bool PrimitiveChecker::Impl::SegHitsPlanes(size_t c, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                   double r) const {
  for (const HalfSpace& h : planes_of[c]) {
    if (std::max(h.normal.dot(a), h.normal.dot(b)) + r + h.margin_m > h.offset) return true;
  }
  return false;
}

template <bool kWide>
bool PrimitiveChecker::Impl::Free(const Joints& q) {
  if (base_blocked) return false;
  Place(q, /*float_trig=*/true);
  // `all` lists moving capsules first (distal first), then fixed ones; see the constructor.
  for (size_t i = 0; i < moving.size(); ++i) {
    if (SegHitsPlanes(i, world_a[i], world_b[i], all[i].radius + kFloatPadM)) return false;
  }
  for (size_t i = 0; i < moving.size(); ++i) {
    if (SegHitsObstacles<kWide>(world_a[i], world_b[i], all[i].radius + kFloatPadM)) {
      return false;
    }
  }
  // Self-collision pairs: bounding spheres about the midpoints first (most pairs are far apart),
  // then the distance in double. The positions come from float sincos, hence the padding (as for
  // the planes above).
  for (const auto& [i, j] : self_pairs) {
    const double reach = cap_half_reach[i] + cap_half_reach[j];
    if ((world_a[i] + world_b[i] - world_a[j] - world_b[j]).squaredNorm() >= 4 * reach * reach) {
      continue;
    }
    if (SegmentSegmentDistance(world_a[i], world_b[i], world_a[j], world_b[j]) <
        all[i].radius + all[j].radius + kFloatPadM) {
      return false;
    }
  }
  return true;
}

double PrimitiveChecker::Impl::SegClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                    double best, int* nearest) const {
  for (const HalfSpace& h : planes) {
    best = std::min(best, h.offset - std::max(h.normal.dot(a), h.normal.dot(b)) - r - h.margin_m);
  }
  // Balls first: a pair whose enclosing balls are apart by more than best (plus a slack far above
  // the rounding) cannot lower it, and costs no segment distance. The result is unchanged.
  constexpr double kBallSlackM = 1e-9;
  const Eigen::Vector3d centre = 0.5 * (a + b);
  const double reach = 0.5 * (b - a).norm() + r;
  auto too_far = [&](const Ball& o) {
    const double apart = best + kBallSlackM + reach + o.reach;  // +inf while best is
    return apart > 0 && (centre - o.centre).squaredNorm() >= apart * apart;
  };
  for (size_t l = 0; l < leaf_bounds.size(); ++l) {
    if (too_far(leaf_balls[l])) continue;
    const double lower = CapsuleCapsuleGap(a, b, r, leaf_bounds[l].a, leaf_bounds[l].b,
                                           leaf_bounds[l].radius);
    if (lower >= best + kBallSlackM) continue;  // slack: the bound is computed, not exact
    const int end = std::min<int>(pieces.size(), (l + 1) * kLeaf);
    for (int k = l * kLeaf; k < end; ++k) {
      if (piece_excluded[k] || too_far(piece_balls[k])) continue;
      const double gap = CapsuleCapsuleGap(a, b, r, pieces[k].a, pieces[k].b, pieces[k].rad);
      if (gap < best) {
        best = gap;
        if (nearest) *nearest = k;
      }
    }
  }
  return best;
}

double PrimitiveChecker::Impl::Clearance(const Joints& q, double floor, double cap) {
  Place(q, /*float_trig=*/false);
  // Starting from `cap` prunes more leaves (their bound >= best); min is exact, so the result
  // is min(cap, clearance) bit for bit.
  double best = cap;
  // The pair nearest at the last query first: the same gap of the same inputs, so the min is
  // unchanged, but the balls and leaf bounds below then skip far more (the vine is mostly near
  // one capsule of the tool).
  const int seed_capsule = last_capsule, seed_piece = last_piece;
  if (seed_capsule >= 0) {
    const prim::Piece& p = pieces[seed_piece];
    best = std::min(best, CapsuleCapsuleGap(world_a[seed_capsule], world_b[seed_capsule],
                                            all[seed_capsule].radius, p.a, p.b, p.rad));
    if (best <= floor) return best;
  }
  last_capsule = last_piece = -1;
  for (size_t i = 0; i < all.size(); ++i) {
    if (all[i].frame == 0) continue;  // the base: its gap is known (below)
    int nearest = -1;
    const double before = best;
    best = SegClearance(world_a[i], world_b[i], all[i].radius, best, &nearest);
    if (nearest >= 0 && best < before) {
      last_capsule = static_cast<int>(i);
      last_piece = nearest;
    }
    if (best <= floor) return best;
  }
  // The base never moves: min(best, its gap) is what its SegClearance from `best` returns (that
  // only skips pieces that cannot go below best).
  best = std::min(best, base_clearance);
  if (best <= floor) return best;
  if (last_capsule < 0 && seed_capsule >= 0 && best < cap) {
    // Nothing below the seed pair's gap: it is still the nearest.
    last_capsule = seed_capsule;
    last_piece = seed_piece;
  }
  for (const auto& [i, j] : self_pairs) {
    best = std::min(best, CapsuleCapsuleGap(world_a[i], world_b[i], all[i].radius, world_a[j],
                                            world_b[j], all[j].radius));
    if (best <= floor) return best;
  }
  return best;
}

namespace {

// Free twice, every call inlined (flatten): for the baseline ISA and for AVX2 + FMA (see
// SelectLanes in primitive_checker_batch.cc). FMA changes the double forward kinematics by an
// ulp and the float tests by an ulp or so: far below the float rounding IsFree already accepts.
__attribute__((flatten)) bool FreeBaseline(PrimitiveChecker::Impl& m, const Joints& q) {
  return m.Free<false>(q);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define VB_PRIM_HAVE_AVX2 1
__attribute__((target("avx2,fma"), flatten)) bool FreeAvx2(PrimitiveChecker::Impl& m,
                                                          const Joints& q) {
  return m.Free<true>(q);
}
#endif

}  // namespace

void PrimitiveChecker::Impl::SelectFree(bool allow_avx2) {
  free_fn = &FreeBaseline;
#if defined(VB_PRIM_HAVE_AVX2)
  if (allow_avx2 && CpuHasAvx2Fma()) free_fn = &FreeAvx2;
#else
  (void)allow_avx2;
#endif
}

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
  m.lanes4.resize(caps.size());
  m.lanes8.resize(caps.size());
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

  m.BuildObstacles(scene);

  m.SelectLanes(/*allow_avx2=*/true);
  m.SelectFree(/*allow_avx2=*/true);
  m.UpdateBaseBlocked();
}

void PrimitiveChecker::Impl::UpdateBaseBlocked() {
  // The base never moves: decide once (per set of obstacles) whether it touches anything.
  base_blocked = false;
  base_clearance = std::numeric_limits<double>::infinity();
  for (const ArmCapsule& c : fixed) {
    const double gap = SegClearance(c.a, c.b, c.radius, std::numeric_limits<double>::infinity());
    base_clearance = std::min(base_clearance, gap);
    if (gap < 0) base_blocked = true;
  }
}


PrimitiveChecker::~PrimitiveChecker() = default;

bool PrimitiveChecker::IsFree(const Joints& q) {
  ++checks_;
  return SaneJoints(q) && impl_->free_fn(*impl_, q);
}

double PrimitiveChecker::Clearance(const Joints& q) {
  ++checks_;
  if (!SaneJoints(q)) return -std::numeric_limits<double>::infinity();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  return impl_->Clearance(q, -kInf, kInf);
}

double PrimitiveChecker::ClearanceAbove(const Joints& q, double floor, double cap) {
  ++checks_;
  if (!SaneJoints(q)) return -std::numeric_limits<double>::infinity();
  return impl_->Clearance(q, floor, cap);
}

int PrimitiveChecker::pieces() const { return static_cast<int>(impl_->pieces.size()); }
int PrimitiveChecker::leaves() const { return static_cast<int>(impl_->leaves.size()); }

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel& robot,
                                                      const CollisionScene& scene) {
  return std::make_unique<PrimitiveChecker>(robot, scene);
}

}  // namespace vb::plan
