// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/skeleton.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

// Pixels within width/2 of segment ab.
void Band(BinaryImage* image, Eigen::Vector2d a, Eigen::Vector2d b, double width) {
  const Eigen::Vector2d d = b - a;
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      const Eigen::Vector2d p(x, y);
      const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      if ((a + t * d - p).norm() <= 0.5 * width) image->set(x, y, 1);
    }
  }
}

int Neighbours(const BinaryImage& image, int x, int y) {
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int u = x + dx;
      const int v = y + dy;
      if ((dx || dy) && u >= 0 && v >= 0 && u < image.width && v < image.height) {
        n += image.at(u, v);
      }
    }
  }
  return n;
}

int Count(const BinaryImage& image) {
  int n = 0;
  for (uint8_t v : image.data) n += v;
  return n;
}

TEST(ThinMask, BandBecomesAThinLineAlongItsMiddle) {
  for (double width : {2.0, 3.0, 6.0, 9.0}) {
    BinaryImage image(80, 60);
    Band(&image, {10, 20}, {70, 42}, width);  // shallow diagonal
    ThinMask(&image);
    int ends = 0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        if (!image.at(x, y)) continue;
        const int n = Neighbours(image, x, y);
        EXPECT_GE(n, 1) << "width " << width << " at " << x << "," << y;
        EXPECT_LE(n, 2) << "width " << width << " at " << x << "," << y;
        ends += n == 1;
        // Within a pixel of the band's axis.
        const Eigen::Vector2d d = Eigen::Vector2d(60, 22).normalized();
        const Eigen::Vector2d r = Eigen::Vector2d(x, y) - Eigen::Vector2d(10, 20);
        EXPECT_LT(std::abs(r.x() * d.y() - r.y() * d.x()), 1.01) << "width " << width;
      }
    }
    EXPECT_EQ(ends, 2) << "width " << width;
    EXPECT_GT(Count(image), 50) << "width " << width;
  }
}

TEST(ThinMask, KeepsAThinDiagonalLine) {
  BinaryImage image(40, 40);
  for (int i = 5; i < 35; ++i) {
    image.set(i, i, 1);
    image.set(i + 1, i, 1);  // a 2-pixel-thick staircase
  }
  ThinMask(&image);
  EXPECT_GE(Count(image), 29);
}

TEST(TraceSkeleton, PlusIsOneJunctionOfFourPaths) {
  BinaryImage image(41, 41);
  for (int i = 5; i <= 35; ++i) {
    image.set(i, 20, 1);
    image.set(20, i, 1);
  }
  SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 4u);
  int junctions = 0;
  for (int n = 0; n < static_cast<int>(graph.nodes.size()); ++n) {
    if (graph.Degree(n) == 4) {
      ++junctions;
      EXPECT_LT((graph.nodes[n].position - Eigen::Vector2d(20, 20)).norm(), 1.0);
    } else {
      EXPECT_EQ(graph.Degree(n), 1);
    }
  }
  EXPECT_EQ(junctions, 1);
  for (const SkeletonGraph::Path& path : graph.paths) EXPECT_NEAR(path.Length(), 14.0, 1.5);
}

TEST(TraceSkeleton, LoopWithoutJunctionIsOnePath) {
  BinaryImage image(30, 30);
  for (int i = 5; i <= 20; ++i) {
    image.set(i, 5, 1);
    image.set(i, 20, 1);
    image.set(5, i, 1);
    image.set(20, i, 1);
  }
  ThinMask(&image);
  const SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 1u);
  EXPECT_EQ(graph.paths[0].node_begin, graph.paths[0].node_end);
  EXPECT_GT(graph.paths[0].Length(), 50.0);
}

TEST(PruneSkeleton, RemovesShortSpurAndJoinsTheRest) {
  BinaryImage image(60, 30);
  for (int x = 5; x <= 55; ++x) image.set(x, 15, 1);
  for (int y = 12; y < 15; ++y) image.set(30, y, 1);  // a 3-pixel spur
  SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 3u);
  PruneSkeleton(PruneOptions{}, [](int, int) { return 3.0; }, &graph);  // canes 6 px wide
  ASSERT_EQ(graph.paths.size(), 1u);
  EXPECT_NEAR(graph.paths[0].Length(), 50.0, 2.0);
  EXPECT_EQ(graph.nodes.size(), 2u);
}

TEST(PruneSkeleton, KeepsBranchesLongerThanTheWidth) {
  BinaryImage image(60, 40);
  for (int x = 5; x <= 55; ++x) image.set(x, 30, 1);
  for (int y = 10; y < 30; ++y) image.set(30, y, 1);
  SkeletonGraph graph = TraceSkeleton(image);
  PruneSkeleton(PruneOptions{}, [](int, int) { return 6.0; }, &graph);  // 12 px: 20 px survives
  EXPECT_EQ(graph.paths.size(), 3u);
}

TEST(PruneSkeleton, KeepsACaneLeavingAThickRegion) {
  // A junction inside a head of radius 30; a 4 px wide cane reaches 12 px beyond the head.
  BinaryImage image(120, 100);
  for (int x = 5; x <= 115; ++x) image.set(x, 60, 1);
  for (int y = 60 - 42; y < 60; ++y) image.set(60, y, 1);
  SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 3u);
  const auto radius = [](int x, int y) { return std::hypot(x - 60, y - 60) < 30 ? 30.0 : 2.0; };
  SkeletonGraph head = graph;
  PruneSkeleton(PruneOptions{}, radius, &head);
  EXPECT_EQ(head.paths.size(), 3u);
  // A 20 px stub on a 30 px wide band is an artefact of thinning.
  for (int y = 0; y < 40; ++y) image.set(60, y, 0);
  graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 3u);
  PruneSkeleton(PruneOptions{}, [](int, int) { return 15.0; }, &graph);
  EXPECT_EQ(graph.paths.size(), 1u);
}

TEST(PruneSkeleton, MergesTwoCloseJunctions) {
  // Two T junctions 6 px apart, as a crossing of two thick canes thins to.
  BinaryImage image(60, 80);
  for (int x = 5; x <= 55; ++x) image.set(x, 40, 1);
  for (int y = 5; y < 40; ++y) image.set(27, y, 1);
  for (int y = 41; y <= 75; ++y) image.set(33, y, 1);
  SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 5u);
  SkeletonGraph thin = graph;
  PruneSkeleton(PruneOptions{}, [](int, int) { return 1.5; }, &thin);
  EXPECT_EQ(thin.paths.size(), 5u);  // canes 3 px wide: two junctions
  PruneSkeleton(PruneOptions{}, [](int, int) { return 6.0; }, &graph);  // 12 px wide: one
  EXPECT_EQ(graph.paths.size(), 4u);
  int degree4 = 0;
  for (int n = 0; n < static_cast<int>(graph.nodes.size()); ++n) degree4 += graph.Degree(n) == 4;
  EXPECT_EQ(degree4, 1);
}

TEST(PruneSkeleton, DropsShortIsolatedPieces) {
  BinaryImage image(30, 30);
  for (int x = 5; x < 9; ++x) image.set(x, 5, 1);
  for (int x = 5; x < 25; ++x) image.set(x, 20, 1);
  SkeletonGraph graph = TraceSkeleton(image);
  ASSERT_EQ(graph.paths.size(), 2u);
  PruneSkeleton(PruneOptions{}, [](int, int) { return 1.5; }, &graph);
  ASSERT_EQ(graph.paths.size(), 1u);
  EXPECT_EQ(graph.paths[0].pixels.front().y(), 20);
}

}  // namespace
}  // namespace vb::reconstruct
