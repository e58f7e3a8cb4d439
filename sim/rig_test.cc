// SPDX-License-Identifier: Apache-2.0
#include "sim/rig.h"

#include <cmath>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/render_rays.h"

namespace vb::sim {
namespace {

using ::testing::HasSubstr;

// RMS pixel displacement of points on the vine plane (y = 0.8) between two calibrations,
// measured independently of the function PerturbCalibration uses internally.
double VinePlaneRms(const CameraCalibration& a, const CameraCalibration& b) {
  double sum = 0.0;
  int n = 0;
  for (double x = -0.6; x <= 0.6001; x += 0.1) {
    for (double z = 0.55; z <= 1.55; z += 0.1) {
      const auto pa = a.Project({x, 0.8, z});
      const auto pb = b.Project({x, 0.8, z});
      if (!pa || !pb || !a.InImage(*pa)) continue;
      sum += (*pa - *pb).squaredNorm();
      ++n;
    }
  }
  return std::sqrt(sum / n);
}

TEST(Rig, DefaultIsATriangleCentredOnTheRigHeight) {
  auto rig = MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  ASSERT_EQ(rig->cameras.size(), 3u);
  EXPECT_EQ(rig->cameras[0].name, "cam0");
  EXPECT_EQ(rig->cameras[2].name, "cam2");
  const Eigen::Vector3d c0 = rig->cameras[0].CentreInPlatform();
  const Eigen::Vector3d c1 = rig->cameras[1].CentreInPlatform();
  const Eigen::Vector3d c2 = rig->cameras[2].CentreInPlatform();
  EXPECT_LT(c0.x(), 0.0);
  EXPECT_GT(c1.x(), 0.0);
  EXPECT_GT(c2.z(), c0.z());
  EXPECT_NEAR(c0.z(), c1.z(), 1e-12);
  EXPECT_NEAR((c0 - c1).norm(), 0.22, 1e-9);
  EXPECT_NEAR((c0 - c2).norm(), 0.22, 1e-9);
  EXPECT_NEAR((c1 - c2).norm(), 0.22, 1e-9);
  EXPECT_TRUE(((c0 + c1 + c2) / 3.0).isApprox(Eigen::Vector3d(0, 0, 1.05), 1e-9));
  EXPECT_TRUE(rig->Validate().ok());
}

TEST(Rig, WithoutToeInCamerasLookAlongPlusYWithImageDownWorldDown) {
  RigOptions o;
  o.toe_in = false;
  auto rig = MakeRig(o);
  ASSERT_TRUE(rig.ok());
  for (const CameraCalibration& c : rig->cameras) {
    const Eigen::Matrix3d& r = c.rotation_camera_from_platform;
    EXPECT_TRUE(r.row(0).isApprox(Eigen::RowVector3d(1, 0, 0), 1e-12)) << c.name;
    EXPECT_TRUE(r.row(1).isApprox(Eigen::RowVector3d(0, 0, -1), 1e-12)) << c.name;
    EXPECT_TRUE(r.row(2).isApprox(Eigen::RowVector3d(0, 1, 0), 1e-12)) << c.name;
  }
}

TEST(Rig, ToeInCamerasLookAtTheVinePlaneCentre) {
  auto rig = MakeRig();
  ASSERT_TRUE(rig.ok());
  for (const CameraCalibration& c : rig->cameras) {
    const auto uv = c.Project({0.0, 0.8, 1.05});
    ASSERT_TRUE(uv.has_value());
    // The target is on the optical axis, so it lands on the principal point.
    EXPECT_NEAR(uv->x(), c.camera_matrix(0, 2), 1e-6) << c.name;
    EXPECT_NEAR(uv->y(), c.camera_matrix(1, 2), 1e-6) << c.name;
    // Principal points are offset a few pixels from the image centre.
    EXPECT_GT(std::abs(c.camera_matrix(0, 2) - 639.5), 0.5);
    EXPECT_LT(std::abs(c.camera_matrix(0, 2) - 639.5), 8.0);
    // Image x follows +x, image down follows world down.
    EXPECT_GT(c.Project({0.1, 0.8, 1.05})->x(), uv->x());
    EXPECT_GT(c.Project({0.0, 0.8, 0.95})->y(), uv->y());
  }
}

TEST(Rig, FocalLengthGivesTheRequestedFieldOfViewWithoutDistortion) {
  RigOptions o;
  o.k1 = o.k2 = o.p1 = o.p2 = o.k3 = 0.0;
  o.horizontal_fov_deg = 90.0;
  o.camera_count = 1;
  o.toe_in = false;
  auto rig = MakeRig(o);
  ASSERT_TRUE(rig.ok());
  EXPECT_NEAR(rig->cameras[0].camera_matrix(0, 0), 640.0, 1e-9);
  EXPECT_EQ(rig->cameras[0].camera_matrix(0, 0), rig->cameras[0].camera_matrix(1, 1));
}

TEST(Rig, DefaultLensIsInvertibleOverTheWholeImage) {
  auto rig = MakeRig();
  ASSERT_TRUE(rig.ok());
  const CameraCalibration& c = rig->cameras[0];
  const RayTable rays(c);
  EXPECT_EQ(rays.invalid_count(), 0);
  // The horizontal field of view stays wide (the corner limit trims it a little).
  const Eigen::Vector3d left = c.RayInPlatform({0.0, c.camera_matrix(1, 2)});
  const Eigen::Vector3d right = c.RayInPlatform({1279.0, c.camera_matrix(1, 2)});
  const double fov_deg = std::acos(left.dot(right)) * 180.0 / M_PI;
  EXPECT_GT(fov_deg, 90.0);
  EXPECT_LT(fov_deg, 101.0);
}

TEST(Rig, TwoCamerasAreAHorizontalPair) {
  RigOptions o;
  o.camera_count = 2;
  o.baseline_m = 0.3;
  auto rig = MakeRig(o);
  ASSERT_TRUE(rig.ok());
  ASSERT_EQ(rig->cameras.size(), 2u);
  const Eigen::Vector3d d = rig->cameras[1].CentreInPlatform() - rig->cameras[0].CentreInPlatform();
  EXPECT_TRUE(d.isApprox(Eigen::Vector3d(0.3, 0, 0), 1e-9));
}

TEST(Rig, InvalidOptionsAreRejectedNamingTheField) {
  auto expect_field = [](RigOptions o, const std::string& field) {
    const absl::Status s = MakeRig(o).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(std::string(s.message()), HasSubstr(field));
  };
  RigOptions o;
  o.camera_count = 0;
  expect_field(o, "camera_count");
  o = {};
  o.camera_count = 4;
  expect_field(o, "camera_count");
  o = {};
  o.image_width = 0;
  expect_field(o, "image_width");
  o = {};
  o.horizontal_fov_deg = 200.0;
  expect_field(o, "horizontal_fov_deg");
  o = {};
  o.baseline_m = -0.1;
  expect_field(o, "baseline_m");
  o = {};
  o.rig_height_m = NAN;
  expect_field(o, "rig_height_m");
  o = {};
  o.distance_to_vine_plane_m = 0.0;
  expect_field(o, "distance_to_vine_plane_m");
  o = {};
  o.k2 = INFINITY;
  expect_field(o, "k2");
}

TEST(Rig, PerturbationOfZeroIsIdentity) {
  const RigCalibration rig = *MakeRig();
  const RigCalibration same = PerturbCalibration(rig, 0.0, 42);
  ASSERT_EQ(same.cameras.size(), rig.cameras.size());
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    EXPECT_EQ(same.cameras[i].camera_matrix, rig.cameras[i].camera_matrix);
    EXPECT_EQ(same.cameras[i].rotation_camera_from_platform, rig.cameras[i].rotation_camera_from_platform);
    EXPECT_EQ(same.cameras[i].translation_camera_from_platform, rig.cameras[i].translation_camera_from_platform);
    EXPECT_EQ(same.cameras[i].distortion, rig.cameras[i].distortion);
  }
}

TEST(Rig, PerturbationMovesReprojectionsByTheRequestedRms) {
  const RigCalibration rig = *MakeRig();
  for (double error_px : {0.3, 1.0, 3.0, 10.0}) {
    for (uint64_t seed : {1u, 2u, 3u}) {
      const RigCalibration bad = PerturbCalibration(rig, error_px, seed);
      ASSERT_TRUE(bad.Validate().ok());
      for (size_t i = 0; i < rig.cameras.size(); ++i) {
        const double rms = VinePlaneRms(rig.cameras[i], bad.cameras[i]);
        EXPECT_GT(rms, error_px / 1.5) << "error " << error_px << " seed " << seed << " cam " << i;
        EXPECT_LT(rms, error_px * 1.5) << "error " << error_px << " seed " << seed << " cam " << i;
        // The camera centre does not move: only intrinsics and orientation are wrong.
        EXPECT_LT((bad.cameras[i].CentreInPlatform() - rig.cameras[i].CentreInPlatform()).norm(), 1e-9);
      }
    }
  }
}

TEST(Rig, PerturbationIsDeterministicInTheSeed) {
  const RigCalibration rig = *MakeRig();
  const RigCalibration a = PerturbCalibration(rig, 2.0, 7);
  const RigCalibration b = PerturbCalibration(rig, 2.0, 7);
  const RigCalibration c = PerturbCalibration(rig, 2.0, 8);
  EXPECT_EQ(a.cameras[1].camera_matrix, b.cameras[1].camera_matrix);
  EXPECT_EQ(a.cameras[1].rotation_camera_from_platform, b.cameras[1].rotation_camera_from_platform);
  EXPECT_NE(a.cameras[1].camera_matrix, c.cameras[1].camera_matrix);
}

}  // namespace
}  // namespace vb::sim
