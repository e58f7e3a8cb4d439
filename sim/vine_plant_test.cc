// SPDX-License-Identifier: Apache-2.0
#include "sim/vine_plant.h"

#include <cmath>
#include <numbers>

#include "gtest/gtest.h"
#include "sim/vine_cane_growth.h"
#include "sim/vine_random.h"

namespace vb::sim {
namespace {

TEST(VineRng, FollowsTheStandardMersenneTwisterSequence) {
  // C++ [rand.predef]: the 10000th output of a default-constructed mt19937_64.
  VineRng rng(5489u);
  uint64_t x = 0;
  for (int i = 0; i < 10000; ++i) x = rng.Next();
  EXPECT_EQ(x, 9981545732273789042ull);
}

TEST(VineRng, UniformAndNormalHaveTheRightMoments) {
  VineRng rng(3);
  constexpr int kN = 200000;
  double su = 0, su2 = 0, sn = 0, sn2 = 0;
  double umin = 1, umax = 0;
  for (int i = 0; i < kN; ++i) {
    const double u = rng.Uniform();
    const double n = rng.Normal();
    su += u;
    su2 += u * u;
    sn += n;
    sn2 += n * n;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
  }
  EXPECT_NEAR(su / kN, 0.5, 0.005);
  EXPECT_NEAR(su2 / kN - 0.25, 1.0 / 12, 0.003);
  EXPECT_GE(umin, 0.0);
  EXPECT_LT(umax, 1.0);
  EXPECT_NEAR(sn / kN, 0.0, 0.01);
  EXPECT_NEAR(sn2 / kN, 1.0, 0.02);
}

TEST(VineRng, UniformIntCoversTheInclusiveRange) {
  VineRng rng(9);
  int counts[5] = {0, 0, 0, 0, 0};
  for (int i = 0; i < 5000; ++i) {
    const int v = rng.UniformInt(-2, 2);
    ASSERT_GE(v, -2);
    ASSERT_LE(v, 2);
    ++counts[v + 2];
  }
  for (int c : counts) EXPECT_GT(c, 800);
}

TEST(VineRng, MixSeedSeparatesIndicesAndStreams) {
  EXPECT_NE(MixSeed(1, 0, 1), MixSeed(1, 1, 1));
  EXPECT_NE(MixSeed(1, 0, 1), MixSeed(1, 0, 2));
  EXPECT_NE(MixSeed(1, 0, 1), MixSeed(2, 0, 1));
  EXPECT_EQ(MixSeed(1, -4, 1), MixSeed(1, -4, 1));
}

// A trellis with one fruiting wire at 1.0 m and no sag.
TrellisRow FlatRow() {
  TrellisRow row;
  row.wires.push_back({WireId(1), 1.0, 0.8, 0.0});
  return row;
}

TEST(GrowCane, HasTheRequestedLengthRadiiAndSpacing) {
  const VineGeneratorOptions options;
  VineRng rng(1);
  CaneGrowth g;
  g.base = {0, 0.8, 0.5};
  g.length_m = 0.83;
  g.base_radius_m = 0.005;
  g.tip_ratio = 0.5;
  g.drape_probability = 0.0;
  const Polyline3 line = GrowCane(g, FlatRow(), options, rng);
  ASSERT_TRUE(line.Validate("cane").ok());
  EXPECT_NEAR(line.Length(), 0.83, 1e-6);
  EXPECT_EQ(line.points.front(), g.base);
  EXPECT_DOUBLE_EQ(line.radii.front(), 0.005);
  EXPECT_NEAR(line.radii.back(), 0.0025, 1e-12);
  for (size_t i = 1; i < line.points.size(); ++i) {
    const double step = (line.points[i] - line.points[i - 1]).norm();
    EXPECT_LE(step, g.step_max_m + 1e-9);
    EXPECT_GE(step, 0.5 * g.step_min_m - 1e-9);
  }
}

TEST(GrowCane, DrapesAlongAWireItMeetsOnlyWhenCaught) {
  const VineGeneratorOptions options;
  int draped = 0, crossed = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    for (double p : {0.0, 1.0}) {
      VineRng rng(seed);
      CaneGrowth g;
      g.base = {0, 0.8, 0.8};
      g.heading_rad = 0.3;  // up and a little along +x: meets the wire at 1.0 m
      g.length_m = 1.0;
      g.base_radius_m = 0.005;
      g.droop_rad_per_m = 0.0;
      g.arch_rad_per_m = 0.0;
      g.wander_rad_per_m = 0.3;
      g.drape_probability = p;
      const Polyline3 line = GrowCane(g, FlatRow(), options, rng);
      // Length of cane resting within 2 cm of the wire.
      double along = 0.0;
      for (size_t i = 1; i < line.points.size(); ++i) {
        const Eigen::Vector3d& q = line.points[i];
        if (std::abs(q.z() - 1.0) < 0.02 && std::abs(q.y() - 0.8) < 0.02) {
          along += (q - line.points[i - 1]).norm();
        }
      }
      if (p == 1.0) draped += along >= 0.12;
      if (p == 0.0) crossed += along < 0.1;
    }
  }
  EXPECT_GE(draped, 18);
  EXPECT_GE(crossed, 18);
}

TEST(GrowCane, StaysAboveTheGround) {
  const VineGeneratorOptions options;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    VineRng rng(seed);
    CaneGrowth g;
    g.base = {0, 0.8, 0.4};
    g.heading_rad = 2.5;  // pointing down
    g.length_m = 1.8;
    g.base_radius_m = 0.006;
    g.droop_rad_per_m = 3.0;
    const Polyline3 line = GrowCane(g, FlatRow(), options, rng);
    for (const Eigen::Vector3d& q : line.points) EXPECT_GT(q.z(), 0.02);
  }
}

TEST(GrowVine, StandsAtItsRowPositionWithTrunkFirst) {
  const VineGeneratorOptions options;
  const TrellisRow row = MakeTrellisRow(4, options);
  for (int k : {-2, 0, 17}) {
    const VinePlant plant = GrowVine(4, k, options, row);
    EXPECT_NEAR(plant.position_m, k * options.vine_spacing_m, 0.1);
    ASSERT_FALSE(plant.model.canes.empty());
    EXPECT_EQ(plant.model.canes[0].kind, CaneKind::kTrunk);
    EXPECT_DOUBLE_EQ(plant.model.canes[0].polyline.points[0].x(), plant.position_m);
    for (size_t i = 0; i < plant.model.canes.size(); ++i) {
      EXPECT_EQ(plant.model.canes[i].id, CaneId(static_cast<int64_t>(i) + 1));
    }
    EXPECT_TRUE(plant.model.wires.empty());
    EXPECT_TRUE(plant.model.Validate().ok());
  }
}

TEST(GrowVine, ShiftModelXMovesEverything) {
  const VineGeneratorOptions options;
  const TrellisRow row = MakeTrellisRow(4, options);
  VinePlant plant = GrowVine(4, 3, options, row);
  const VineModel before = plant.model;
  ShiftModelX(-2.0, &plant.model);
  EXPECT_NEAR(plant.model.canes[2].polyline.points[4].x(),
              before.canes[2].polyline.points[4].x() - 2.0, 1e-12);
  EXPECT_EQ(plant.model.canes[2].polyline.points[4].z(), before.canes[2].polyline.points[4].z());
  EXPECT_NEAR(plant.model.head.spheres[0].center.x(), before.head.spheres[0].center.x() - 2.0,
              1e-12);
}

}  // namespace
}  // namespace vb::sim
