// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/structure2d.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kFocal = 300.0;

// A pinhole camera at the platform origin looking along +z (optionally with lens distortion).
CameraCalibration TestCamera(bool distortion = false) {
  CameraCalibration camera;
  camera.name = "test";
  camera.image_width = kWidth;
  camera.image_height = kHeight;
  camera.camera_matrix << kFocal, 0, 160, 0, kFocal, 120, 0, 0, 1;
  if (distortion) camera.distortion = {-0.2, 0.05, 0.0, 0.0, 0.0};
  return camera;
}

// Paints the pixels within width/2 of the segment ab (with round caps).
void PaintBand(ClassImage* image, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
               double width, PixelClass cls) {
  const Eigen::Vector2d d = b - a;
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      const Eigen::Vector2d p(x, y);
      const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      if ((a + t * d - p).norm() <= 0.5 * width) image->set(x, y, cls);
    }
  }
}

double DistanceToLine(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = (b - a).normalized();
  const Eigen::Vector2d r = p - a;
  return std::abs(r.x() * d.y() - r.y() * d.x());
}

View2D MustExtract(const ClassImage& classes, const CameraCalibration& camera = TestCamera(),
                   const Structure2DOptions& options = {}) {
  absl::StatusOr<View2D> view = ExtractStructure(classes, camera, options, Deadline::Infinite());
  EXPECT_TRUE(view.ok()) << view.status();
  return view.ok() ? *std::move(view) : View2D{};
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

std::vector<int> Degrees(const View2D& view) {
  std::vector<int> degrees;
  for (const Node2D& node : view.nodes) degrees.push_back(static_cast<int>(node.segments.size()));
  std::sort(degrees.begin(), degrees.end());
  return degrees;
}

TEST(ExtractStructure, StraightBandIsOneSegmentOnItsCentreLine) {
  struct Case {
    Eigen::Vector2d a, b;
    double width;
  };
  for (const Case& c : {Case{{40, 100.3}, {280, 141.7}, 7.0}, Case{{30, 120.5}, {290, 120.5}, 6.0},
                        Case{{60, 30}, {250, 200}, 4.0}, Case{{100, 20}, {110, 220}, 11.0}}) {
    ClassImage classes(kWidth, kHeight);
    PaintBand(&classes, c.a, c.b, c.width, PixelClass::kForeground);
    const View2D view = MustExtract(classes);
    ASSERT_EQ(view.segments.size(), 1u) << "width " << c.width;
    ASSERT_EQ(view.nodes.size(), 2u);
    const Segment2D& segment = view.segments[0];
    ASSERT_EQ(segment.points.size(), segment.widths_px.size());
    const Eigen::Vector2d axis = (c.b - c.a).normalized();
    double signed_sum = 0.0;
    int count = 0;
    for (size_t i = 0; i < segment.points.size(); ++i) {
      const Eigen::Vector2d& p = segment.points[i];
      if ((p - c.a).norm() < c.width || (p - c.b).norm() < c.width) continue;  // round caps
      // A binary band's staircase edges leave up to ~0.5 px of ripple; no bias.
      EXPECT_LT(DistanceToLine(p, c.a, c.b), 0.5) << "width " << c.width << " point " << i;
      signed_sum += (p - c.a).x() * axis.y() - (p - c.a).y() * axis.x();
      ++count;
      if (i > 0) {
        const double step = (p - segment.points[i - 1]).norm();
        EXPECT_GT(step, 0.3);
        EXPECT_LT(step, 2.0);
      }
    }
    ASSERT_GT(count, 100);
    EXPECT_LT(std::abs(signed_sum / count), 0.1) << "width " << c.width;
    EXPECT_NEAR(Median(segment.widths_px), c.width, 0.75) << "width " << c.width;
    // The ends reach the band's ends (its caps).
    const double length = (c.b - c.a).norm() + c.width;
    EXPECT_NEAR((segment.points.back() - segment.points.front()).norm(), length, 3.0);
    EXPECT_EQ(view.nodes[segment.node_begin].position, segment.points.front());
    EXPECT_EQ(view.nodes[segment.node_end].position, segment.points.back());
    // The centreline distance is 0 on the line and grows away from it.
    const int x = static_cast<int>(std::lround(segment.points[segment.points.size() / 2].x()));
    const int y = static_cast<int>(std::lround(segment.points[segment.points.size() / 2].y()));
    EXPECT_LE(view.centreline_distance_px[y * kWidth + x], 1.0f);
    EXPECT_EQ(view.centreline_distance_px[0], kCentrelineDistanceCapPx);
    // A thin band is not thick.
    for (uint8_t t : view.thick_mask) ASSERT_EQ(t, 0);
  }
}

TEST(ExtractStructure, YIsOneJunctionOfThreeSegments) {
  ClassImage classes(kWidth, kHeight);
  const Eigen::Vector2d hub(160, 130);
  PaintBand(&classes, {160, 230}, hub, 9.0, PixelClass::kForeground);
  PaintBand(&classes, hub, {80, 20}, 7.0, PixelClass::kForeground);
  PaintBand(&classes, hub, {250, 30}, 6.0, PixelClass::kForeground);
  const View2D view = MustExtract(classes);
  EXPECT_EQ(view.segments.size(), 3u);
  EXPECT_EQ(Degrees(view), (std::vector<int>{1, 1, 1, 3}));
  for (const Node2D& node : view.nodes) {
    if (node.segments.size() == 3) {
      EXPECT_LT((node.position - hub).norm(), 5.0);
    }
  }
}

TEST(ExtractStructure, CrossingCanesJoinFourSegmentsAtAJunction) {
  for (double angle_deg : {90.0, 60.0, 35.0}) {
    ClassImage classes(kWidth, kHeight);
    const Eigen::Vector2d centre(160, 120);
    const Eigen::Vector2d u(1, 0);
    const double a = angle_deg * M_PI / 180;
    const Eigen::Vector2d v(std::cos(a), std::sin(a));
    PaintBand(&classes, centre - 110 * u, centre + 110 * u, 7.0, PixelClass::kForeground);
    PaintBand(&classes, centre - 100 * v, centre + 100 * v, 8.0, PixelClass::kForeground);
    const View2D view = MustExtract(classes);
    const std::vector<int> degrees = Degrees(view);
    // One junction of four, or two junctions of three close together (a shallow crossing).
    if (degrees.back() == 4) {
      EXPECT_EQ(degrees, (std::vector<int>{1, 1, 1, 1, 4})) << angle_deg;
      EXPECT_EQ(view.segments.size(), 4u);
    } else {
      EXPECT_EQ(degrees, (std::vector<int>{1, 1, 1, 1, 3, 3})) << angle_deg;
      EXPECT_EQ(view.segments.size(), 5u);
    }
    for (const Node2D& node : view.nodes) {
      if (node.segments.size() >= 3) {
        EXPECT_LT((node.position - centre).norm(), 12.0) << angle_deg;
      }
    }
    // No segment jumps from one cane to the other away from the crossing.
    for (const Segment2D& segment : view.segments) {
      for (const Eigen::Vector2d& p : segment.points) {
        if ((p - centre).norm() < 15.0) continue;
        const double du = DistanceToLine(p, centre, centre + u);
        const double dv = DistanceToLine(p, centre, centre + v);
        EXPECT_LT(std::min(du, dv), 0.75) << angle_deg;
      }
    }
  }
}

TEST(ExtractStructure, WireInFrontOfACaneIsBridged) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {150, 10}, {170, 230}, 8.0, PixelClass::kForeground);
  PaintBand(&classes, {0, 118}, {319, 124}, 3.0, PixelClass::kWire);
  const View2D view = MustExtract(classes);
  ASSERT_EQ(view.segments.size(), 1u);
  EXPECT_GT((view.segments[0].points.back() - view.segments[0].points.front()).norm(), 200.0);
  // The wire itself is still a wire.
  ASSERT_EQ(view.wires.size(), 1u);
}

