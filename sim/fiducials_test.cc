// SPDX-License-Identifier: Apache-2.0
#include "sim/fiducials.h"

#include <algorithm>
#include <cmath>

#include "gtest/gtest.h"
#include "sim/renderer.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"

namespace vb::sim {
namespace {

// Every default fiducial is seen by every camera of the default rig, inside the image, at least
// 50 px inside (with the rig before 2026-11-22 the top row's middle one was 44 px from the upper
// camera's top edge).
TEST(PlatformFiducials, DefaultLayoutIsSeenByEveryCamera) {
  const RigCalibration rig = MakeRig().value();
  const std::vector<Fiducial> fiducials = PlatformFiducials().value();
  ASSERT_EQ(fiducials.size(), 18u);
  for (const CameraCalibration& camera : rig.cameras) {
    int well_inside = 0;
    for (const Fiducial& f : fiducials) {
      EXPECT_DOUBLE_EQ(f.position_in_platform.y(), 1.25);
      const auto uv = camera.Project(f.position_in_platform);
      ASSERT_TRUE(uv.has_value()) << f.name << " " << camera.name;
      const double margin = std::min({uv->x(), uv->y(), camera.image_width - 1 - uv->x(),
                                      camera.image_height - 1 - uv->y()});
      EXPECT_GT(margin, 15.0) << f.name << " " << camera.name;
      well_inside += margin > 50.0;
    }
    EXPECT_EQ(well_inside, 18) << camera.name;
  }
  RigCalibration with = rig;
  with.fiducials = fiducials;
  EXPECT_TRUE(with.Validate().ok());
}

TEST(PlatformFiducials, RejectsABadRadius) {
  FiducialLayoutOptions options;
  options.radius_m = 0.0;
  const auto fiducials = PlatformFiducials(options);
  ASSERT_FALSE(fiducials.ok());
  EXPECT_NE(fiducials.status().message().find("radius_m"), std::string::npos);
}

// The renderer draws each disc white on the blue backdrop where the camera projects its centre,
// with the backdrop's label, and leaves the backdrop blue just outside it.
TEST(PlatformFiducials, RendererDrawsWhiteDiscsOnTheBackdrop) {
  Scene scene = GenerateScene(1101, 1).value();
  scene.neighbours.clear();
  scene.vine.canes.clear();
  scene.vine.head.spheres.clear();
  scene.fiducials = PlatformFiducials().value();
  const CameraCalibration camera = MakeRig().value().cameras[0];
  RenderOptions options;
  options.read_noise_dn = 0.0;
  options.shot_noise = 0.0;
  const RenderedView view = Render(scene, camera, options, 1).value();
  int white = 0;
  for (const Fiducial& f : scene.fiducials) {
    const Eigen::Vector2d uv = *camera.Project(f.position_in_platform);
    const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
    const uint8_t* centre = view.image.at(x, y);
    const uint8_t* outside = view.image.at(x, y + 20);  // 20 px below: ~2 disc radii
    if (view.labels.at(x, y) != kLabelBackground) continue;  // behind a wire or post
    EXPECT_GT(centre[0], 3 * outside[0] + 10) << f.name;
    EXPECT_GT(outside[2], outside[0]) << f.name;  // blue backdrop
    white += centre[0] > 60 && centre[1] > 60 && centre[2] > 60;
  }
  EXPECT_GE(white, 12);  // the rest lie behind a wire or in a shadow
}

}  // namespace
}  // namespace vb::sim
