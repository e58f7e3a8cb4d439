// SPDX-License-Identifier: Apache-2.0
// ConnectCanes where a cane's taper decides (connect.h): which end of a far cane is its base
// (TaperTowardCentre), a cane hung on a left-out cane, far canes thinning away from the vine
// against leaves thickening away from it. Split from connect_test.cc.
#include "workers/reconstruct/connect.h"

#include <optional>
#include <string>
#include <tuple>

#include "gtest/gtest.h"
#include "workers/reconstruct/connect_test_util.h"

namespace vb::reconstruct {
namespace {

using connect_test::Line;
using connect_test::Head;

// A cane whose radius runs from r_a at a to r_b at b.
Polyline3 TaperedLine(Eigen::Vector3d a, Eigen::Vector3d b, double r_a, double r_b) {
  Polyline3 line = Line(a, b);
  for (size_t i = 0; i < line.radii.size(); ++i)
    line.radii[i] = r_a + (r_b - r_a) * static_cast<double>(i) / (line.radii.size() - 1);
  return line;
}

// Step 3b: the arborescence would hang C on G (likelier than C's join to the head), but G has no
// join to the tree and is left out: C, its join to the head better than none, hangs there after
// all, and E, hung on C, comes with it. G stays out. Everything here reaches 0.6-0.9 m along the
// row, out of step 6's reach.
TEST(ConnectCanes, ACaneHungOnALeftOutCaneTakesItsLikelyJoinToTheTree) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  PreparedCanes prepared;
  prepared.trunk = trunk;
  prepared.canes = {Line({0.06, 0.8, 1.05}, {0.6, 0.8, 1.2}),  // C, from the head outward
                    Line({0.62, 0.8, 1.25}, {0.9, 0.8, 1.5}),   // G, left out
                    Line({0.6, 0.8, 1.18}, {0.8, 0.8, 1.0})};   // E, hung on C
  auto join = [](int child, int parent, double p, Eigen::Vector3d at) {
    JoinCandidate c;
    c.child = child;
    c.parent = parent;
    c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
    c.point = at;
    c.probability = p;
    return c;
  };
  std::vector<JoinCandidate> joins = {join(0, 1, 0.9, {0.62, 0.8, 1.25}),
                                      join(0, -1, 0.3, {0.05, 0.8, 1.04}),
                                      join(1, 0, 0.05, {0.6, 0.8, 1.2}),
                                      join(2, 0, 0.8, {0.6, 0.8, 1.2})};
  joins[0].base_is_last = true;  // C's base would be its end near G
  ConnectOptions off;
  off.rescue_min_probability = 0.0;
  ConnectSummary summary;
  auto model = BuildTree(prepared, joins, Head(), off, &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 1u);  // C on G, E on C, G on nothing: all out
  EXPECT_EQ(summary.unattached, 3);

  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.attached, 2);
  EXPECT_EQ(summary.rescued, 2);
  EXPECT_EQ(summary.unattached, 1);
  const Cane* c = nullptr;
  const Cane* e = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.6, 0.8, 1.2))) c = &cane;
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.8, 0.8, 1.0))) e = &cane;
    EXPECT_FALSE(cane.polyline.points.back().isApprox(Eigen::Vector3d(0.9, 0.8, 1.5)));
  }
  ASSERT_NE(c, nullptr);  // based at the head: the rescued join's orientation
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(c->parent_id, CaneId(1));
  EXPECT_EQ(e->parent_id, c->id);

  // A join to the tree less likely than none does not rescue: all stay out.
  joins[1].probability = 0.1;
  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 1u);
  EXPECT_EQ(summary.rescued, 0);

  // A C thickening away from the vine's centre (a neighbour's cane, entering the view tip
  // first) is not rescued, unless the taper test is off.
  joins[1].probability = 0.3;
  prepared.canes[0] = TaperedLine({0.06, 0.8, 1.05}, {0.6, 0.8, 1.2}, 0.003, 0.005);
  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 1u);
  ConnectOptions any_taper;
  any_taper.rescue_min_taper = 0.0;
  model = BuildTree(prepared, joins, Head(), any_taper, &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 3u);
  EXPECT_EQ(summary.rescued, 2);

  ConnectOptions bad;
  bad.rescue_min_probability = 1.0;
  const auto rejected = BuildTree(prepared, joins, Head(), bad);
  EXPECT_EQ(rejected.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(rejected.status().message()).find("rescue_min_probability"),
            std::string::npos);
  bad.rescue_min_probability = 0.1;  // below "none" (min_join_probability 0.12)
  const auto below_none = BuildTree(prepared, joins, Head(), bad);
  EXPECT_NE(std::string(below_none.status().message()).find("min_join_probability"),
            std::string::npos);
}

TEST(TaperTowardCentre, IsInnerOverOuterRadiusWhicheverWayTheCaneRuns) {
  const Polyline3 outward = TaperedLine({0.4, 0.8, 1.3}, {0.9, 0.8, 1.3}, 0.005, 0.003);
  EXPECT_GT(TaperTowardCentre(outward, 0.0), 1.3);
  Polyline3 reversed = outward;
  std::reverse(reversed.points.begin(), reversed.points.end());
  std::reverse(reversed.radii.begin(), reversed.radii.end());
  EXPECT_NEAR(TaperTowardCentre(reversed, 0.0), TaperTowardCentre(outward, 0.0), 1e-9);
  // Seen from a centre beyond its far end, the same cane thickens toward the centre.
  EXPECT_LT(TaperTowardCentre(outward, 1.5), 1.0);
  EXPECT_NEAR(TaperTowardCentre(Line({0.4, 0.8, 1.3}, {0.9, 0.8, 1.3}), 0.0), 1.0, 1e-12);
  EXPECT_EQ(TaperTowardCentre(Line({0.4, 0.8, 1.3}, {0.41, 0.8, 1.3}), 0.0), 1.0);  // too short
}