TEST(ExtractStructure, WithoutBridgingTheWireSplitsTheCane) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {150, 10}, {170, 230}, 8.0, PixelClass::kForeground);
  PaintBand(&classes, {0, 118}, {319, 124}, 3.0, PixelClass::kWire);
  Structure2DOptions options;
  options.max_wire_gap_px = 0;
  EXPECT_EQ(MustExtract(classes, TestCamera(), options).segments.size(), 2u);
}

TEST(ExtractStructure, KeepsASmallPieceOfCaneButDropsASpeck) {
  // A thin cane seen only over 14 px (a 2 px band, 28 px of foreground: what segmentation leaves
  // of a thin, faint cane between occluders) is kept; a 2x3 px speck is noise.
  ClassImage classes(kWidth, kHeight);
  for (int x = 100; x < 114; ++x)
    for (int y = 60; y < 62; ++y) classes.set(x, y, PixelClass::kForeground);
  for (int x = 200; x < 203; ++x)
    for (int y = 150; y < 152; ++y) classes.set(x, y, PixelClass::kForeground);
  const View2D view = MustExtract(classes);
  ASSERT_EQ(view.segments.size(), 1u);
  for (const Eigen::Vector2d& p : view.segments[0].points) {
    EXPECT_NEAR(p.y(), 60.5, 1.0);
    EXPECT_GE(p.x(), 99.0);
    EXPECT_LE(p.x(), 114.0);
  }
  // With the previous default (30 px) the piece went as a speck.
  Structure2DOptions options;
  options.min_speck_area_px = 30;
  EXPECT_TRUE(MustExtract(classes, TestCamera(), options).segments.empty());
}

