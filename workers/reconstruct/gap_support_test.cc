// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/gap_support.h"

#include "gtest/gtest.h"
#include "core/vine_model_test_util.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

TEST(GapSupport, AStretchOfTheCaneIsWoodInEveryView) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  const Eigen::Vector3d a(-0.05, 0.8, 0.9 + 0.1 * 0.05 / 0.3);
  const Eigen::Vector3d b(0.15, 0.8, 0.9 + 0.1 * 0.25 / 0.3);
  EXPECT_GE(GapSupport(a, b, views, rig), 0.99);
}

TEST(GapSupport, AGapOverBackgroundIsNotWood) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  // From a point on the cane straight up 8 cm, over the blue backdrop.
  const Eigen::Vector3d a(0.0, 0.8, 0.9 + 0.1 / 3.0);
  EXPECT_LT(GapSupport(a, a + Eigen::Vector3d(0, 0, 0.08), views, rig), 0.2);
  // 2 cm in front of the cane: its image lies off the cane by several pixels in the side
  // cameras, and misses it in the upper one, so not all of it is supported.
  const Eigen::Vector3d front_a(-0.05, 0.78, 0.9 + 0.1 * 0.05 / 0.3 + 0.02);
  const Eigen::Vector3d front_b(0.15, 0.78, 0.9 + 0.1 * 0.25 / 0.3 + 0.02);
  EXPECT_LT(GapSupport(front_a, front_b, views, rig), 0.5);
}

TEST(GapSupport, WhatNoTwoViewsSeeIsUnsupported) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(OneCaneAcrossTheView(), rig);
  // Far beside the rig, outside every image.
  EXPECT_EQ(GapSupport({3.0, 0.8, 1.0}, {3.1, 0.8, 1.0}, views, rig), 0.0);
  EXPECT_EQ(GapSupport({0.0, 0.8, 1.0}, {NAN, 0.8, 1.0}, views, rig), 0.0);
}

}  // namespace
}  // namespace vb::reconstruct
