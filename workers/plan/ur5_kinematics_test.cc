// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/ur5_kinematics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <limits>
#include <random>

#include "gtest/gtest.h"

namespace vb::plan {
namespace {

// At q = 0 the UR5 lies stretched along -x of the base: flange at
// x = a2 + a3, y = -(d4 + d6), z = d1 - d5 (ur_kinematics' zero pose).
TEST(Ur5Kinematics, ZeroConfigurationMatchesDhTable) {
  const Eigen::Isometry3d flange = ForwardKinematics(Joints::Zero());
  EXPECT_NEAR(flange.translation().x(), -0.425 - 0.39225, 1e-12);
  EXPECT_NEAR(flange.translation().y(), -(0.10915 + 0.0823), 1e-12);
  EXPECT_NEAR(flange.translation().z(), 0.089159 - 0.09465, 1e-12);
}

TEST(Ur5Kinematics, LinkFramesEndAtTheFlange) {
  Joints q;
  q << 0.3, -1.2, 1.0, -0.4, 0.7, 2.0;
  const auto frames = LinkFrames(q);
  EXPECT_TRUE(frames[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(frames[6].isApprox(ForwardKinematics(q), 1e-12));
  // Joint 1 rotates about the base z axis only: the shoulder frame sits at height d1.
  EXPECT_NEAR(frames[1].translation().z(), 0.089159, 1e-12);
}

TEST(Ur5Kinematics, LimitsRejectBadValues) {
  JointLimits limits;
  EXPECT_TRUE(limits.Validate().ok());
  limits.upper[2] = limits.lower[2];
  EXPECT_NE(limits.Validate().message().find("joint 3"), std::string::npos);
  limits = JointLimits();
  limits.max_velocity[0] = 0.0;
  EXPECT_FALSE(limits.Validate().ok());
}

// Largest joint difference modulo 2 pi.
double AngleDistance(const Joints& a, const Joints& b) {
  double worst = 0;
  for (int i = 0; i < 6; ++i) {
    worst = std::max(worst, std::abs(std::remainder(a[i] - b[i], 2.0 * M_PI)));
  }
  return worst;
}

double PositionError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

// Frobenius norm of the rotation difference (~ the angle for small errors).
double RotationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.linear() - b.linear()).norm();
}

Joints RandomJoints(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  Joints q;
  for (int i = 0; i < 6; ++i) q[i] = angle(rng);
  return q;
}

TEST(Ur5InverseKinematics, EverySolutionReproducesThePose) {
  std::mt19937 rng(17);
  const JointLimits limits;
  double worst_position = 0, worst_rotation = 0;
  int solutions = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const Eigen::Isometry3d pose = ForwardKinematics(RandomJoints(rng));
    const IkSolutions ik = InverseKinematics(pose, limits);
    ASSERT_GT(ik.count, 0) << "trial " << trial;
    for (int k = 0; k < ik.count; ++k) {
      ASSERT_TRUE(ik.q[k].allFinite());
      const Eigen::Isometry3d back = ForwardKinematics(ik.q[k]);
      worst_position = std::max(worst_position, PositionError(back, pose));
      worst_rotation = std::max(worst_rotation, RotationError(back, pose));
      ++solutions;
    }
  }
  RecordProperty("worst_position_m", std::to_string(worst_position));
  RecordProperty("worst_rotation", std::to_string(worst_rotation));
  std::printf("worst round trip: position %.3g m, rotation %.3g\n", worst_position, worst_rotation);
  EXPECT_LT(worst_position, 1e-9);
  EXPECT_LT(worst_rotation, 1e-9);
  EXPECT_GT(solutions, 5000 * 7);  // nearly every random pose has all 8
}

TEST(Ur5InverseKinematics, GeneratingConfigurationIsAmongTheSolutions) {
  std::mt19937 rng(23);
  const JointLimits limits;
  for (int trial = 0; trial < 2000; ++trial) {
    const Joints q = RandomJoints(rng);
    const IkSolutions ik = InverseKinematics(ForwardKinematics(q), limits);
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < ik.count; ++k) best = std::min(best, AngleDistance(ik.q[k], q));
    EXPECT_LT(best, 1e-6) << "trial " << trial << " q " << q.transpose();
  }
}