TEST(ExtractStructure, ThickDiscIsThickAndThinBandIsNot) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {100, 120}, {100, 120.01}, 60.0, PixelClass::kForeground);  // a disc
  PaintBand(&classes, {130, 120}, {300, 60}, 8.0, PixelClass::kForeground);
  const View2D view = MustExtract(classes);
  const auto thick = [&](int x, int y) { return view.thick_mask[y * kWidth + x]; };
  EXPECT_EQ(thick(100, 120), 1);
  EXPECT_EQ(thick(100, 93), 1);   // near the rim: the opening keeps the whole disc
  EXPECT_EQ(thick(73, 120), 1);
  EXPECT_EQ(thick(100, 85), 0);   // outside
  EXPECT_EQ(thick(215, 90), 0);   // on the band
  EXPECT_EQ(thick(280, 67), 0);
  int count = 0;
  for (uint8_t t : view.thick_mask) count += t;
  EXPECT_NEAR(count, M_PI * 30 * 30, 0.1 * M_PI * 30 * 30);
}

TEST(ExtractStructure, WireLinesAreRecoveredInNormalisedCoordinates) {
  for (bool distortion : {false, true}) {
    const CameraCalibration camera = TestCamera(distortion);
    ClassImage classes(kWidth, kHeight);
    // Two straight lines in normalised coordinates, drawn through the lens.
    const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> truth = {
        {{-0.6, -0.1}, {0.6, -0.05}}, {{-0.6, 0.2}, {0.6, 0.26}}};
    for (const auto& [a, b] : truth) {
      for (int k = 0; k <= 4000; ++k) {
        const Eigen::Vector2d uv = camera.NormalisedToPixel(a + (b - a) * k / 4000.0);
        for (double dy : {-0.5, 0.5}) {
          const int x = static_cast<int>(std::lround(uv.x()));
          const int y = static_cast<int>(std::lround(uv.y() + dy));
          if (x >= 0 && y >= 0 && x < kWidth && y < kHeight) classes.set(x, y, PixelClass::kWire);
        }
      }
    }
    // Canes in front split the wires into pieces.
    PaintBand(&classes, {100, 0}, {105, 239}, 9.0, PixelClass::kForeground);
    PaintBand(&classes, {220, 0}, {210, 239}, 7.0, PixelClass::kForeground);
    const View2D view = MustExtract(classes, camera);
    ASSERT_EQ(view.wires.size(), 2u) << "distortion " << distortion;
    for (const auto& [a, b] : truth) {
      int matched = 0;
      for (const Line2D& wire : view.wires) {
        const double da = std::abs(wire.line.dot(a.homogeneous()));
        const double db = std::abs(wire.line.dot(b.homogeneous()));
        if (da < 3.0 / kFocal && db < 3.0 / kFocal) {
          ++matched;
          EXPECT_NEAR(wire.line.head<2>().norm(), 1.0, 1e-9);
          EXPECT_LT(std::abs(wire.line.dot(((a + b) / 2).homogeneous())), 0.5 / kFocal);
          EXPECT_NEAR(wire.width_px, 2.0, 0.6);
          // The extent spans the image (both ends beyond the canes).
          EXPECT_GT(std::abs(wire.end.x() - wire.begin.x()), 0.8);
        }
      }
      EXPECT_EQ(matched, 1) << "distortion " << distortion;
    }
  }
}

TEST(ExtractStructure, ShortWireFragmentsAreRejected) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {50, 50}, {90, 52}, 2.0, PixelClass::kWire);
  EXPECT_TRUE(MustExtract(classes).wires.empty());
}

