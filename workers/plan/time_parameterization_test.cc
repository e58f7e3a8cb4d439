// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/time_parameterization.h"

#include <cmath>
#include <limits>
#include <random>

#include "gtest/gtest.h"
#include "workers/plan/fake_checker_test_util.h"

namespace vb::plan {
namespace {

using testing::J;

TEST(MoveTime, TrapezoidMatchesClosedForm) {
  JointLimits limits;  // v = pi
  limits.max_acceleration = Joints::Constant(1.4);
  // One joint, 3 rad: v^2/a = 7.05 rad > 3, so triangular: 2 sqrt(3 / 1.4).
  EXPECT_NEAR(MoveTimeS(J(0), J(3), limits), 2.0 * std::sqrt(3.0 / 1.4), 1e-12);
  // With a = 10: v^2/a = 0.987 < 3, trapezoidal: d/v + v/a.
  limits.max_acceleration = Joints::Constant(10.0);
  EXPECT_NEAR(MoveTimeS(J(0), J(3), limits), 3.0 / M_PI + M_PI / 10.0, 1e-12);
  // Sign does not matter.
  EXPECT_NEAR(MoveTimeS(J(3), J(0), limits), MoveTimeS(J(0), J(3), limits), 1e-15);
}

TEST(MoveTime, SlowestJointSetsTheTime) {
  JointLimits limits;
  limits.max_acceleration = Joints::Constant(10.0);
  limits.max_velocity[2] = 0.5;
  // Joint 1 moves 3 rad (alone: 1.27 s); joint 3 moves 1 rad at most at 0.5 rad/s. Synchronised,
  // the path parameter cruises at V = 0.5 / 1 (joint 3) and accelerates at A = 10 / 3 (joint 1).
  EXPECT_NEAR(MoveTimeS(J(0, 0, 0), J(3, 0, 1), limits), 1.0 / 0.5 + 0.5 / (10.0 / 3.0), 1e-12);
  EXPECT_NEAR(MoveTimeS(J(0), J(0), limits), 0.0, 0.0);
}

TEST(TimeParameterize, StaysWithinLimitsOnRandomPaths) {
  JointLimits limits;
  limits.max_velocity << 3.14, 3.14, 2.0, 3.14, 1.0, 3.14;
  limits.max_acceleration << 1.4, 2.0, 1.4, 5.0, 1.4, 0.7;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Joints> w;
    for (int k = 0; k < 5; ++k) {
      Joints q;
      for (int i = 0; i < 6; ++i) q[i] = u(rng) * (trial % 2 == 0 ? 1.0 : 0.02);  // long and short
      w.push_back(q);
    }
    const double dt = 0.004;
    auto samples = TimeParameterize(w, limits, 5.0, dt);
    ASSERT_TRUE(samples.ok()) << samples.status();
    const auto& s = *samples;
    EXPECT_DOUBLE_EQ(s.front().t, 5.0);
    EXPECT_NEAR(s.back().t, 5.0 + PathTimeS(w, limits), 1e-9);
    // Every waypoint appears at its time.
    double t = 5.0;
    size_t found = 0;
    for (size_t k = 0; k < w.size(); ++k) {
      if (k > 0) t += MoveTimeS(w[k - 1], w[k], limits);
      for (const TimedJoints& p : s) {
        if (std::abs(p.t - t) < 1e-9 && p.q == w[k]) {
          ++found;
          break;
        }
      }
    }
    EXPECT_EQ(found, w.size());
    for (size_t k = 1; k < s.size(); ++k) {
      const double h = s[k].t - s[k - 1].t;
      ASSERT_GT(h, 0.0);
      const Joints v = (s[k].q - s[k - 1].q) / h;
      for (int i = 0; i < 6; ++i) {
        EXPECT_LE(std::abs(v[i]), limits.max_velocity[i] * (1 + 1e-9)) << "sample " << k;
      }
      if (k + 1 < s.size()) {
        // The second divided difference is a weighted average of the acceleration.
        const double h2 = s[k + 1].t - s[k].t;
        const Joints v2 = (s[k + 1].q - s[k].q) / h2;
        const Joints acc = 2.0 * (v2 - v) / (h + h2);
        for (int i = 0; i < 6; ++i) {
          EXPECT_LE(std::abs(acc[i]), limits.max_acceleration[i] * (1 + 1e-6) + 1e-9) << "sample " << k;
        }
      }
    }
  }
}

TEST(TimeParameterize, SlowestJointReachesItsLimit) {
  // The profile is time-optimal on the segment: some joint hits its velocity or acceleration
  // limit (here velocity: a long move with high acceleration).
  JointLimits limits;
  limits.max_acceleration = Joints::Constant(20.0);
  std::vector<Joints> w = {J(0), J(3, 1)};
  auto s = TimeParameterize(w, limits, 0.0, 0.001);
  ASSERT_TRUE(s.ok());
  double vmax = 0;
  for (size_t k = 1; k < s->size(); ++k) {
    vmax = std::max(vmax, std::abs(((*s)[k].q[0] - (*s)[k - 1].q[0]) / ((*s)[k].t - (*s)[k - 1].t)));
  }
  EXPECT_GT(vmax, 0.99 * M_PI);
}

TEST(TimeParameterize, PathStaysOnTheSegments) {
  JointLimits limits;
  std::vector<Joints> w = {J(0), J(1, 2), J(-1, 0.5, 0.3)};
  auto s = TimeParameterize(w, limits, 0.0, 0.01);
  ASSERT_TRUE(s.ok());
  const double t1 = MoveTimeS(w[0], w[1], limits);
  for (const TimedJoints& p : *s) {
    const Joints& a = p.t <= t1 ? w[0] : w[1];
    const Joints& b = p.t <= t1 ? w[1] : w[2];
    // On the line a-b: the residual after projecting onto it is zero.
    const Joints ab = b - a;
    const double f = (p.q - a).dot(ab) / ab.squaredNorm();
    EXPECT_GE(f, -1e-12);
    EXPECT_LE(f, 1 + 1e-12);
    EXPECT_LT((a + f * ab - p.q).norm(), 1e-12);
  }
}

TEST(TimeParameterize, ZeroLengthSegmentsAreMerged) {
  JointLimits limits;
  std::vector<Joints> w = {J(0), J(0), J(1), J(1), J(1)};
  auto s = TimeParameterize(w, limits, 1.0, 0.05);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->front().q, J(0));
  EXPECT_EQ(s->back().q, J(1));
  EXPECT_NEAR(s->back().t, 1.0 + MoveTimeS(J(0), J(1), limits), 1e-12);
  for (size_t k = 1; k < s->size(); ++k) EXPECT_GT((*s)[k].t, (*s)[k - 1].t);
  auto single = TimeParameterize(std::vector<Joints>{J(0.5)}, limits, 2.0, 0.05);
  ASSERT_TRUE(single.ok());
  ASSERT_EQ(single->size(), 1u);
  EXPECT_EQ((*single)[0].t, 2.0);
}

