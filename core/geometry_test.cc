// SPDX-License-Identifier: Apache-2.0
#include "core/geometry.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb {
namespace {

Polyline3 LShape() {
  Polyline3 p;
  p.points = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}};
  p.radii = {0.01, 0.008, 0.004};
  return p;
}

TEST(Polyline3, LengthAndArcLengths) {
  const Polyline3 p = LShape();
  EXPECT_DOUBLE_EQ(p.Length(), 3.0);
  const auto arc = p.ArcLengths();
  ASSERT_EQ(arc.size(), 3u);
  EXPECT_DOUBLE_EQ(arc[1], 1.0);
  EXPECT_DOUBLE_EQ(arc[2], 3.0);
}

TEST(Polyline3, PointRadiusAndTangentAtArcLength) {
  const Polyline3 p = LShape();
  EXPECT_TRUE(p.PointAt(0.5).isApprox(Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_TRUE(p.PointAt(2.0).isApprox(Eigen::Vector3d(1, 1, 0)));
  EXPECT_TRUE(p.PointAt(-1.0).isApprox(Eigen::Vector3d(0, 0, 0)));
  EXPECT_TRUE(p.PointAt(99.0).isApprox(Eigen::Vector3d(1, 2, 0)));
  EXPECT_NEAR(p.RadiusAt(0.5), 0.009, 1e-12);
  EXPECT_NEAR(p.RadiusAt(2.0), 0.006, 1e-12);
  EXPECT_TRUE(p.TangentAt(0.2).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(p.TangentAt(2.5).isApprox(Eigen::Vector3d::UnitY()));
}

TEST(Polyline3, PointAndRadiusGivenArcLengths) {
  const Polyline3 p = LShape();
  const std::vector<double> arc = p.ArcLengths();
  EXPECT_EQ(p.PointAt(1.5, arc), Eigen::Vector3d(1, 0.5, 0));
  EXPECT_NEAR(p.RadiusAt(1.5, arc), 0.007, 1e-15);
  EXPECT_EQ(p.PointAt(-1.0, arc), Eigen::Vector3d(0, 0, 0));  // clamped
  EXPECT_EQ(p.PointAt(4.0, arc), Eigen::Vector3d(1, 2, 0));
  EXPECT_EQ(p.RadiusAt(4.0, arc), 0.004);
  for (double s : {-1.0, 0.2, 1.0, 1.5, 2.5, 4.0}) EXPECT_EQ(p.TangentAt(s, arc), p.TangentAt(s));
  EXPECT_TRUE(p.TangentAt(1.5, arc).isApprox(Eigen::Vector3d::UnitY()));
}

TEST(Polyline3, TruncateAtKeepsTheBasePart) {
  Polyline3 p = LShape();
  p.TruncateAt(2.0);
  ASSERT_EQ(p.points.size(), 3u);
  EXPECT_NEAR(p.Length(), 2.0, 1e-12);
  EXPECT_TRUE(p.points.back().isApprox(Eigen::Vector3d(1, 1, 0)));
  EXPECT_NEAR(p.radii.back(), 0.006, 1e-12);
  Polyline3 q = LShape();
  q.TruncateAt(1.0);  // exactly at a vertex
  EXPECT_EQ(q.points.size(), 2u);
  EXPECT_NEAR(q.Length(), 1.0, 1e-12);
  EXPECT_TRUE(q.Validate("q").ok());
}

TEST(Polyline3, ProjectFindsTheNearestArcLengthAndDistance) {
  const Polyline3 p = LShape();
  double d = -1;
  EXPECT_NEAR(p.Project({0.4, 0.3, 0}, &d), 0.4, 1e-12);
  EXPECT_NEAR(d, 0.3, 1e-12);
  EXPECT_NEAR(p.Project({1.5, 1.5, 0}, &d), 2.5, 1e-12);
  EXPECT_NEAR(d, 0.5, 1e-12);
  EXPECT_NEAR(p.Project({-2, 0, 0}, &d), 0.0, 1e-12);
  EXPECT_NEAR(d, 2.0, 1e-12);
  EXPECT_NEAR(p.Project({1, 5, 0}), 3.0, 1e-12);
  EXPECT_EQ(Polyline3{}.Project({1, 1, 1}), 0.0);
}

TEST(Polyline3, SampleSpacing) {
  const auto s = LShape().Sample(0.005);
  EXPECT_EQ(s.size(), 601u);
  for (size_t i = 1; i < s.size(); ++i) EXPECT_LE((s[i] - s[i - 1]).norm(), 0.005 + 1e-12);
}

TEST(Polyline3, ResampledMatchesPointAndRadiusAtEqualSpacing) {
  const Polyline3 line = LShape();
  const Polyline3 r = line.Resampled(0.4);
  ASSERT_EQ(r.points.size(), 9u);  // length 3 m: round(7.5) + 1 points
  ASSERT_EQ(r.radii.size(), 9u);
  for (size_t k = 0; k < r.points.size(); ++k) {
    const double s = 3.0 * k / 8.0;
    EXPECT_LT((r.points[k] - line.PointAt(s)).norm(), 1e-12) << k;
    EXPECT_NEAR(r.radii[k], line.RadiusAt(s), 1e-12) << k;
  }
  // A step longer than the line still keeps both ends.
  const Polyline3 ends = line.Resampled(10.0);
  ASSERT_EQ(ends.points.size(), 2u);
  EXPECT_EQ(ends.points.back(), line.points.back());
}

TEST(Polyline3, ValidateRejectsBadPolylines) {
  Polyline3 p = LShape();
  p.radii.pop_back();
  EXPECT_NE(p.Validate("canes[0]").message().find("canes[0].radii"), std::string::npos);
  p = LShape();
  p.points[1].y() = std::nan("");
  EXPECT_NE(p.Validate("c").message().find("c.points[1]"), std::string::npos);
  p = LShape();
  p.radii[2] = 0.0;
  EXPECT_EQ(p.Validate("c").code(), absl::StatusCode::kInvalidArgument);
  p.points.resize(1);
  p.radii.resize(1);
  EXPECT_EQ(p.Validate("c").code(), absl::StatusCode::kInvalidArgument);
}

TEST(Distance, PointSegment) {
  double t = -1;
  EXPECT_NEAR(PointSegmentDistance({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, &t), 1.0, 1e-12);
  EXPECT_NEAR(t, 0.5, 1e-12);
  EXPECT_NEAR(PointSegmentDistance({2, 0, 0}, {0, 0, 0}, {1, 0, 0}, &t), 1.0, 1e-12);
  EXPECT_NEAR(t, 1.0, 1e-12);
}

TEST(Distance, SegmentSegmentCrossingParallelAndDegenerate) {
  EXPECT_NEAR(SegmentSegmentDistance({-1, 0, 0}, {1, 0, 0}, {0, -1, 0.3}, {0, 1, 0.3}), 0.3, 1e-12);
  EXPECT_NEAR(SegmentSegmentDistance({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}), 1.0, 1e-12);
  EXPECT_NEAR(SegmentSegmentDistance({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}), 1.0, 1e-12);
  EXPECT_NEAR(SegmentSegmentDistance({0, 0, 0}, {0, 0, 0}, {0, 2, 0}, {0, 2, 0}), 2.0, 1e-12);
  // Brute force agreement on random segments.
  std::srand(3);
  auto r = [] { return static_cast<double>(std::rand()) / RAND_MAX * 2.0 - 1.0; };
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d p0(r(), r(), r()), p1(r(), r(), r()), q0(r(), r(), r()), q1(r(), r(), r());
    double brute = 1e9;
    for (int i = 0; i <= 200; ++i) {
      const Eigen::Vector3d p = p0 + (p1 - p0) * (i / 200.0);
      brute = std::min(brute, PointSegmentDistance(p, q0, q1));
    }
    const double d = SegmentSegmentDistance(p0, p1, q0, q1);
    EXPECT_LE(d, brute + 1e-9);
    EXPECT_GE(d, brute - 0.02);
  }
}

}  // namespace
}  // namespace vb

namespace vb {
namespace {

TEST(Polyline3, MeanBaseDiameterAveragesTheTaperOverTheSpan) {
  Polyline3 line;
  line.points = {{0, 0, 0}, {0.1, 0, 0}, {0.3, 0, 0}};
  line.radii = {0.006, 0.004, 0.002};
  // Radius 6 -> 4 mm over the first 0.1 m: mean diameter 10 mm.
  EXPECT_NEAR(line.MeanBaseDiameter(0.1), 0.010, 1e-12);
  // Over 0.2 m: (0.1 * 5 mm + 0.1 * 3.5 mm) / 0.2 = 4.25 mm radius.
  EXPECT_NEAR(line.MeanBaseDiameter(0.2), 0.0085, 1e-12);
  EXPECT_NEAR(line.MeanBaseDiameter(5.0), line.MeanBaseDiameter(0.3), 1e-12);
  EXPECT_NEAR(line.MeanBaseDiameter(0.0), 0.012, 1e-12);
}

}  // namespace
}  // namespace vb
