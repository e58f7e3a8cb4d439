// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head.h"

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

// Enclosure of the true head by the carved spheres, on simulated vines drawn without rendering
// (so any miss is the carving's, not the segmentation's). Seeds from the development range.
TEST(ReconstructHeadAndTrunk, EnclosesTheTrueHeadAndFindsTheTrunk) {
  const RigCalibration rig = sim::MakeRig().value();
  for (uint64_t seed : {1003u, 1017u}) {
    const sim::Scene scene = sim::GenerateScene(seed, 1).value();
    const std::vector<View2D> views = SyntheticViews(scene.vine, rig);
    const auto result =
        ReconstructHeadAndTrunk(views, rig, WorkingVolume(), HeadOptions(), Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    ASSERT_FALSE(result->head.spheres.empty());
    VineModel model;
    model.head = result->head;
    const ReconstructionMetrics m = EvaluateReconstruction(model, [&] {
      VineModel truth;
      truth.head = scene.vine.head;
      return truth;
    }()).value();
    EXPECT_GE(m.head_enclosed_fraction, 0.99) << "seed " << seed;
    EXPECT_LT(m.head_volume_ratio, 25.0) << "seed " << seed;
    // The trunk axis from slab centres lies near the true trunk; its base, extrapolated to the
    // ground below the images, within 5 cm.
    ASSERT_TRUE(result->trunk.has_value()) << "seed " << seed;
    const Polyline3& truth_trunk = scene.vine.canes[0].polyline;
    for (const Eigen::Vector3d& p : result->trunk->points) {
      double best = 1e9;
      for (size_t i = 0; i + 1 < truth_trunk.points.size(); ++i)
        best = std::min(best, PointSegmentDistance(p, truth_trunk.points[i], truth_trunk.points[i + 1]));
      EXPECT_LT(best, p.z() < 0.01 ? 0.05 : 0.03) << "seed " << seed << " trunk point " << p.transpose();
    }
  }
}

// A thick trunk under a tall head only ~1.5x as wide (tuning stop 1187 with the rig refined by
// fiducials looked like this): no slab is wide by head_width_factor, so the head must start at
// its widest slab, not collapse to the top head_min_height_m of the hull.
TEST(ReconstructHeadAndTrunk, WeakWideningStillEnclosesATallHead) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel vine;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  for (double z = 0.0; z <= 0.8201; z += 0.02) {
    trunk.polyline.points.push_back({0.0, 0.8, z});
    trunk.polyline.radii.push_back(0.035);
  }
  vine.canes.push_back(trunk);
  for (double z = 0.84; z <= 0.9801; z += 0.02)
    for (double x : {-0.02, 0.0, 0.02}) vine.head.spheres.push_back({{x, 0.8, z}, 0.035});
  const std::vector<View2D> views = SyntheticViews(vine, rig);
  const auto result =
      ReconstructHeadAndTrunk(views, rig, WorkingVolume(), HeadOptions(), Deadline::Infinite());
  ASSERT_TRUE(result.ok()) << result.status();
  VineModel model;
  model.head = result->head;
  VineModel truth;
  truth.head = vine.head;
  const ReconstructionMetrics m = EvaluateReconstruction(model, truth).value();
  EXPECT_GE(m.head_enclosed_fraction, 0.99);
  EXPECT_LT(m.head_volume_ratio, 25.0);
}

TEST(ReconstructHeadAndTrunk, EmptyViewsGiveAnEmptyHead) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(VineModel(), rig);
  const auto result =
      ReconstructHeadAndTrunk(views, rig, WorkingVolume(), HeadOptions(), Deadline::Infinite());
  ASSERT_TRUE(result.ok());
  EXPECT_TRUE(result->head.spheres.empty());
  EXPECT_FALSE(result->trunk.has_value());
}

TEST(ReconstructHeadAndTrunk, RejectsMismatchedViews) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = SyntheticViews(VineModel(), rig);
  views.pop_back();
  EXPECT_EQ(ReconstructHeadAndTrunk(views, rig, WorkingVolume(), HeadOptions(),
                                    Deadline::Infinite())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
  views = SyntheticViews(VineModel(), rig);
  views[1].thick_mask.resize(10);
  EXPECT_EQ(ReconstructHeadAndTrunk(views, rig, WorkingVolume(), HeadOptions(),
                                    Deadline::Infinite())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vb::reconstruct
