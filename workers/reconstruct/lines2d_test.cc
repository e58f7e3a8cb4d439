// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/lines2d.h"

#include <numeric>
#include <random>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

std::vector<int> All(size_t n) {
  std::vector<int> indices(n);
  std::iota(indices.begin(), indices.end(), 0);
  return indices;
}

TEST(FitLineLeastSquares, RecoversALine) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 20; ++i) points.emplace_back(i, 0.5 * i + 3.0 + (i % 2 ? 0.1 : -0.1));
  const Eigen::Vector3d line = FitLineLeastSquares(points, All(points.size()));
  EXPECT_NEAR(line.head<2>().norm(), 1.0, 1e-12);
  // y = 0.5 x + 3  <=>  0.5 x - y + 3 = 0.
  const Eigen::Vector3d truth = Eigen::Vector3d(0.5, -1.0, 3.0) / std::hypot(0.5, 1.0);
  EXPECT_LT(std::min((line - truth).norm(), (line + truth).norm()), 0.03);
}

TEST(FitLineLeastSquares, DegenerateSetsGiveZero) {
  const std::vector<Eigen::Vector2d> points = {{1, 1}, {1, 1}};
  EXPECT_EQ(FitLineLeastSquares(points, {0, 1}), Eigen::Vector3d::Zero());
  EXPECT_EQ(FitLineLeastSquares(points, {0}), Eigen::Vector3d::Zero());
}

TEST(FitLinesRansac, FindsTwoLinesAmongOutliers) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 100; ++i) points.emplace_back(i, 10.0);         // y = 10
  for (int i = 0; i < 60; ++i) points.emplace_back(50.0 + 0.1 * i, i);  // steep
  std::mt19937 random(3);
  for (int i = 0; i < 40; ++i) points.emplace_back(random() % 100, random() % 100);
  RansacOptions options;
  options.inlier_distance = 0.5;
  options.min_support = 30;
  options.iterations = 200;
  const std::vector<LinePiece> lines = FitLinesRansac(points, All(points.size()), options);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_GE(lines[0].inliers.size(), 100u);
  EXPECT_NEAR(lines[0].Distance({30.0, 10.0}), 0.0, 0.05);
  EXPECT_NEAR((lines[0].end - lines[0].begin).norm(), 99.0, 1.0);
  EXPECT_GE(lines[1].inliers.size(), 59u);  // (51, 10) went to the first line
  EXPECT_NEAR(lines[1].Distance({53.0, 30.0}), 0.0, 0.1);
}

TEST(MergeCollinear, JoinsPiecesOfOneLineAndKeepsParallelLinesApart) {
  std::vector<Eigen::Vector2d> points;
  std::vector<LinePiece> pieces;
  const auto piece = [&](double x0, double x1, double y) {
    LinePiece p;
    for (double x = x0; x <= x1; x += 1.0) {
      p.inliers.push_back(static_cast<int>(points.size()));
      points.emplace_back(x, y + 0.01 * x);
    }
    p.line = FitLineLeastSquares(points, p.inliers);
    UpdateExtent(points, &p);
    pieces.push_back(p);
  };
  piece(0, 40, 10);
  piece(50, 90, 10);
  piece(100, 140, 10);
  piece(0, 140, 30);  // a parallel line 20 units away
  const std::vector<LinePiece> merged = MergeCollinear(points, pieces, 2.0, 0.05);
  ASSERT_EQ(merged.size(), 2u);
  EXPECT_EQ(merged[0].inliers.size(), 141u);  // largest support first
  EXPECT_EQ(merged[1].inliers.size(), 123u);
  EXPECT_NEAR(merged[1].Distance({70.0, 10.7}), 0.0, 1e-6);
  EXPECT_NEAR(std::abs((merged[1].end - merged[1].begin).x()), 140.0, 0.1);
}

}  // namespace
}  // namespace vb::reconstruct
