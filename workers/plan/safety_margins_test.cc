// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/safety_margins.h"

#include "gtest/gtest.h"

namespace vb::plan {
namespace {

// A robot of one fixed body: a vertical capsule at the base origin, 0.1 m long, radius 0.05.
// Where it is does not depend on q, so clearances are known in closed form.
RobotModel Post() {
  RobotModel robot;
  robot.links.push_back({"base", 0, {Capsule{Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 0.1), 0.05}}});
  return robot;
}

Obstacle Ball(double x, double radius, ObstacleKind kind = ObstacleKind::kHead, int64_t owner = 0) {
  Obstacle o;
  o.kind = kind;
  o.owner_id = owner;
  o.capsule = {Eigen::Vector3d(x, 0, 0.05), Eigen::Vector3d(x, 0, 0.05), radius};
  return o;
}

std::vector<ProtectedMotion> Still() { return {{{Joints::Zero()}, CaneId{0}, {}, 0.0}}; }

TEST(SafetyMargins, FarObstaclesGetTheMaximum) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(1.0, 0.01));
  MarginOptions options;
  const MarginSummary summary = InflateMargins(Post(), Still(), options, &scene);
  EXPECT_DOUBLE_EQ(scene.obstacles[0].margin_m, options.max_margin_m);
  EXPECT_EQ(summary.configurations, 1);
}

TEST(SafetyMargins, NearObstaclesStopShortOfTheProtectedBody) {
  CollisionScene scene;
  // Surface gap: 0.07 - 0.05 - 0.01 = 0.01 m.
  scene.obstacles.push_back(Ball(0.07, 0.01));
  MarginOptions options;
  options.slack_m = 0.002;
  InflateMargins(Post(), Still(), options, &scene);
  EXPECT_NEAR(scene.obstacles[0].margin_m, 0.008, 1e-12);
}

TEST(SafetyMargins, TouchingObstaclesGetNone) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(0.055, 0.01));
  InflateMargins(Post(), Still(), MarginOptions{}, &scene);
  EXPECT_EQ(scene.obstacles[0].margin_m, 0.0);
}

TEST(SafetyMargins, TheCutCaneNearTheCutDoesNotLimitItsMargin) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 7));
  scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 8));
  std::vector<ProtectedMotion> cut = {
      {{Joints::Zero()}, CaneId{7}, Eigen::Vector3d(0.05, 0, 0.05), 0.02}};
  MarginOptions options;
  InflateMargins(Post(), cut, options, &scene);
  EXPECT_DOUBLE_EQ(scene.obstacles[0].margin_m, options.max_margin_m);  // cane 7: ignored there
  EXPECT_EQ(scene.obstacles[1].margin_m, 0.0);                          // cane 8: touching
}

TEST(SafetyMargins, PlanesKeepTheirDistance) {
  CollisionScene scene;
  HalfSpace ground;  // free side: z >= -0.02, i.e. -z <= 0.02
  ground.normal = Eigen::Vector3d(0, 0, -1);
  ground.offset = 0.02;
  scene.planes.push_back(ground);
  MarginOptions options;
  options.slack_m = 0.0;
  InflateMargins(Post(), Still(), options, &scene);
  // Lowest body point: z = -0.05; distance to the plane z = -0.02 is negative: no margin.
  EXPECT_EQ(scene.planes[0].margin_m, 0.0);
  scene.planes[0].offset = 0.07;  // plane at z = -0.07: 0.02 m below the body
  InflateMargins(Post(), Still(), options, &scene);
  EXPECT_NEAR(scene.planes[0].margin_m, 0.02, 1e-12);
}

TEST(SafetyMargins, OptionsRejectBadValues) {
  MarginOptions options;
  options.max_step_m = 0.0;
  EXPECT_NE(options.Validate().message().find("max_step_m"), std::string::npos);
  options = MarginOptions();
  options.max_margin_m = -1;
  EXPECT_NE(options.Validate().message().find("max_margin_m"), std::string::npos);
}

}  // namespace
}  // namespace vb::plan