TEST(Ur5InverseKinematics, GenericPoseHasEightDistinctSolutions) {
  Joints q;
  q << 0.4, -1.1, 1.3, -0.9, 1.2, 0.5;
  const IkSolutions ik = InverseKinematics(ForwardKinematics(q), JointLimits());
  ASSERT_EQ(ik.count, 8);
  for (int i = 0; i < 8; ++i) {
    for (int j = i + 1; j < 8; ++j) {
      EXPECT_GT(AngleDistance(ik.q[i], ik.q[j]), 1e-3) << i << " vs " << j;
    }
  }
}

TEST(Ur5InverseKinematics, SolutionsLieNearestTheGivenConfiguration) {
  Joints q;
  q << 0.4, -1.1, 1.3, -0.9, 1.2, 0.5;
  Joints near = q;
  near[0] -= 2.0 * M_PI;  // the equivalent angles one turn down are the nearest
  near[5] -= 2.0 * M_PI;
  const IkSolutions ik = InverseKinematics(ForwardKinematics(q), JointLimits(), &near);
  ASSERT_EQ(ik.count, 8);
  bool found = false;
  for (int k = 0; k < ik.count; ++k) {
    // Joints 2-5: near is central in the default limits, so every solution is within a half turn.
    for (int i = 1; i < 5; ++i) EXPECT_LE(std::abs(ik.q[k][i] - near[i]), M_PI + 1e-9);
    found = found || (ik.q[k] - near).norm() < 1e-9;
  }
  EXPECT_TRUE(found);
}

TEST(Ur5InverseKinematics, OneBranchIsTheFullSolveOfThatBranchAndOthersLieApart) {
  std::mt19937 rng(29);
  const JointLimits limits;
  int branches = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Joints q = RandomJoints(rng);
    const Joints near = RandomJoints(rng);
    const Eigen::Isometry3d pose = ForwardKinematics(q);
    const IkSolutions all = InverseKinematics(pose, limits, &near);
    for (int branch = 0; branch < 8; ++branch) {
      Joints one;
      double apart = -1;
      const bool found = InverseKinematicsBranch(pose, limits, &near, branch, &one, &apart);
      int k = 0;
      while (k < all.count && all.branch[k] != branch) ++k;
      ASSERT_EQ(found, k < all.count) << "trial " << trial << " branch " << branch;
      if (!found) continue;
      ++branches;
      // Bit for bit the full solve's solution of that branch.
      for (int j = 0; j < 6; ++j) EXPECT_EQ(one[j], all.q[k][j]) << trial << " " << branch;
      // Every other solution is at least `apart` from it in some joint, modulo whole turns.
      for (int m = 0; m < all.count; ++m) {
        if (m == k) continue;
        double farthest = 0;
        for (int j = 0; j < 6; ++j) {
          const double d = std::remainder(all.q[m][j] - one[j], 2 * M_PI);
          farthest = std::max(farthest, std::abs(d));
        }
        EXPECT_GE(farthest, apart - 1e-9) << trial << " " << branch << " vs " << all.branch[m];
      }
    }
  }
  EXPECT_GT(branches, 1000);  // most random poses have all 8 within the default limits
  Joints unused;
  double apart = 0;
  EXPECT_FALSE(InverseKinematicsBranch(ForwardKinematics(Joints::Zero()), limits, nullptr, 8,
                                       &unused, &apart));
}

TEST(Ur5InverseKinematics, UnreachablePoseHasNoSolution) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << 2.0, 0.0, 0.3;
  EXPECT_EQ(InverseKinematics(pose, JointLimits()).count, 0);
  // Inside the shoulder's cylinder: the wrist centre nearer the base axis than d4.
  pose.translation() << 0.02, 0.01, 0.3 + 0.0823;
  pose.linear() = Eigen::Matrix3d::Identity();
  EXPECT_EQ(InverseKinematics(pose, JointLimits()).count, 0);
}

