// SPDX-License-Identifier: Apache-2.0
// Test helper of the path planner's tests (path_planner_test.cc, path_planner_refusal_test.cc).
#pragma once

#include "gtest/gtest.h"
#include "workers/plan/fake_checker_test_util.h"
#include "workers/plan/path_planner.h"

namespace vb::plan::testing {

// Every segment of the path is free, it starts and ends where asked, and stays in the limits.
inline void ExpectValidPath(JointBallChecker& checker, const JointLimits& limits,
                            const PathResult& r, const Joints& start, const Joints& goal) {
  ASSERT_EQ(r.outcome, PathOutcome::kSolved) << r.message;
  ASSERT_GE(r.waypoints.size(), 2u);
  EXPECT_EQ(r.waypoints.front(), start);
  EXPECT_EQ(r.waypoints.back(), goal);
  for (size_t k = 0; k < r.waypoints.size(); ++k) {
    EXPECT_TRUE(limits.Contains(r.waypoints[k])) << "waypoint " << k;
    if (k > 0) {
      EXPECT_TRUE(checker.IsMotionFree(r.waypoints[k - 1], r.waypoints[k], 0.01))
          << "segment " << k;
    }
  }
}

}  // namespace vb::plan::testing