TEST(TimeParameterize, MoveStateAtEndsExactly) {
  JointLimits limits;
  const Joints a = J(0.1, 0.2), b = J(-0.7, 1.1, 0.4);
  const double T = MoveTimeS(a, b, limits);
  EXPECT_EQ(MoveStateAt(a, b, limits, 0.0), a);
  EXPECT_EQ(MoveStateAt(a, b, limits, T), b);
  EXPECT_EQ(MoveStateAt(a, b, limits, T + 1), b);
  // Symmetric profile: half way in time is half way in space.
  EXPECT_LT((MoveStateAt(a, b, limits, T / 2) - 0.5 * (a + b)).norm(), 1e-12);
}

TEST(TimeParameterize, BadInputIsRejected) {
  JointLimits limits;
  std::vector<Joints> w = {J(0), J(1)};
  EXPECT_NE(TimeParameterize({}, limits, 0, 0.01).status().message().find("waypoints"), std::string::npos);
  EXPECT_NE(TimeParameterize(w, limits, 0, 0.0).status().message().find("sample_dt_s"), std::string::npos);
  EXPECT_FALSE(TimeParameterize(w, limits, std::numeric_limits<double>::infinity(), 0.01).ok());
  w[1][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(TimeParameterize(w, limits, 0, 0.01).status().message().find("waypoints[1]"), std::string::npos);
  w[1][2] = 0;
  limits.max_acceleration[4] = 0;
  EXPECT_FALSE(TimeParameterize(w, limits, 0, 0.01).ok());
  limits = JointLimits();
  EXPECT_FALSE(TimeParameterize(w, limits, 0, 1e-9).ok());  // too many samples
}

// A straight stroke in and out again (the secateur's approach and retract), 12 steps each way.
std::vector<Joints> InAndOut() {
  std::vector<Joints> w;
  for (int i = 0; i <= 12; ++i) w.push_back(J(0.01 * i, -0.004 * i, 0.5, 0.002 * i));
  for (int i = 11; i >= 0; --i) w.push_back(w[i]);
  return w;
}

TEST(TimeParameterizeAlongPath, StopsWhereAskedAndStaysWithinLimits) {
  const std::vector<Joints> w = InAndOut();
  const JointLimits limits;
  const std::vector<double> full(w.size() - 1, 1.0);
  const int stop[] = {12};
  const double dt = 0.01;
  auto samples = TimeParameterizeAlongPath(w, limits, full, stop, 1.0, dt);
  ASSERT_TRUE(samples.ok()) << samples.status();
  const auto& s = *samples;
  // Rest to rest twice on a straight line: each half is MoveTimeS of its ends.
  EXPECT_NEAR(s.back().t - 1.0, 2.0 * MoveTimeS(w.front(), w[12], limits), 1e-9);
  bool at_stop = false;
  for (size_t i = 1; i < s.size(); ++i) {
    const double h = s[i].t - s[i - 1].t;
    ASSERT_GT(h, 0.0);
    const Joints v = (s[i].q - s[i - 1].q) / h;
    for (int j = 0; j < 6; ++j) EXPECT_LE(std::abs(v[j]), limits.max_velocity[j] * (1 + 1e-9));
    if (s[i].q == w[12]) at_stop = true;
    if (i + 1 < s.size()) {
      const double h2 = s[i + 1].t - s[i].t;
      const Joints a = 2.0 * ((s[i + 1].q - s[i].q) / h2 - v) / (h + h2);
      // The reversal is a stop, so no instant turn of the velocity anywhere on this line.
      for (int j = 0; j < 6; ++j)
        EXPECT_LE(std::abs(a[j]), limits.max_acceleration[j] * (1 + 1e-6)) << i << " " << j;
    }
  }
  EXPECT_TRUE(at_stop);
  // Without the stop the velocity turns instantly at the reversal: a second difference far
  // beyond the limit (what a stop at the cut prevents).
  auto turning = TimeParameterizeAlongPath(w, limits, full, {}, 1.0, dt);
  ASSERT_TRUE(turning.ok());
  double worst = 0;
  for (size_t i = 1; i + 1 < turning->size(); ++i) {
    const auto& t = *turning;
    const double h1 = t[i].t - t[i - 1].t, h2 = t[i + 1].t - t[i].t;
    const Joints a = 2.0 * ((t[i + 1].q - t[i].q) / h2 - (t[i].q - t[i - 1].q) / h1) / (h1 + h2);
    worst = std::max(worst, a.cwiseAbs().maxCoeff() / 1.4);
  }
  EXPECT_GT(worst, 2.0);
}

TEST(TimeParameterizeAlongPath, SlowSegmentsKeepTheirSpeedFraction) {
  std::vector<Joints> w;
  for (int i = 0; i <= 20; ++i) w.push_back(J(0.02 * i, 0.01 * i));
  JointLimits limits;
  limits.max_velocity = Joints::Constant(0.5);
  std::vector<double> fraction(20, 1.0);
  for (int k = 8; k < 12; ++k) fraction[k] = 0.25;  // waypoints 8-12 in contact
  auto samples = TimeParameterizeAlongPath(w, limits, fraction, {}, 0.0, 0.005);
  ASSERT_TRUE(samples.ok());
  const auto& s = *samples;
  double fast = 0;
  for (size_t i = 1; i < s.size(); ++i) {
    const double v = std::abs(s[i].q[0] - s[i - 1].q[0]) / (s[i].t - s[i - 1].t);
    EXPECT_LE(v, 0.5 * (1 + 1e-9));
    const bool in_contact = s[i - 1].q[0] >= 0.16 - 1e-12 && s[i].q[0] <= 0.24 + 1e-12;
    if (in_contact) EXPECT_LE(v, 0.125 * (1 + 1e-9)) << i;
    else fast = std::max(fast, v);
  }
  EXPECT_GT(fast, 0.3);  // outside the contact the arm goes faster
  auto all_slow = TimeParameterizeAlongPath(w, limits, std::vector<double>(20, 0.25), {}, 0.0, 0.005);
  ASSERT_TRUE(all_slow.ok());
  EXPECT_LT(s.back().t, all_slow->back().t);
}

TEST(TimeParameterizeAlongPath, RejectsBadSpeedFractionsAndStops) {
  const std::vector<Joints> w = {J(0), J(1), J(2)};
  const JointLimits limits;
  const std::vector<double> one = {1.0};
  EXPECT_NE(TimeParameterizeAlongPath(w, limits, one, {}, 0, 0.01).status().message().find(
                "speed_fraction"),
            std::string::npos);
  const std::vector<double> zero = {1.0, 0.0};
  EXPECT_NE(TimeParameterizeAlongPath(w, limits, zero, {}, 0, 0.01).status().message().find(
                "speed_fraction[1]"),
            std::string::npos);
  const std::vector<double> ok = {1.0, 1.0};
  const int bad_stop[] = {3};
  EXPECT_NE(TimeParameterizeAlongPath(w, limits, ok, bad_stop, 0, 0.01).status().message().find(
                "stops"),
            std::string::npos);
}

}  // namespace
}  // namespace vb::plan

