// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/mask_ops.h"

#include <cmath>
#include <random>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

void Fill(BinaryImage* image, int x0, int y0, int x1, int y1, uint8_t v) {
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) image->set(x, y, v);
  }
}

TEST(FlipSmallComponents, DropsSpecksAndKeepsLargeRegions) {
  BinaryImage image(40, 30);
  Fill(&image, 2, 2, 4, 4, 1);      // 9 px speck
  Fill(&image, 10, 5, 30, 25, 1);   // large
  image.set(36, 10, 1);             // 3 px diagonal speck: one component if 8-connected
  image.set(37, 11, 1);
  image.set(38, 12, 1);
  EXPECT_EQ(FlipSmallComponents(1, 9, true, false, &image), 2);
  EXPECT_EQ(image.at(3, 3), 0);
  EXPECT_EQ(image.at(37, 11), 0);
  EXPECT_EQ(image.at(20, 15), 1);
  EXPECT_EQ(image.at(10, 5), 1);
}

TEST(FlipSmallComponents, KeepsAComponentOneLargerThanTheLimit) {
  BinaryImage image(20, 20);
  Fill(&image, 5, 5, 9, 6, 1);  // 10 px
  EXPECT_EQ(FlipSmallComponents(1, 9, true, false, &image), 0);
  EXPECT_EQ(image.at(5, 5), 1);
}

TEST(FlipSmallComponents, FillsEnclosedHolesOnly) {
  BinaryImage image(30, 20);
  Fill(&image, 0, 0, 29, 19, 1);
  image.set(10, 10, 0);           // a pinhole
  Fill(&image, 20, 8, 22, 10, 0);  // a 9 px hole
  Fill(&image, 0, 5, 1, 6, 0);    // a notch on the border: not a hole
  EXPECT_EQ(FlipSmallComponents(0, 8, false, true, &image), 1);
  EXPECT_EQ(image.at(10, 10), 1);
  EXPECT_EQ(image.at(21, 9), 0);
  EXPECT_EQ(image.at(0, 5), 0);
}

TEST(FlipSmallComponents, FourConnectedHolesSplitAtDiagonals) {
  BinaryImage image(10, 10);
  Fill(&image, 0, 0, 9, 9, 1);
  image.set(4, 4, 0);
  image.set(5, 5, 0);
  EXPECT_EQ(FlipSmallComponents(0, 1, false, true, &image), 2);
  EXPECT_EQ(image.at(4, 4), 1);
  EXPECT_EQ(image.at(5, 5), 1);
}

TEST(CappedDistanceTransform, MatchesBruteForce) {
  std::mt19937 random(5);
  BinaryImage sites(97, 61);
  for (int i = 0; i < 25; ++i) sites.set(random() % 97, random() % 61, 1);
  for (int x = 10; x < 80; ++x) sites.set(x, 40 + x / 10, 1);
  for (int cap : {5, 30}) {
    const std::vector<float> d = CappedDistanceTransform(sites, cap);
    for (int y = 0; y < sites.height; ++y) {
      for (int x = 0; x < sites.width; ++x) {
        double best = cap;
        for (int v = 0; v < sites.height; ++v) {
          for (int u = 0; u < sites.width; ++u) {
            if (sites.at(u, v)) best = std::min(best, std::hypot(u - x, v - y));
          }
        }
        ASSERT_NEAR(d[y * sites.width + x], best, 1e-5) << x << "," << y << " cap " << cap;
      }
    }
  }
}

TEST(CappedDistanceTransform, NoSitesIsTheCapEverywhere) {
  const std::vector<float> d = CappedDistanceTransform(BinaryImage(8, 6), 30);
  ASSERT_EQ(d.size(), 48u);
  for (float v : d) EXPECT_EQ(v, 30.0f);
}

}  // namespace
}  // namespace vb::reconstruct
