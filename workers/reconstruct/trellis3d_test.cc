// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/trellis3d.h"

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

VineModel Trellis3() {
  VineModel model;
  for (int i = 0; i < 3; ++i) {
    Wire wire;
    wire.id = WireId(i + 1);
    const double z = 0.95 + 0.3 * i;
    wire.points = {{-2.0, 0.8, z}, {2.0, 0.8, z + 0.01}};
    model.wires.push_back(wire);
  }
  Post post;
  post.id = PostId(1);
  post.base = {0.5, 0.8, 0.0};
  post.top = {0.5, 0.8, 1.9};
  model.posts.push_back(post);
  return model;
}

TEST(ReconstructTrellis, RecoversWiresAndPostsFromThreeViews) {
  const RigCalibration rig = sim::MakeRig().value();
  const VineModel truth = Trellis3();
  const auto trellis = ReconstructTrellis(SyntheticViews(truth, rig), rig, WorkingVolume());
  ASSERT_TRUE(trellis.ok()) << trellis.status();
  ASSERT_EQ(trellis->wires.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    // Sorted from the lowest; each within 5 mm of its true wire over the volume's span.
    for (const Eigen::Vector3d& p : trellis->wires[i].points) {
      EXPECT_LT(PointSegmentDistance(p, truth.wires[i].points[0], truth.wires[i].points[1]), 0.005)
          << "wire " << i;
    }
  }
  ASSERT_EQ(trellis->posts.size(), 1u);
  EXPECT_LT(PointSegmentDistance(trellis->posts[0].base, truth.posts[0].base, truth.posts[0].top),
            0.01);
  EXPECT_NEAR(trellis->posts[0].radius, 0.04, 0.01);
}

TEST(MatchTrellisLines, NamesTheLineOfEveryViewThatSeesIt) {
  const RigCalibration rig = sim::MakeRig().value();
  const std::vector<View2D> views = SyntheticViews(Trellis3(), rig);
  const auto matches = MatchTrellisLines(views, rig, WorkingVolume());
  ASSERT_TRUE(matches.ok()) << matches.status();
  ASSERT_EQ(matches->size(), 4u);
  for (size_t m = 0; m < matches->size(); ++m) {
    const TrellisLineMatch& match = (*matches)[m];
    EXPECT_EQ(match.post, m == 3) << m;  // wires first, then the post
    ASSERT_EQ(match.lines.size(), 3u);
    for (size_t v = 0; v < 3; ++v) {
      ASSERT_GE(match.lines[v], 0) << "match " << m << " view " << v;
      const Line2D& line = match.post ? views[v].posts[match.lines[v]] : views[v].wires[match.lines[v]];
      // The 3D segment's midpoint lies on the named line.
      const Eigen::Vector3d mid = rig.cameras[v].camera_from_platform() * (0.5 * (match.a + match.b));
      EXPECT_NEAR(line.line.dot(mid.hnormalized().homogeneous()) * rig.cameras[v].camera_matrix(0, 0),
                  0.0, 0.5) << "match " << m << " view " << v;
    }
  }
}

// A third view that sees where the pair's wire would be, but has no line there, rejects it.
TEST(ReconstructTrellis, DropsAPairsWireThatAThirdViewCouldSeeButDoesNot) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel truth;
  Wire wire;
  wire.id = WireId(1);
  wire.points = {{-2.0, 0.8, 1.2}, {2.0, 0.8, 1.2}};
  truth.wires.push_back(wire);
  std::vector<View2D> views = SyntheticViews(truth, rig);
  views[1].wires.clear();
  const auto trellis = ReconstructTrellis(views, rig, WorkingVolume());
  ASSERT_TRUE(trellis.ok()) << trellis.status();
  EXPECT_TRUE(trellis->wires.empty());
}

TEST(ReconstructTrellis, RejectsMismatchedViewsAndBadOptions) {
  const RigCalibration rig = sim::MakeRig().value();
  std::vector<View2D> views = SyntheticViews(Trellis3(), rig);
  views.pop_back();
  EXPECT_EQ(ReconstructTrellis(views, rig, WorkingVolume()).status().code(),
            absl::StatusCode::kInvalidArgument);
  TrellisOptions options;
  options.max_residual_px = 0;
  EXPECT_EQ(ReconstructTrellis(SyntheticViews(Trellis3(), rig), rig, WorkingVolume(), options)
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vb::reconstruct