namespace vb::plan {
namespace {

// A dense, gently curving stroke: one profile over all of it, within the joint limits, every
// waypoint kept, times strictly increasing.
TEST(TimeParameterizeStroke, OneProfileWithinTheLimits) {
  std::vector<Joints> stroke;
  for (int i = 0; i <= 24; ++i) {
    Joints q;
    q << 0.01 * i, 0.5 + 0.004 * i, -1.0 + 0.0001 * i * i, 0.2, 1.0 - 0.003 * i, 0.0;
    stroke.push_back(q);
  }
  JointLimits limits;
  limits.max_velocity = Joints::Constant(0.25 * M_PI);
  limits.max_acceleration = Joints::Constant(0.25 * 1.4);
  auto samples = TimeParameterizeStroke(stroke, limits, 3.0, 0.013);
  ASSERT_TRUE(samples.ok()) << samples.status();
  EXPECT_DOUBLE_EQ(samples->front().t, 3.0);
  EXPECT_TRUE(samples->back().q.isApprox(stroke.back()));
  size_t found = 0;
  for (size_t i = 1; i < samples->size(); ++i) {
    const double dt = (*samples)[i].t - (*samples)[i - 1].t;
    ASSERT_GT(dt, 0.0) << i;
    const Joints v = ((*samples)[i].q - (*samples)[i - 1].q) / dt;
    for (int j = 0; j < 6; ++j) EXPECT_LE(std::abs(v[j]), limits.max_velocity[j] * 1.001);
  }
  for (const Joints& q : stroke) {
    for (const TimedJoints& s : *samples) found += (s.q - q).norm() < 1e-12 ? 1 : 0;
  }
  EXPECT_GE(found, stroke.size());
  // Faster than stopping at every waypoint.
  auto stops = TimeParameterize(stroke, limits, 3.0, 0.013);
  ASSERT_TRUE(stops.ok());
  EXPECT_LT(samples->back().t, 0.5 * stops->back().t);
}

TEST(TimeParameterizeStroke, RejectsBadInput) {
  EXPECT_FALSE(TimeParameterizeStroke({}, JointLimits{}, 0.0, 0.01).ok());
  std::vector<Joints> one = {Joints::Zero(), Joints::Ones()};
  EXPECT_FALSE(TimeParameterizeStroke(one, JointLimits{}, 0.0, 0.0).ok());
}

}  // namespace
}  // namespace vb::plan
