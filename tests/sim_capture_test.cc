// SPDX-License-Identifier: Apache-2.0
// The simulator's images agree with its ground truth and its calibration: ground-truth cane
// points projected through calibration.yaml land on pixels the renderer drew as that cane.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "core/geometry.h"
#include "core/vine_model_json.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/capture/bundle.h"
#include "workers/capture/sim_capture.h"

namespace vb {
namespace {

struct ProjectionStats {
  int visible = 0;        // sampled axis points inside the image, at least 2 px thick
  int on_own_cane = 0;    // ... that land on a pixel labelled with their own cane
  int explained = 0;      // ... on their own cane, or on something that is in front of them
  int not_blue = 0;       // ... on a pixel that is not backdrop-blue in the rendered image
};

// Does the sight line from `eye` to `p` pass through `label`'s geometry before reaching p?
// `slack_m` allows for the pixel-centre ray differing from the exact ray by up to ~0.7 px.
bool Occludes(const sim::Scene& scene, uint16_t label, const Eigen::Vector3d& eye,
              const Eigen::Vector3d& p, double slack_m) {
  // Stop short of p so that p's own cane does not count as its occluder.
  const Eigen::Vector3d end = p + (eye - p).normalized() * 0.004;
  auto hits_polyline = [&](const Polyline3& line) {
    for (size_t k = 0; k + 1 < line.points.size(); ++k) {
      const double r = std::max(line.radii[k], line.radii[k + 1]);
      if (SegmentSegmentDistance(eye, end, line.points[k], line.points[k + 1]) < r + slack_m) return true;
    }
    return false;
  };
  if (label >= sim::kLabelCaneBase) {
    const auto i = scene.vine.IndexOf(CaneId(label - sim::kLabelCaneBase));
    return i.has_value() && hits_polyline(scene.vine.canes[*i].polyline);
  }
  if (label == sim::kLabelWire) {
    for (const Wire& w : scene.vine.wires) {
      for (size_t k = 0; k + 1 < w.points.size(); ++k) {
        if (SegmentSegmentDistance(eye, end, w.points[k], w.points[k + 1]) < w.radius + slack_m) return true;
      }
    }
    return false;
  }
  if (label == sim::kLabelHead) {
    for (const Sphere& s : scene.vine.head.spheres) {
      if (PointSegmentDistance(s.center, eye, end) < s.radius + slack_m) return true;
    }
    return false;
  }
  if (label == sim::kLabelPost) {
    for (const Post& post : scene.vine.posts) {
      if (SegmentSegmentDistance(eye, end, post.base, post.top) < post.radius + slack_m) return true;
    }
    return false;
  }
  if (label == sim::kLabelOtherVine) {
    for (const VineModel& n : scene.neighbours) {
      for (const Cane& c : n.canes) {
        if (hits_polyline(c.polyline)) return true;
      }
      for (const Sphere& s : n.head.spheres) {
        if (PointSegmentDistance(s.center, eye, end) < s.radius + slack_m) return true;
      }
    }
  }
  return false;
}

ProjectionStats ProjectCanes(const sim::Scene& scene, const CameraCalibration& camera,
                             const LabelImage& labels, const Image& rgb) {
  ProjectionStats stats;
  const Eigen::Vector3d eye = camera.CentreInPlatform();
  const double fx = camera.camera_matrix(0, 0);
  for (const Cane& cane : scene.vine.canes) {
    const double length = cane.polyline.Length();
    for (double s = 0.0; s <= length; s += 0.005) {
      const Eigen::Vector3d p = cane.polyline.PointAt(s);
      const auto uv = camera.Project(p);
      if (!uv || !camera.InImage(*uv)) continue;
      const double depth_m = (p - eye).norm();
      // Sub-pixel parts (thin tips far from the centre) are legitimately blended with the
      // backdrop; only structure at least 2 px thick must carry its label.
      if (cane.polyline.RadiusAt(s) * fx / depth_m < 1.0) continue;
      const int x = static_cast<int>(std::lround(uv->x()));
      const int y = static_cast<int>(std::lround(uv->y()));
      if (x < 0 || y < 0 || x >= labels.width || y >= labels.height) continue;
      ++stats.visible;
      const uint16_t label = labels.at(x, y);
      const bool own = label == sim::kLabelCaneBase + cane.id.value;
      stats.on_own_cane += own;
      const double slack_m = 0.75 * depth_m / fx;
      const bool ok = own || Occludes(scene, label, eye, p, slack_m);
      stats.explained += ok;
      const uint8_t* px = rgb.at(x, y);
      if (px[2] < px[0] + 25) ++stats.not_blue;
    }
  }
  return stats;
}

class SimCaptureProjection : public ::testing::TestWithParam<std::pair<uint64_t, int>> {};

TEST_P(SimCaptureProjection, GroundTruthProjectsOntoRenderedCanesInEveryCamera) {
  auto scene = sim::GenerateScene(GetParam().first, GetParam().second);
  ASSERT_TRUE(scene.ok()) << scene.status();
  capture::SimCaptureOptions options;  // rgb8, noise on, exact calibration
  auto capture = capture::RenderSimCapture(*scene, options, 99);
  ASSERT_TRUE(capture.ok()) << capture.status();
  ASSERT_EQ(capture->bundle.images.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const ProjectionStats s = ProjectCanes(*scene, capture->bundle.calibration.cameras[i],
                                           capture->labels[i], capture->bundle.images[i]);
    SCOPED_TRACE(capture->bundle.calibration.cameras[i].name);
    ASSERT_GT(s.visible, 500);
    // Every point is drawn as its own cane or hidden behind something truly in front of it.
    EXPECT_GE(s.explained, 0.995 * s.visible) << s.explained << " of " << s.visible;
    EXPECT_GT(s.on_own_cane, 0.7 * s.visible);
    EXPECT_GT(s.not_blue, 0.95 * s.visible);
  }
}

INSTANTIATE_TEST_SUITE_P(Stops, SimCaptureProjection,
                         ::testing::Values(std::pair<uint64_t, int>{7, 3},
                                           std::pair<uint64_t, int>{21, 0},
                                           std::pair<uint64_t, int>{4, -11}));

TEST(SimCapture, CalibrationErrorMovesProjectionsButStaysNear) {
  auto scene = sim::GenerateScene(7, 3);
  ASSERT_TRUE(scene.ok());
  capture::SimCaptureOptions options;
  options.calibration_error_px = 1.0;
  auto capture = capture::RenderSimCapture(*scene, options, 99);
  ASSERT_TRUE(capture.ok());
  auto exact_options = options;
  exact_options.calibration_error_px = 0.0;
  auto exact = capture::RenderSimCapture(*scene, exact_options, 99);
  ASSERT_TRUE(exact.ok());
  for (size_t i = 0; i < 3; ++i) {
    double sum_sq = 0.0;
    int n = 0;
    for (const Cane& cane : scene->vine.canes) {
      for (const Eigen::Vector3d& p : cane.polyline.Sample(0.05)) {
        const auto a = capture->bundle.calibration.cameras[i].Project(p);
        const auto b = exact->bundle.calibration.cameras[i].Project(p);
        if (!a || !b || !exact->bundle.calibration.cameras[i].InImage(*b)) continue;
        sum_sq += (*a - *b).squaredNorm();
        ++n;
      }
    }
    ASSERT_GT(n, 50);
    const double rms = std::sqrt(sum_sq / n);
    EXPECT_GT(rms, 0.4);
    EXPECT_LT(rms, 2.5);
  }
}

TEST(SimCapture, BundleRoundTripsThroughImport) {
  auto scene = sim::GenerateScene(7, 3);
  ASSERT_TRUE(scene.ok());
  capture::SimCaptureOptions options;
  options.render.pixel_format = PixelFormat::kBayerRg8;
  auto capture = capture::RenderSimCapture(*scene, options, 5);
  ASSERT_TRUE(capture.ok());
  const std::string dir = ::testing::TempDir() + "/sim_capture_round_trip_" +
                          std::to_string(getpid());
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(capture::WriteSimCapture(dir, *capture).ok());
  auto bundle = capture::ReadBundle(dir);
  ASSERT_TRUE(bundle.ok()) << bundle.status();
  ASSERT_EQ(bundle->images.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(bundle->images[i].format, PixelFormat::kBayerRg8);
    EXPECT_EQ(bundle->images[i].data, capture->bundle.images[i].data);
    EXPECT_TRUE(bundle->calibration.cameras[i].camera_matrix.isApprox(
        capture->bundle.calibration.cameras[i].camera_matrix, 1e-12));
    auto labels = capture::ReadLabelPng(dir + "/labels_" + bundle->metadata.cameras[i].name + ".png");
    ASSERT_TRUE(labels.ok()) << labels.status();
    EXPECT_EQ(labels->data, capture->labels[i].data);
    auto rgb = capture::ToRgb(bundle->images[i]);
    ASSERT_TRUE(rgb.ok());
    EXPECT_EQ(rgb->format, PixelFormat::kRgb8);
  }
  auto truth = ReadVineModel(dir + "/ground_truth.json");
  ASSERT_TRUE(truth.ok()) << truth.status();
  EXPECT_EQ(truth->canes.size(), scene->vine.canes.size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vb
