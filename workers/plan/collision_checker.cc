// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace vb::plan {

void CollisionChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  for (size_t i = 0; i < qs.size() && i < out.size(); ++i) out[i] = IsFree(qs[i]);
}

double CollisionChecker::ClearanceAbove(const Joints& q, double /*floor*/, double cap) {
  return std::min(cap, Clearance(q));
}

namespace {

// Carries the cylinder about z_j that holds point p of frame `frame` (for every q_{j+1..frame})
// down the chain, calling visit(j, the cylinder about z_{j-1}) for j = frame .. 1; see the header.
template <typename Visit>
ReachCylinder CarryDown(int frame, const Eigen::Vector3d& p, Visit visit) {
  const DhParameters& dh = Ur5Dh();
  ReachCylinder c{std::hypot(p.x(), p.y()), p.z(), p.z()};
  for (int j = frame; j >= 1; --j) {
    const double ca = std::cos(dh.alpha[j - 1]), sa = std::sin(dh.alpha[j - 1]);
    const double a = std::abs(dh.a[j - 1]), z = std::max(std::abs(c.lo_z_m), std::abs(c.hi_z_m));
    const double lo_c = std::min(c.lo_z_m * ca, c.hi_z_m * ca);
    const double hi_c = std::max(c.lo_z_m * ca, c.hi_z_m * ca);
    const double rho = c.radius_m;
    c.lo_z_m = dh.d[j - 1] + lo_c - rho * std::abs(sa);
    c.hi_z_m = dh.d[j - 1] + hi_c + rho * std::abs(sa);
    c.radius_m =
        std::sqrt((rho + a) * (rho + a) + 2 * rho * z * std::abs(sa * ca) + z * z * sa * sa);
    visit(j, c);
  }
  return c;
}

}  // namespace

JointLevers JointLeverArms(const RobotModel& robot) {
  JointLevers lever{};
  for (const LinkBody& body : robot.BodiesWithTool()) {
    for (const Capsule& c : body.capsules) {
      for (const Eigen::Vector3d& e : {c.a, c.b}) {
        CarryDown(body.frame, e, [&](int j, const ReachCylinder& cyl) {
          lever[j - 1] = std::max(lever[j - 1], cyl.radius_m + c.radius);
        });
      }
    }
  }
  return lever;
}

ReachCylinder ReachOfPoint(int frame, const Eigen::Vector3d& p) {
  return CarryDown(std::clamp(frame, 0, 6), p, [](int, const ReachCylinder&) {});
}

int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m) {
  return MotionSteps(a, b, max_step_m, UniformLevers(std::max(reach_m, 0.0)));
}

int MotionSteps(const Joints& a, const Joints& b, double max_step_m, const JointLevers& lever_m) {
  constexpr int kMaxSteps = 1 << 20;
  // See JointLeverArms: sum_i |dq_i| lever_i bounds the travel of every point of the arm.
  double travel = 0;
  for (int i = 0; i < 6; ++i) travel += std::abs(b[i] - a[i]) * std::max(lever_m[i], 0.0);
  if (!std::isfinite(travel) || !(max_step_m > 0)) return kMaxSteps;
  const double steps = std::ceil(travel / max_step_m);
  return static_cast<int>(std::clamp(steps, 1.0, static_cast<double>(kMaxSteps)));
}

bool CollisionChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  const int n = MotionSteps(a, b, max_step_m, lever_m_);
  // Ends first, then the interior in van der Corput order (coarse to fine) so that a colliding
  // motion usually fails after few checks; chunks let batched checkers work on many at once.
  std::array<bool, 2> ends_free{};
  const std::array<Joints, 2> ends = {a, b};
  AreFree(ends, ends_free);
  if (!ends_free[0] || !ends_free[1]) return false;
  if (n <= 1) return true;
  int bits = 0;
  while ((1 << bits) < n) ++bits;
  constexpr size_t kChunk = 16;
  std::vector<Joints> chunk;
  chunk.reserve(kChunk);
  std::array<bool, kChunk> free{};
  for (uint32_t i = 0; i < (1u << bits); ++i) {
    // Bit-reversed i, scaled into (0, n).
    uint32_t rev = 0;
    for (int k = 0; k < bits; ++k) rev |= ((i >> k) & 1u) << (bits - 1 - k);
    if (rev == 0 || static_cast<int>(rev) >= n) continue;
    chunk.push_back(a + (b - a) * (static_cast<double>(rev) / n));
    if (chunk.size() == kChunk || i + 1 == (1u << bits)) {
      AreFree(chunk, std::span<bool>(free.data(), chunk.size()));
      for (size_t k = 0; k < chunk.size(); ++k) {
        if (!free[k]) return false;
      }
      chunk.clear();
    }
  }
  if (!chunk.empty()) {
    AreFree(chunk, std::span<bool>(free.data(), chunk.size()));
    for (size_t k = 0; k < chunk.size(); ++k) {
      if (!free[k]) return false;
    }
  }
  return true;
}

}  // namespace vb::plan
