// SPDX-License-Identifier: Apache-2.0
#include "core/view_coverage.h"

#include <cmath>
#include <optional>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "core/vine_model_test_util.h"

namespace vb {
namespace {

using ::testing::HasSubstr;

// A distortion-free 1000x1000 camera with f = 500 px at (x, 0, 0), looking along +y, image down =
// platform -z: on the plane y = 1 it sees exactly x - 1 <= X < x + 1 and -1 < Z <= 1.
CameraCalibration Pinhole(const std::string& name, double x) {
  CameraCalibration c;
  c.name = name;
  c.image_width = 1000;
  c.image_height = 1000;
  c.camera_matrix << 500, 0, 499.5, 0, 500, 499.5, 0, 0, 1;
  c.rotation_camera_from_platform << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  c.translation_camera_from_platform = -c.rotation_camera_from_platform * Eigen::Vector3d(x, 0, 0);
  return c;
}

// Camera A at x = 0 sees X in [-1, 1) on the plane y = 1, camera B at x = 1 sees [0, 2).
RigCalibration TwoCameras() {
  RigCalibration rig;
  rig.cameras = {Pinhole("a", 0.0), Pinhole("b", 1.0)};
  return rig;
}

TEST(ViewCoverage, SplitsACanePartlyOutsideEachCamera) {
  VineModel truth;
  // From X = -1.5 to 1.5: [0, 1) in both images, [-1, 0) and [1, 1.5] in one, [-1.5, -1) in none.
  // A trunk outside both images (behind the cameras) carries the cane; it is 0.5 m long.
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {-1.5, -1, 0}, {-1.5, -0.5, 0}));
  truth.canes.push_back(StraightCane(2, 1, CaneKind::kCane, {-1.5, 1, 0}, {1.5, 1, 0}));
  const auto all = SampleViewCoverage(truth, TwoCameras(), 0.001);
  ASSERT_TRUE(all.ok()) << all.status();
  std::vector<CoverageSample> cane;
  for (const CoverageSample& s : *all)
    if (s.cane_index == 1) cane.push_back(s);
  const auto c = std::optional<ViewCoverage>(SummariseViewCoverage(cane, 2));
  EXPECT_NEAR(c->truth_cane_length_m, 3.0, 1e-9);
  EXPECT_NEAR(c->in_two_or_more_fraction, 1.0 / 3.0, 1e-3);
  EXPECT_NEAR(c->in_one_fraction, 0.5, 1e-3);
  EXPECT_NEAR(c->in_none_fraction, 1.0 / 6.0, 1e-3);
  EXPECT_DOUBLE_EQ(c->trunk_in_fewer_than_two_fraction, 0.0);
  ASSERT_EQ(c->side_fraction.size(), 2u);
  // Camera a misses 0.5 m on each side; camera b misses 1.5 m on the left and nothing else.
  const auto& a = c->side_fraction[0];
  const auto& b = c->side_fraction[1];
  EXPECT_NEAR(a[static_cast<int>(ImageSide::kInside)], 2.0 / 3.0, 1e-3);
  EXPECT_NEAR(a[static_cast<int>(ImageSide::kBeyondLeft)], 0.5 / 3.0, 1e-3);
  EXPECT_NEAR(a[static_cast<int>(ImageSide::kBeyondRight)], 0.5 / 3.0, 1e-3);
  EXPECT_NEAR(b[static_cast<int>(ImageSide::kBeyondLeft)], 0.5, 1e-3);
  EXPECT_NEAR(b[static_cast<int>(ImageSide::kBeyondRight)], 0.0, 1e-12);
  EXPECT_NEAR(b[static_cast<int>(ImageSide::kBeyondTop)] + b[static_cast<int>(ImageSide::kBeyondBottom)],
              0.0, 1e-12);
}

TEST(ViewCoverage, CountsATrunkBelowTheImagesAndSkipsSpurs) {
  VineModel truth;
  // Trunk from Z = -2 to 0.5 at X = 0.5 (inside both images across): in view for Z > -1 only.
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0.5, 1, -2}, {0.5, 1, 0.5}));
  truth.canes.push_back(StraightCane(2, 1, CaneKind::kSpur, {0.5, 1, 0.5}, {5, 1, 0.5}));
  std::vector<CoverageSample> samples = *SampleViewCoverage(truth, TwoCameras(), 0.001);
  for (const CoverageSample& s : samples) ASSERT_EQ(s.kind, CaneKind::kTrunk);
  const ViewCoverage c = SummariseViewCoverage(samples, 2);
  EXPECT_NEAR(c.truth_cane_length_m, 2.5, 1e-9);
  EXPECT_NEAR(c.in_two_or_more_fraction, 1.5 / 2.5, 1e-3);
  EXPECT_NEAR(c.in_none_fraction, 1.0 / 2.5, 1e-3);
  EXPECT_NEAR(c.trunk_in_fewer_than_two_fraction, 1.0 / 2.5, 1e-3);
  EXPECT_NEAR(c.side_fraction[0][static_cast<int>(ImageSide::kBeyondBottom)], 1.0 / 2.5, 1e-3);
  EXPECT_NEAR(ViewCoverageToJson(c)["cane_length_in_two_views_fraction"].get<double>(), 0.6, 1e-3);
}

TEST(ViewCoverage, PointsBehindACameraAreNotProjected) {
  VineModel truth;
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0.5, -1, 0}, {0.5, -2, 0}));
  const auto samples = SampleViewCoverage(truth, TwoCameras(), 0.01);
  ASSERT_TRUE(samples.ok());
  ASSERT_FALSE(samples->empty());
  for (const CoverageSample& s : *samples) {
    EXPECT_EQ(s.views, 0);
    EXPECT_EQ(s.sides[0], ImageSide::kNotProjected);
  }
}

TEST(ViewCoverage, RejectsABadStepRigOrModel) {
  VineModel truth;
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0, 1, 0}, {0, 1, 1}));
  EXPECT_THAT(EvaluateViewCoverage(truth, TwoCameras(), 0.0).status().message(),
              HasSubstr("sample_step_m"));
  RigCalibration bad = TwoCameras();
  bad.cameras[1].camera_matrix(0, 0) = std::nan("");
  EXPECT_THAT(EvaluateViewCoverage(truth, bad).status().message(), HasSubstr("rig"));
  VineModel broken = truth;
  broken.canes[0].polyline.radii.clear();
  EXPECT_THAT(EvaluateViewCoverage(broken, TwoCameras()).status().message(), HasSubstr("truth"));
}

}  // namespace
}  // namespace vb
