// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_peel.h"

#include <cmath>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

uint8_t At(const std::vector<uint8_t>& mask, const View2D& view, const Eigen::Vector2d& uv) {
  const int x = static_cast<int>(std::lround(uv.x()));
  const int y = static_cast<int>(std::lround(uv.y()));
  return mask[static_cast<size_t>(y) * view.width + x];
}

// A head 10 cm across with a thick cane leaving it to the right and another crossing in front
// of its middle. The leaving cane is peeled off the rim; the head's middle, where the other cane
// crosses it, stays silhouette (the head is behind that cane); the rim away from canes stays.
TEST(PeelCanesOffSilhouette, PeelsTheRimAndLeavesTheMiddle) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel vine;
  vine.head.spheres.push_back({{0.0, 0.8, 0.9}, 0.05});
  Cane leaving;
  leaving.id = CaneId(2);
  Cane crossing;
  crossing.id = CaneId(3);
  std::vector<Eigen::Vector3d> hints;
  for (double x = 0.03; x <= 0.2001; x += 0.01) {
    leaving.polyline.points.push_back({x, 0.8, 0.9});
    leaving.polyline.radii.push_back(0.006);
  }
  for (double z = 0.75; z <= 1.0501; z += 0.01) {
    crossing.polyline.points.push_back({0.0, 0.7, z});
    crossing.polyline.radii.push_back(0.006);
  }
  vine.canes = {leaving, crossing};
  for (const Cane& c : vine.canes)
    hints.insert(hints.end(), c.polyline.points.begin(), c.polyline.points.end());
  const std::vector<View2D> views = SyntheticViews(vine, rig, {}, /*thick_width_px=*/8.0);
  HeadOptions options;
  for (size_t v = 0; v < views.size(); ++v) {
    const CameraCalibration& camera = rig.cameras[v];
    const std::vector<uint8_t> peeled = PeelCanesOffSilhouette(views[v], camera, hints, options);
    ASSERT_EQ(peeled.size(), views[v].thick_mask.size());
    const Eigen::Vector2d middle = *camera.Project({0.0, 0.8, 0.9});
    const Eigen::Vector2d on_leaving = *camera.Project({0.12, 0.8, 0.9});
    const Eigen::Vector2d rim_left = *camera.Project({-0.047, 0.8, 0.9});
    // Drawn thick before peeling.
    ASSERT_NE(At(views[v].thick_mask, views[v], on_leaving), 0) << "view " << v;
    EXPECT_EQ(At(peeled, views[v], on_leaving), 0) << "view " << v;
    EXPECT_NE(At(peeled, views[v], middle), 0) << "view " << v;
    EXPECT_NE(At(peeled, views[v], rim_left), 0) << "view " << v;
    // Nothing is added: the peeled mask lies within the thick mask.
    for (size_t i = 0; i < peeled.size(); ++i)
      if (peeled[i] != 0) ASSERT_NE(views[v].thick_mask[i], 0);
  }
  // Without canes nothing is peeled.
  EXPECT_EQ(PeelCanesOffSilhouette(views[0], rig.cameras[0], {}, options), views[0].thick_mask);
}

}  // namespace
}  // namespace vb::reconstruct
