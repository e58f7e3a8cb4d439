// SPDX-License-Identifier: Apache-2.0
// The simulator's images agree with its ground truth and its calibration: ground-truth cane
// points projected through calibration.yaml land on pixels the renderer drew as that cane.
#include <filesystem>
#include <map>

#include "core/vine_model_json.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/capture/bundle.h"
#include "workers/capture/sim_capture.h"

namespace vb {
namespace {

struct ProjectionStats {
  int visible = 0;      // sampled points that project inside the image
  int on_own_cane = 0;  // ... onto a pixel labelled with the same cane
  int on_foreground = 0;  // ... onto any vine structure (cane, head, neighbour, wire, post)
  int not_blue = 0;     // ... onto a pixel that is not backdrop-blue in the rendered image
};

ProjectionStats ProjectCanes(const VineModel& truth, const CameraCalibration& camera,
                             const LabelImage& labels, const Image& rgb) {
  ProjectionStats stats;
  for (const Cane& cane : truth.canes) {
    for (const Eigen::Vector3d& p : cane.polyline.Sample(0.005)) {
      const auto uv = camera.Project(p);
      if (!uv || !camera.InImage(*uv)) continue;
      const int x = static_cast<int>(std::lround(uv->x()));
      const int y = static_cast<int>(std::lround(uv->y()));
      if (x < 0 || y < 0 || x >= labels.width || y >= labels.height) continue;
      ++stats.visible;
      const uint16_t label = labels.at(x, y);
      if (label == sim::kLabelCaneBase + cane.id.value) ++stats.on_own_cane;
      if (label != sim::kLabelBackground) ++stats.on_foreground;
      const uint8_t* px = rgb.at(x, y);
      if (px[2] < px[0] + 25) ++stats.not_blue;
    }
  }
  return stats;
}

TEST(SimCapture, GroundTruthProjectsOntoRenderedCanesInEveryCamera) {
  auto scene = sim::GenerateScene(7, 3);
  ASSERT_TRUE(scene.ok()) << scene.status();
  capture::SimCaptureOptions options;  // rgb8, noise on, exact calibration
  auto capture = capture::RenderSimCapture(*scene, options, 99);
  ASSERT_TRUE(capture.ok()) << capture.status();
  ASSERT_EQ(capture->bundle.images.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const ProjectionStats s = ProjectCanes(capture->ground_truth, capture->bundle.calibration.cameras[i],
                                           capture->labels[i], capture->bundle.images[i]);
    SCOPED_TRACE(capture->bundle.calibration.cameras[i].name);
    ASSERT_GT(s.visible, 500);
    // Occlusion by nearer canes, the head and wires explains the rest.
    EXPECT_GT(s.on_own_cane, 0.85 * s.visible);
    EXPECT_GT(s.on_foreground, 0.99 * s.visible);
    EXPECT_GT(s.not_blue, 0.95 * s.visible);
  }
}

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
  const std::string dir = ::testing::TempDir() + "/sim_capture_round_trip";
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
