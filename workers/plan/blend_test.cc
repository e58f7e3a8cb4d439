// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/blend.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "workers/plan/fake_checker_test_util.h"

namespace vb::plan {
namespace {

using testing::JointBallChecker;

using testing::J;

JointLimits MixedLimits() {
  JointLimits limits;
  limits.max_velocity << 3.14, 3.14, 2.0, 3.14, 1.0, 3.14;
  limits.max_acceleration << 1.4, 2.0, 1.4, 5.0, 1.4, 0.7;
  return limits;
}

// Finite differences of the samples: velocity and acceleration within the limits, times strictly
// increasing, at rest at both ends.
void ExpectWithinLimits(const std::vector<TimedJoints>& s, const JointLimits& limits, double dt) {
  ASSERT_GE(s.size(), 2u);
  for (size_t i = 1; i < s.size(); ++i) {
    ASSERT_GT(s[i].t, s[i - 1].t) << i;
    const Joints v = (s[i].q - s[i - 1].q) / (s[i].t - s[i - 1].t);
    for (int j = 0; j < 6; ++j) EXPECT_LE(std::abs(v[j]), limits.max_velocity[j] * (1 + 1e-9)) << i;
  }
  // Second divided differences are weighted means of the (piecewise constant) acceleration.
  for (size_t i = 1; i + 1 < s.size(); ++i) {
    const double h1 = s[i].t - s[i - 1].t, h2 = s[i + 1].t - s[i].t;
    const Joints a = 2.0 * ((s[i + 1].q - s[i].q) / h2 - (s[i].q - s[i - 1].q) / h1) / (h1 + h2);
    for (int j = 0; j < 6; ++j)
      EXPECT_LE(std::abs(a[j]), limits.max_acceleration[j] * (1 + 1e-6) + 1e-9) << i << " " << j;
  }
  // At rest at the ends: from rest, the first step moves at most amax h^2 / 2.
  for (size_t i : {size_t{1}, s.size() - 1}) {
    const double h = s[i].t - s[i - 1].t;
    for (int j = 0; j < 6; ++j)
      EXPECT_LE(std::abs(s[i].q[j] - s[i - 1].q[j]), 0.5 * limits.max_acceleration[j] * h * h + 1e-12);
  }
  (void)dt;
}

std::vector<Joints> RandomPath(std::mt19937& rng, int points, double scale) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Joints> w;
  for (int k = 0; k < points; ++k) {
    Joints q;
    for (int i = 0; i < 6; ++i) q[i] = u(rng) * scale;
    w.push_back(q);
  }
  return w;
}

TEST(BlendedPath, OneSegmentIsTheRestToRestMove) {
  const JointLimits limits;
  for (double d : {0.01, 0.5, 3.0, 9.0}) {  // triangular and (9 rad) trapezoidal
    const std::vector<Joints> w = {J(0, 0.1), J(d, 0.1 - d / 3)};
    EXPECT_NEAR(BlendedPathTimeS(w, limits), MoveTimeS(w[0], w[1], limits), 1e-6 * d) << d;
  }
}

TEST(BlendedPath, CollinearWaypointsAreOneMove) {
  const JointLimits limits;
  const std::vector<Joints> w = {J(0, 0), J(1, -0.5), J(2, -1)};
  EXPECT_NEAR(BlendedPathTimeS(w, limits), MoveTimeS(w.front(), w.back(), limits), 1e-6);
  EXPECT_LT(BlendedPathTimeS(w, limits), PathTimeS(w, limits) - 0.5);
}

TEST(BlendedPath, StaysWithinLimitsAndPassesThroughTheEnds) {
  const JointLimits limits = MixedLimits();
  std::mt19937 rng(5);
  double blended = 0, stopped = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::vector<Joints> w = RandomPath(rng, 2 + trial % 6, trial % 3 == 0 ? 0.03 : 1.0);
    const double dt = 0.004;
    auto path = TimeParameterizeBlended(w, limits, nullptr, {}, 2.0, dt);
    ASSERT_TRUE(path.ok()) << path.status();
    const auto& s = path->samples;
    EXPECT_EQ(s.front().t, 2.0);
    EXPECT_TRUE(s.front().q == w.front());
    EXPECT_TRUE(s.back().q == w.back());
    EXPECT_NEAR(s.back().t - 2.0, path->duration_s, 1e-12);
    EXPECT_NEAR(path->duration_s, BlendedPathTimeS(w, limits), 1e-12);
    EXPECT_LE(path->duration_s, PathTimeS(w, limits) + 1e-12);
    EXPECT_EQ(path->shrinks, 0);
    ExpectWithinLimits(s, limits, dt);
    // Samples at most dt apart.
    for (size_t i = 1; i < s.size(); ++i) EXPECT_LE(s[i].t - s[i - 1].t, dt * (1 + 1e-9));
    blended += path->duration_s;
    stopped += PathTimeS(w, limits);
  }
  // Blending must pay off on random paths (the fallback alone would give equality).
  EXPECT_LT(blended, 0.9 * stopped);
}

