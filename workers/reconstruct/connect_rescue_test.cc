// SPDX-License-Identifier: Apache-2.0
// Connection's steps 3b (rescue) and 6 (kept near the vine) taken in turn (connect.h,
// ConnectOptions::repeat_rescue, off by default): a cane kept by step 6 can be the likely join
// that rescues another.
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/connect.h"

namespace vb::reconstruct {
namespace {

Polyline3 TaperedLine(Eigen::Vector3d a, Eigen::Vector3d b, double r_a, double r_b, int n = 10) {
  Polyline3 line;
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    line.points.push_back(a + (b - a) * t);
    line.radii.push_back(r_a + (r_b - r_a) * t);
  }
  return line;
}

HeadModel Head() {
  HeadModel head;
  head.spheres.push_back({{0, 0.8, 1.0}, 0.05});
  return head;
}

JoinCandidate Join(int child, bool base_is_last, int parent, double p, Eigen::Vector3d at) {
  JoinCandidate c;
  c.child = child;
  c.base_is_last = base_is_last;
  c.parent = parent;
  c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
  c.point = at;
  c.probability = p;
  return c;
}

// N lies wholly near the vine (x 0.2-0.4 m) but its only join, to the head, is less likely than
// none: step 6 keeps it. R reaches beyond 0.5 m and thins outward a little (taper 1.1: enough
// for a rescue, not for step 6's 1.2); its likeliest join is to G, a far cane without any join
// to the tree, so the arborescence leaves both out, and its join to N (0.4, better than none)
// can rescue it only once N is in the tree. G stays out.
struct Scene {
  PreparedCanes prepared;
  std::vector<JoinCandidate> joins;
};

ConnectOptions Repeating() {
  ConnectOptions options;
  options.repeat_rescue = true;
  return options;
}

Scene MakeScene() {
  Scene s;
  s.prepared.trunk = TaperedLine({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025, 0.025);
  s.prepared.canes = {
      TaperedLine({0.2, 0.8, 1.3}, {0.4, 0.8, 1.3}, 0.004, 0.004),       // N
      TaperedLine({0.41, 0.8, 1.31}, {0.7, 0.8, 1.7}, 0.0044, 0.0040),   // R, not along N
      TaperedLine({0.72, 0.8, 1.72}, {1.0, 0.8, 1.9}, 0.003, 0.005),     // G
  };
  s.joins = {Join(0, false, -1, 0.05, {0.04, 0.8, 1.03}),
             Join(1, false, 0, 0.4, {0.4, 0.8, 1.3}),
             Join(1, true, 2, 0.6, {0.72, 0.8, 1.72})};
  return s;
}

bool HasCaneEndingAt(const VineModel& model, const Eigen::Vector3d& p) {
  for (const Cane& cane : model.canes) {
    if (cane.polyline.points.back().isApprox(p) || cane.polyline.points.front().isApprox(p))
      return true;
  }
  return false;
}

TEST(ConnectRescue, ACaneKeptNearTheVineCanRescueAnother) {
  const Scene s = MakeScene();
  ASSERT_GT(TaperTowardCentre(s.prepared.canes[1], 0.0), 1.0);
  ASSERT_LT(TaperTowardCentre(s.prepared.canes[1], 0.0), ConnectOptions().keep_taper_ratio);

  ConnectSummary summary;
  const auto model = BuildTree(s.prepared, s.joins, Head(), Repeating(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  ASSERT_EQ(model->canes.size(), 3u);  // the trunk, N and R
  EXPECT_EQ(summary.kept_near, 1);
  EXPECT_EQ(summary.rescued, 1);
  EXPECT_EQ(summary.unattached, 1);
  EXPECT_TRUE(HasCaneEndingAt(*model, {0.7, 0.8, 1.7}));      // R, based on N
  EXPECT_FALSE(HasCaneEndingAt(*model, {1.0, 0.8, 1.9}));    // G
  const Cane* n = nullptr;
  const Cane* r = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.4, 0.8, 1.3))) n = &cane;
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.7, 0.8, 1.7))) r = &cane;
  }
  ASSERT_NE(n, nullptr);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(n->parent_id, CaneId(1));
  EXPECT_EQ(r->parent_id, n->id);
}

TEST(ConnectRescue, WithoutRepeatingOnlyStepSixKeeps) {
  const Scene s = MakeScene();
  ConnectSummary summary;  // the default: each step once
  const auto model = BuildTree(s.prepared, s.joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 2u);  // the trunk and N
  EXPECT_EQ(summary.kept_near, 1);
  EXPECT_EQ(summary.rescued, 0);
  EXPECT_FALSE(HasCaneEndingAt(*model, {0.7, 0.8, 1.7}));
}

TEST(ConnectRescue, ACaneThickeningOutwardIsNotRescuedEvenSo) {
  Scene s = MakeScene();
  // R now thickens away from the vine's centre (a neighbour's cane, entering tip first).
  s.prepared.canes[1] = TaperedLine({0.41, 0.8, 1.31}, {0.7, 0.8, 1.7}, 0.0036, 0.0044);
  ConnectSummary summary;
  const auto model = BuildTree(s.prepared, s.joins, Head(), Repeating(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 2u);
  EXPECT_EQ(summary.rescued, 0);
}

TEST(ConnectRescue, ANoneLikelierThanTheJoinToTheKeptCaneRescuesNothing) {
  Scene s = MakeScene();
  s.joins[1].probability = 0.1;  // below "none" (min_join_probability 0.12)
  ConnectSummary summary;
  const auto model = BuildTree(s.prepared, s.joins, Head(), Repeating(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 2u);
  EXPECT_EQ(summary.rescued, 0);
}

}  // namespace
}  // namespace vb::reconstruct
