// SPDX-License-Identifier: Apache-2.0
#include "sim/trellis.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb::sim {
namespace {

TEST(Trellis, IsAPureFunctionOfTheSeed) {
  const VineGeneratorOptions options;
  const TrellisRow a = MakeTrellisRow(11, options);
  const TrellisRow b = MakeTrellisRow(11, options);
  const TrellisRow c = MakeTrellisRow(12, options);
  ASSERT_EQ(a.wires.size(), b.wires.size());
  EXPECT_EQ(a.post_offset_m, b.post_offset_m);
  for (size_t i = 0; i < a.wires.size(); ++i) EXPECT_EQ(a.wires[i].height_m, b.wires[i].height_m);
  EXPECT_NE(a.post_offset_m, c.post_offset_m);
}

TEST(Trellis, WiresAreOrderedFruitingFirstAndFitOnThePosts) {
  const VineGeneratorOptions options;
  for (uint64_t seed = 0; seed < 100; ++seed) {
    const TrellisRow row = MakeTrellisRow(seed, options);
    ASSERT_GE(row.wires.size(), 3u);
    ASSERT_LE(row.wires.size(), 4u);
    EXPECT_GE(row.wires[0].height_m, options.fruiting_wire_min_m);
    EXPECT_LE(row.wires[0].height_m, options.fruiting_wire_max_m);
    for (size_t i = 1; i < row.wires.size(); ++i) {
      EXPECT_GT(row.wires[i].height_m, row.wires[i - 1].height_m + 0.1);
      EXPECT_LT(row.wires[i].height_m, options.post_height_m);
    }
    EXPECT_GE(row.post_offset_m, 0.0);
    EXPECT_LT(row.post_offset_m, options.post_spacing_m);
  }
}

TEST(Trellis, WiresSagParabolicallyBetweenPosts) {
  const VineGeneratorOptions options;
  const TrellisRow row = MakeTrellisRow(5, options);
  const TrellisWire& wire = row.wires[0];
  const double post = 3 * options.post_spacing_m + row.post_offset_m;
  EXPECT_NEAR(WireHeightAt(row, wire, post, options), wire.height_m, 1e-12);
  EXPECT_NEAR(WireHeightAt(row, wire, post + 0.5 * options.post_spacing_m, options),
              wire.height_m - wire.sag_m, 1e-12);
  EXPECT_NEAR(WireHeightAt(row, wire, post + 0.25 * options.post_spacing_m, options),
              wire.height_m - 0.75 * wire.sag_m, 1e-12);
  EXPECT_GT(wire.sag_m, 0.0);
}

TEST(Trellis, AddTrellisPutsPostsAndWiresInThePlatformFrame) {
  const VineGeneratorOptions options;
  const TrellisRow row = MakeTrellisRow(5, options);
  // Stop with a post exactly 1 m ahead of the rig.
  const double origin = 4 * options.post_spacing_m + row.post_offset_m - 1.0;
  VineModel model;
  AddTrellisToModel(row, origin, options, &model);
  ASSERT_EQ(model.posts.size(), 1u);  // the next posts are >= 5 m away
  EXPECT_NEAR(model.posts[0].base.x(), 1.0, 1e-9);
  EXPECT_EQ(model.posts[0].id, PostId(1));
  ASSERT_EQ(model.wires.size(), row.wires.size());
  for (size_t i = 0; i < model.wires.size(); ++i) {
    const Wire& w = model.wires[i];
    EXPECT_EQ(w.id, row.wires[i].id);
    bool at_post = false;
    for (size_t k = 0; k < w.points.size(); ++k) {
      if (k > 0) {
        EXPECT_GT(w.points[k].x(), w.points[k - 1].x());
      }
      if (std::abs(w.points[k].x() - 1.0) < 1e-9) {
        at_post = true;
        EXPECT_NEAR(w.points[k].z(), row.wires[i].height_m, 1e-9);
      }
    }
    EXPECT_TRUE(at_post);
  }
  EXPECT_TRUE(model.Validate().ok());
}

}  // namespace
}  // namespace vb::sim