TEST(BlendedPath, BlendStaysInTheTriangleOfItsWaypoints) {
  // An L: the blend cuts the corner inside the square [0, 1]^2 of joints 1-2 and leaves the
  // other joints alone.
  const JointLimits limits;
  const std::vector<Joints> w = {J(0, 0, 0.3), J(1, 0, 0.3), J(1, 1, 0.3)};
  auto path = TimeParameterizeBlended(w, limits, nullptr, {}, 0.0, 0.01);
  ASSERT_TRUE(path.ok());
  bool cut_corner = false;
  for (const TimedJoints& p : path->samples) {
    EXPECT_GE(p.q[0], -1e-12);
    EXPECT_LE(p.q[0], 1 + 1e-12);
    EXPECT_GE(p.q[1], -1e-12);
    EXPECT_LE(p.q[1], p.q[0] + 1e-12);  // below the diagonal: inside the triangle
    EXPECT_DOUBLE_EQ(p.q[2], 0.3);
    if (p.q[0] < 0.999 && p.q[1] > 0.001) cut_corner = true;
  }
  EXPECT_TRUE(cut_corner);
  EXPECT_EQ(path->stops, 0);
}

TEST(BlendedPath, CollidingBlendFallsBackToAStop) {
  // An L whose full blend (by symmetry: segments of sqrt(1 / 1.4) s at 1.18 rad/s) deviates 0.125
  // rad per joint from the corner, on the diagonal 0.177 rad away. A ball on the diagonal, 0.11
  // rad from the corner with radius 0.075, touches neither segment but every blend down to a
  // quarter of that (apexes at 0.177, 0.088, 0.044 rad from the corner).
  const JointLimits limits;
  const std::vector<Joints> w = {J(0, 0), J(1, 0), J(1, 1)};
  JointBallChecker checker;
  const double c = 0.11 / std::sqrt(2.0);
  checker.AddBall(J(1 - c, c), 0.075);
  ASSERT_TRUE(checker.IsMotionFree(w[0], w[1], 0.005));
  ASSERT_TRUE(checker.IsMotionFree(w[1], w[2], 0.005));
  BlendOptions options;
  options.max_shrinks = 2;
  auto path = TimeParameterizeBlended(w, limits, &checker, options, 0.0, 0.02);
  ASSERT_TRUE(path.ok());
  EXPECT_EQ(path->vias, 1);
  EXPECT_EQ(path->stops, 1);
  EXPECT_EQ(path->shrinks, 2);
  EXPECT_GT(path->checks, 0);
  EXPECT_NEAR(path->duration_s, PathTimeS(w, limits), 1e-9);
  // It stops exactly at the via, and every chord is free.
  bool at_via = false;
  for (size_t i = 0; i < path->samples.size(); ++i) {
    at_via = at_via || path->samples[i].q == w[1];
    if (i > 0) {
      EXPECT_TRUE(checker.IsMotionFree(path->samples[i - 1].q, path->samples[i].q, 0.005)) << i;
    }
  }
  EXPECT_TRUE(at_via);
  EXPECT_TRUE(path->blend_chords.empty());  // no blend left: the path is its segments
  ExpectWithinLimits(path->samples, limits, 0.02);
}

