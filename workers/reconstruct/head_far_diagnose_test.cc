// SPDX-License-Identifier: Apache-2.0
// Known answers of the diagnosis support in head_far_diagnose.h (runs in ctest).
#include "workers/reconstruct/head_far_diagnose.h"

#include "gtest/gtest.h"
#include "workers/reconstruct/connect_test_util.h"

namespace vb::reconstruct {
namespace {

using connect_test::Head;  // one sphere of 5 cm at (0, 0.8, 1.0)
using connect_test::Line;

TEST(HeadFarDiagnose, InnerEndDistanceAndPointing) {
  // Pointing straight away from the head, its first point 20 cm from the surface.
  const InnerEnd out = InnerEndToHead(Line({0.25, 0.8, 1.0}, {0.5, 0.8, 1.0}), Head());
  EXPECT_FALSE(out.last);
  EXPECT_NEAR(out.distance_m, 0.20, 1e-9);
  EXPECT_NEAR(out.cos, 1.0, 1e-9);
  // The same line reversed: the inner end is its last point.
  const InnerEnd reversed = InnerEndToHead(Line({0.5, 0.8, 1.0}, {0.25, 0.8, 1.0}), Head());
  EXPECT_TRUE(reversed.last);
  EXPECT_NEAR(reversed.cos, 1.0, 1e-9);
  // Running across the direction to the head.
  const InnerEnd across = InnerEndToHead(Line({0.25, 0.8, 1.0}, {0.25, 1.1, 1.0}), Head());
  EXPECT_NEAR(across.distance_m, 0.20, 1e-9);
  EXPECT_NEAR(across.cos, 0.0, 1e-9);
}

TEST(HeadFarDiagnose, Bins) {
  EXPECT_EQ(HeadFarBin(-0.01), 0);
  EXPECT_EQ(HeadFarBin(0.149), 0);
  EXPECT_EQ(HeadFarBin(0.15), 1);
  EXPECT_EQ(HeadFarBin(0.30), 2);
  EXPECT_EQ(HeadFarBin(0.40), 3);
}

}  // namespace
}  // namespace vb::reconstruct
