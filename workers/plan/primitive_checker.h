// SPDX-License-Identifier: Apache-2.0
// The primitive collision checker: the arm's capsules against the scene's capsules, spheres and
// half-spaces, exactly (no tessellation, no sphere approximation of the arm).
//
// After Botterill et al. 2017 section 3.4 (primitives culled by distance, early exit) and VAMP
// (Thomason, Kingston, Kavraki, ICRA 2024: SIMD over primitives, many configurations at once):
//  - obstacles are cut into pieces of at most kMaxPieceM (the union is unchanged), ordered by a
//    recursive median split and stored as float SoA leaves of 8 capsules; 8 consecutive leaves
//    form a node. Each arm capsule's bounding box is tested against the node boxes (8 lanes),
//    then the leaf boxes of hit nodes, then the capsules of hit leaves with an exact
//    segment-segment test (GCC/Clang vector extensions: SSE2 on x86-64, NEON on arm64);
//  - planes first, then obstacles (distal links first), then self-collision pairs; the first
//    hit ends the check; the base, which never moves, is checked once at build;
//  - forward kinematics is written out for the DH chain with an inlined sincos;
//  - AreFree and IsMotionFree check 8 configurations at a time in AVX2 lanes where the CPU has
//    AVX2 and FMA (detected at run time; the library is built for baseline x86-64), 4 in
//    SSE2/NEON lanes elsewhere.
// IsFree, AreFree and IsMotionFree test in float with the arm padded by 1e-5 m, which covers the
// float rounding (< 3e-6 m, see primitive_checker_internal.h): they are conservative, never free
// in contact, and may report contact within ~1e-5 m of it. Clearance is exact in double with
// branch-and-bound over the same leaves.
// Thread-compatible: one checker per thread (it counts checks).
#pragma once

#include <memory>
#include <span>

#include "workers/plan/collision_checker.h"

namespace vb::plan {

// The longest obstacle piece the primitive checker stores (longer capsules are split).
inline constexpr double kMaxPieceM = 0.12;

class PrimitiveChecker : public CollisionChecker {
 public:
  PrimitiveChecker(const RobotModel& robot, const CollisionScene& scene);
  ~PrimitiveChecker() override;

  bool IsFree(const Joints& q) override;
  // 8 (AVX2) or 4 configurations at a time: forward kinematics and the plane and self-collision
  // tests in SIMD lanes (float), the obstacle hierarchy walked per configuration. Agrees with
  // IsFree except within float rounding (~1e-6 m) of the padded contact (1e-5 m).
  void AreFree(std::span<const Joints> qs, std::span<bool> out) override;
  // Batched along the motion: blocks of 8 (AVX2) or 4 consecutive samples share one walk of the
  // obstacle hierarchy (with the union of their boxes); the first collision ends the check. Same
  // samples as CollisionChecker::IsMotionFree (MotionSteps with lever_m()).
  bool IsMotionFree(const Joints& a, const Joints& b, double max_step_m) override;
  // IsMotionFree without its two ends: the same interior samples, checked the same way. For
  // callers that already checked the ends with AreFree, whose lanes decide each configuration
  // exactly as IsMotionFree's batch of the two ends does (the same code, lane by lane).
  bool IsMotionInteriorFree(const Joints& a, const Joints& b, double max_step_m);
  double Clearance(const Joints& q) override;
  // Branch-and-bound from `cap`, and stops once the clearance is at or below `floor`.
  double ClearanceAbove(const Joints& q, double floor, double cap) override;

  // The batched checks (AreFree, IsMotionFree) run AVX2 + FMA code where the CPU has it (x86-64,
  // detected at construction); UseBaselineSimd() switches this checker to the baseline code
  // (SSE2 / NEON) that every machine runs, for tests and benchmarks.
  void UseBaselineSimd();
  bool uses_avx2() const;

  // Leaves out the obstacles of the scene it was built on whose indices (into
  // scene.obstacles) are listed, replacing any earlier exclusion (none: the whole scene again).
  // Every check then answers as a checker built on the scene without them would: excluded pieces
  // become padding, the bounds of the leaves and nodes that held them are refitted to the pieces
  // left, and each piece is tested on its own, so which pieces share a leaf changes no result.
  // Rebuilding costs far more (cut motions leave out the cut cane near each cut point,
  // cut_motion.cc). Out-of-range indices are ignored.
  void Exclude(std::span<const int> obstacles);

  // Number of obstacle pieces, leaves and nodes (for benchmarks and tests).
  int pieces() const;
  int leaves() const;

 // The state (primitive_checker_internal.h), named here for the checker's own translation units.
  struct Impl;

 private:
  bool InteriorFree(const Joints& a, const Joints& b, int n);  // n: MotionSteps
  std::unique_ptr<Impl> impl_;
};

}  // namespace vb::plan