TEST(Ur5InverseKinematics, NonFiniteInputHasNoSolution) {
  Eigen::Isometry3d pose = ForwardKinematics(Joints::Constant(0.3));
  Joints near = Joints::Zero();
  near[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(InverseKinematics(pose, JointLimits(), &near).count, 0);
  pose.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(InverseKinematics(pose, JointLimits()).count, 0);
}

TEST(Ur5InverseKinematics, LimitsDropSolutionsOutsideThem) {
  Joints q;
  q << 0.4, -1.1, 1.3, -0.9, 1.2, 0.5;
  JointLimits limits;
  limits.lower = q - Joints::Constant(0.1);
  limits.upper = q + Joints::Constant(0.1);
  const IkSolutions ik = InverseKinematics(ForwardKinematics(q), limits);
  ASSERT_EQ(ik.count, 1);
  EXPECT_LT((ik.q[0] - q).norm(), 1e-9);
  // An elbow range that excludes the generating elbow angle leaves only the other elbow branch.
  limits = JointLimits();
  limits.lower[2] = -M_PI;
  limits.upper[2] = 0.0;
  const IkSolutions elbow_down = InverseKinematics(ForwardKinematics(q), limits);
  EXPECT_EQ(elbow_down.count, 4);
  for (int k = 0; k < elbow_down.count; ++k) EXPECT_LE(elbow_down.q[k][2], 0.0);
  // A limit range narrower than a turn that misses every equivalent angle drops everything.
  limits = JointLimits();
  limits.lower[0] = 2.0;
  limits.upper[0] = 2.1;
  EXPECT_EQ(InverseKinematics(ForwardKinematics(q), limits).count, 0);
}

TEST(Ur5InverseKinematics, WrapIntoLimitsPicksTheNearestEquivalent) {
  JointLimits limits;
  Joints q = Joints::Constant(-0.5);
  Joints near = Joints::Constant(5.0);
  ASSERT_TRUE(WrapIntoLimits(limits, &near, &q));
  EXPECT_NEAR(q[0], -0.5 + 2.0 * M_PI, 1e-12);
  limits.upper = Joints::Constant(1.0);  // -0.5 + 2 pi is above it: fall back to -0.5
  q = Joints::Constant(-0.5);
  ASSERT_TRUE(WrapIntoLimits(limits, &near, &q));
  EXPECT_NEAR(q[3], -0.5, 1e-12);
  limits.lower = Joints::Constant(-0.4);  // [-0.4, 1] holds no equivalent of -0.5
  q = Joints::Constant(-0.5);
  EXPECT_FALSE(WrapIntoLimits(limits, &near, &q));
}

TEST(Ur5InverseKinematics, WristSingularityTakesQ6FromNear) {
  Joints q;
  q << 0.3, -1.2, 1.1, -0.5, 0.0, 0.7;  // q5 = 0: axes 4 and 6 coincide
  const Eigen::Isometry3d pose = ForwardKinematics(q);
  Joints near = Joints::Zero();
  near[5] = 1.9;
  const IkSolutions ik = InverseKinematics(pose, JointLimits(), &near);
  ASSERT_GT(ik.count, 0);
  for (int k = 0; k < ik.count; ++k) {
    ASSERT_TRUE(ik.q[k].allFinite());
    EXPECT_LT(PositionError(ForwardKinematics(ik.q[k]), pose), 1e-9);
    EXPECT_LT(RotationError(ForwardKinematics(ik.q[k]), pose), 1e-9);
  }
  bool q6_from_near = false;
  for (int k = 0; k < ik.count; ++k) {
    q6_from_near = q6_from_near || std::abs(ik.q[k][5] - 1.9) < 1e-12;
  }
  EXPECT_TRUE(q6_from_near);
}

TEST(Ur5InverseKinematics, NearSingularPosesGiveFiniteAccurateSolutions) {
  // Wrist near-singular, elbow stretched or folded, shoulder at the d4 cylinder.
  std::vector<Joints> cases;
  for (double eps : {0.0, 1e-14, 1e-10, 1e-7, 1e-4}) {
    Joints q;
    q << 0.3, -1.2, 1.1, -0.5, eps, 0.7;
    cases.push_back(q);
    q << 0.3, -1.2, eps, -0.5, 1.0, 0.7;
    cases.push_back(q);
    q << -2.0, -0.2, M_PI - eps, 0.4, M_PI - eps, -1.0;
    cases.push_back(q);
  }
  for (const Joints& q : cases) {
    const Eigen::Isometry3d pose = ForwardKinematics(q);
    const IkSolutions ik = InverseKinematics(pose, JointLimits());
    ASSERT_GT(ik.count, 0) << q.transpose();
    for (int k = 0; k < ik.count; ++k) {
      ASSERT_TRUE(ik.q[k].allFinite()) << q.transpose();
      EXPECT_LT(PositionError(ForwardKinematics(ik.q[k]), pose), 1e-8) << q.transpose();
      EXPECT_LT(RotationError(ForwardKinematics(ik.q[k]), pose), 1e-7) << q.transpose();
    }
  }
}

}  // namespace
}  // namespace vb::plan