// Step 6 beyond keep_within_m: of two canes reaching 0.9 m along the row with only unlikely
// joins, the one thinning outward (this vine's) is kept, hung by its thicker inner end even
// when the join by its outer end is likelier; the one thinning inward (a neighbour's, entering
// tip first) stays out, as does either with keep_taper_ratio 0.
TEST(ConnectCanes, AFarCaneThinningAwayFromTheVineIsKeptByItsThickerEnd) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  PreparedCanes prepared;
  prepared.trunk = trunk;
  prepared.canes = {Line({0.05, 0.8, 1.1}, {0.45, 0.8, 1.3}, 0.006),               // A, near
                    TaperedLine({0.9, 0.8, 1.32}, {0.5, 0.8, 1.3}, 0.003, 0.005),  // B, ours
                    TaperedLine({0.5, 0.8, 1.2}, {0.9, 0.8, 1.2}, 0.003, 0.005)};  // C, theirs
  auto join = [](int child, bool base_is_last, int parent, double p) {
    JoinCandidate c;
    c.child = child;
    c.base_is_last = base_is_last;
    c.parent = parent;
    c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
    // On A's side, not its tip: B does not continue A and is not appended to it.
    c.point = parent < 0 ? Eigen::Vector3d(0.05, 0.8, 1.05) : Eigen::Vector3d(0.25, 0.8, 1.2);
    c.probability = p;
    return c;
  };
  const std::vector<JoinCandidate> joins = {join(0, false, -1, 0.9),
                                            join(1, false, 0, 0.08),  // B by its outer end
                                            join(1, true, 0, 0.04),   // B by its inner end
                                            join(2, false, 0, 0.05)};
  ConnectOptions off;
  off.keep_taper_ratio = 0.0;
  ConnectSummary summary;
  auto model = BuildTree(prepared, joins, Head(), off, &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(summary.attached, 1);
  EXPECT_EQ(summary.unattached, 2);

  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.attached, 2);
  EXPECT_EQ(summary.kept_near, 1);
  EXPECT_EQ(summary.unattached, 1);
  ASSERT_EQ(model->canes.size(), 3u);
  const Cane& b = model->canes[2];
  EXPECT_EQ(b.parent_id, model->canes[1].id);
  EXPECT_NEAR(b.polyline.points.back().x(), 0.9, 1e-9);  // base first: the thick inner end
  EXPECT_GT(b.polyline.radii.front(), b.polyline.radii.back());

  for (const double ratio : {-1.0, 0.5, 1.0}) {
    ConnectOptions bad;
    bad.keep_taper_ratio = ratio;
    const auto rejected = BuildTree(prepared, joins, Head(), bad);
    EXPECT_EQ(rejected.status().code(), absl::StatusCode::kInvalidArgument) << ratio;
    EXPECT_NE(std::string(rejected.status().message()).find("keep_taper_ratio"),
              std::string::npos);
  }
}

// A neighbour's cane hung on this vine's by a likely join (its tip near a cane it crosses):
// reaching beyond keep_within_m and thickening away from the centre, a leaf of the tree, it is
// dropped (drop_thickening_ratio); this vine's far cane, thinning outward, stays; with the ratio
// 0 both stay. A ratio in (0, 1] is rejected, naming the field.
TEST(ConnectCanes, AFarLeafThickeningAwayFromTheVineIsDropped) {
  PreparedCanes prepared;
  prepared.trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  prepared.canes = {Line({0.05, 0.8, 1.1}, {0.45, 0.8, 1.3}, 0.006),               // A, near
                    TaperedLine({0.5, 0.8, 1.3}, {0.9, 0.8, 1.32}, 0.005, 0.003),  // B, ours
                    TaperedLine({0.5, 0.8, 1.2}, {0.9, 0.8, 1.2}, 0.003, 0.005)};  // C, theirs
  auto join = [](int child, int parent, double p) {
    JoinCandidate c;
    c.child = child;
    c.parent = parent;
    c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
    c.point = parent < 0 ? Eigen::Vector3d(0.05, 0.8, 1.05) : Eigen::Vector3d(0.25, 0.8, 1.2);
    c.probability = p;
    return c;
  };
  const std::vector<JoinCandidate> joins = {join(0, -1, 0.9), join(1, 0, 0.8), join(2, 0, 0.8)};
  ConnectOptions off;
  off.drop_thickening_ratio = 0.0;
  ConnectSummary summary;
  auto model = BuildTree(prepared, joins, Head(), off, &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(summary.attached, 3);
  EXPECT_EQ(summary.dropped_thickening, 0);

  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.attached, 2);
  EXPECT_EQ(summary.dropped_thickening, 1);
  ASSERT_EQ(model->canes.size(), 3u);
  EXPECT_NEAR(model->canes[2].polyline.points.back().z(), 1.32, 1e-9);  // B, not C

  for (const double ratio : {-1.0, 0.5, 1.0}) {
    ConnectOptions bad;
    bad.drop_thickening_ratio = ratio;
    const auto rejected = BuildTree(prepared, joins, Head(), bad);
    EXPECT_EQ(rejected.status().code(), absl::StatusCode::kInvalidArgument) << ratio;
    EXPECT_NE(std::string(rejected.status().message()).find("drop_thickening_ratio"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace vb::reconstruct