TEST(BlendedPath, CollidingBlendIsShrunkUntilFree) {
  // A ball farther inside the corner: a full blend touches it, a smaller one does not.
  const JointLimits limits;
  const std::vector<Joints> w = {J(0, 0), J(1, 0), J(1, 1)};
  auto free_path = TimeParameterizeBlended(w, limits, nullptr, {}, 0.0, 0.01);
  ASSERT_TRUE(free_path.ok());
  JointBallChecker checker;
  checker.AddBall(J(0.86, 0.14), 0.03);  // the full blend's apex (0.875, 0.125) is inside
  ASSERT_TRUE(checker.IsMotionFree(w[0], w[1], 0.005));
  ASSERT_TRUE(checker.IsMotionFree(w[1], w[2], 0.005));
  bool full_collides = false;
  for (size_t i = 1; i < free_path->samples.size(); ++i)
    full_collides |= !checker.IsMotionFree(free_path->samples[i - 1].q, free_path->samples[i].q, 0.005);
  ASSERT_TRUE(full_collides);
  auto path = TimeParameterizeBlended(w, limits, &checker, {}, 0.0, 0.01);
  ASSERT_TRUE(path.ok());
  EXPECT_EQ(path->stops, 0);
  EXPECT_GE(path->shrinks, 1);
  EXPECT_GT(path->duration_s, free_path->duration_s);
  EXPECT_LT(path->duration_s, PathTimeS(w, limits));
  for (size_t i = 1; i < path->samples.size(); ++i)
    EXPECT_TRUE(checker.IsMotionFree(path->samples[i - 1].q, path->samples[i].q, 0.005)) << i;
  ExpectWithinLimits(path->samples, limits, 0.01);
}

// Distance in joint space from q to the segment a-b.
double ToSegment(const Joints& q, const Joints& a, const Joints& b) {
  const Joints d = b - a;
  const double len2 = d.squaredNorm();
  const double s = len2 > 0 ? std::clamp((q - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (q - (a + s * d)).norm();
}

TEST(BlendedPath, ChordsOutsideTheBlendsLieOnTheWaypointSegments) {
  // What PlanVine proves again after blending (blend_chords) must hold every chord that leaves
  // the waypoint segments: both ends of any other chord are on one segment.
  std::mt19937 rng(1104);
  const JointLimits limits = MixedLimits();
  int blend_chords = 0, chords = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<Joints> w = RandomPath(rng, 2 + trial % 6, 0.5);
    auto path = TimeParameterizeBlended(w, limits, nullptr, {}, 0.0, 0.05);
    ASSERT_TRUE(path.ok());
    const auto& s = path->samples;
    size_t next = 0;  // into blend_chords
    for (size_t i = 0; i + 1 < s.size(); ++i) {
      ++chords;
      if (next < path->blend_chords.size() && path->blend_chords[next] == static_cast<int>(i)) {
        ++next;
        ++blend_chords;
        continue;
      }
      bool on_one = false;
      for (size_t k = 0; k + 1 < w.size() && !on_one; ++k)
        on_one = ToSegment(s[i].q, w[k], w[k + 1]) < 1e-9 &&
                 ToSegment(s[i + 1].q, w[k], w[k + 1]) < 1e-9;
      EXPECT_TRUE(on_one) << "trial " << trial << " chord " << i;
    }
    EXPECT_EQ(next, path->blend_chords.size()) << "trial " << trial << ": not increasing";
  }
  EXPECT_GT(blend_chords, 0);
  EXPECT_LT(blend_chords, chords);
}

TEST(BlendedPath, RepeatedWaypointsAreMerged) {
  const JointLimits limits;
  const std::vector<Joints> w = {J(0), J(0), J(1), J(1), J(1, 1)};
  auto path = TimeParameterizeBlended(w, limits, nullptr, {}, 0.0, 0.05);
  ASSERT_TRUE(path.ok());
  EXPECT_EQ(path->vias, 1);
  auto single = TimeParameterizeBlended(std::vector<Joints>{J(2)}, limits, nullptr, {}, 1.0, 0.05);
  ASSERT_TRUE(single.ok());
  ASSERT_EQ(single->samples.size(), 1u);
  EXPECT_EQ(single->samples[0].t, 1.0);
}

TEST(BlendedPath, BadInputRejects) {
  const JointLimits limits;
  const std::vector<Joints> w = {J(0), J(1)};
  auto empty = TimeParameterizeBlended({}, limits, nullptr, {}, 0.0, 0.05);
  EXPECT_EQ(empty.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(empty.status().message().find("waypoints"), std::string::npos);
  BlendOptions bad;
  bad.max_step_m = 0;
  auto status = TimeParameterizeBlended(w, limits, nullptr, bad, 0.0, 0.05).status();
  EXPECT_NE(status.message().find("max_step_m"), std::string::npos);
  status = TimeParameterizeBlended(w, limits, nullptr, {}, 0.0, -1).status();
  EXPECT_NE(status.message().find("sample_dt_s"), std::string::npos);
  std::vector<Joints> nan = w;
  nan[1][3] = std::nan("");
  status = TimeParameterizeBlended(nan, limits, nullptr, {}, 0.0, 0.05).status();
  EXPECT_NE(status.message().find("waypoints[1]"), std::string::npos);
}

}  // namespace
}  // namespace vb::plan