TEST(ExtractStructure, PostAxisIsRecovered) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {200, -10}, {206, 250}, 30.0, PixelClass::kPost);
  PaintBand(&classes, {0, 100}, {319, 100}, 9.0, PixelClass::kForeground);  // a cane in front
  const View2D view = MustExtract(classes);
  ASSERT_EQ(view.posts.size(), 1u);
  const Line2D& post = view.posts[0];
  for (double v : {0.0, 120.0, 239.0}) {
    const double u = 200 + 6 * (v + 10) / 260;
    const Eigen::Vector2d n((u - 160) / kFocal, (v - 120) / kFocal);
    EXPECT_LT(std::abs(post.line.dot(n.homogeneous())) * kFocal, 0.5) << v;
  }
  EXPECT_NEAR(post.width_px, 30.0, 1.5);
  EXPECT_GT(std::abs(post.end.y() - post.begin.y()) * kFocal, 220.0);
  EXPECT_GT(post.support_px, 5000);
}

TEST(ExtractStructure, EmptyAndFullImagesDoNotFail) {
  ClassImage empty(kWidth, kHeight);
  const View2D view = MustExtract(empty);
  EXPECT_TRUE(view.segments.empty());
  EXPECT_TRUE(view.wires.empty());
  EXPECT_TRUE(view.posts.empty());
  ASSERT_EQ(view.centreline_distance_px.size(), static_cast<size_t>(kWidth * kHeight));
  EXPECT_EQ(view.centreline_distance_px[123], kCentrelineDistanceCapPx);

  ClassImage full(kWidth, kHeight);
  std::fill(full.data.begin(), full.data.end(), static_cast<uint8_t>(PixelClass::kForeground));
  const View2D full_view = MustExtract(full);
  EXPECT_EQ(full_view.thick_mask[120 * kWidth + 160], 1);
  for (const Segment2D& segment : full_view.segments) EXPECT_GE(segment.points.size(), 2u);

  for (PixelClass cls : {PixelClass::kWire, PixelClass::kPost}) {
    ClassImage all(kWidth, kHeight);
    std::fill(all.data.begin(), all.data.end(), static_cast<uint8_t>(cls));
    MustExtract(all);
  }
}

TEST(ExtractStructure, SizeMismatchFails) {
  ClassImage classes(kWidth + 1, kHeight);
  const absl::StatusOr<View2D> view =
      ExtractStructure(classes, TestCamera(), {}, Deadline::Infinite());
  EXPECT_EQ(view.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(view.status().message()).find("size"), std::string::npos);

  ClassImage truncated(kWidth, kHeight);
  truncated.data.resize(100);
  EXPECT_EQ(ExtractStructure(truncated, TestCamera(), {}, Deadline::Infinite()).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(ExtractStructure, BadClassValueAndBadCalibrationFail) {
  ClassImage classes(kWidth, kHeight);
  classes.data[77] = 9;
  EXPECT_EQ(ExtractStructure(classes, TestCamera(), {}, Deadline::Infinite()).status().code(),
            absl::StatusCode::kInvalidArgument);
  CameraCalibration camera = TestCamera();
  camera.camera_matrix(0, 0) = std::nan("");
  EXPECT_EQ(ExtractStructure(ClassImage(kWidth, kHeight), camera, {}, Deadline::Infinite())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(ExtractStructure, ExpiredDeadlineFails) {
  ClassImage classes(kWidth, kHeight);
  PaintBand(&classes, {40, 100}, {280, 140}, 7.0, PixelClass::kForeground);
  EXPECT_EQ(ExtractStructure(classes, TestCamera(), {}, Deadline::In(0.0)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  std::atomic<bool> cancelled{true};
  EXPECT_EQ(
      ExtractStructure(classes, TestCamera(), {}, Deadline::In(10.0, &cancelled)).status().code(),
      absl::StatusCode::kCancelled);
}

TEST(Structure2DOptions, ValidateRejectsBadFields) {
  EXPECT_TRUE(Structure2DOptions{}.Validate().ok());
  Structure2DOptions options;
  options.thick_radius_px = 0.5;
  EXPECT_NE(std::string(options.Validate().message()).find("thick_radius_px"), std::string::npos);
  options = {};
  options.wire_inlier_px = std::nan("");
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  options = {};
  options.max_post_tilt_deg = 95;
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  options = {};
  options.min_speck_area_px = -1;
  EXPECT_EQ(ExtractStructure(ClassImage(kWidth, kHeight), TestCamera(), options,
                             Deadline::Infinite())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vb::reconstruct
