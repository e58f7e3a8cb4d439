// SPDX-License-Identifier: Apache-2.0
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

TEST(ConnectCanes, GrowsATreeFromTheTrunkAndHead) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  std::vector<Polyline3> canes = {
      Line({0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}),        // A: from the head surface outward
      Line({0.3, 0.8, 1.5}, {0.3, 0.8, 1.0464}),      // B: lower end 2 mm from A's middle
      Line({1.0, 0.9, 0.3}, {1.0, 0.9, 0.8}),         // C: far from everything
      Line({0.0, 0.8, 0.3}, {0.0, 0.8, 0.7}, 0.02),   // D: the trunk seen again
      Line({-0.05, 0.8, 1.03}, {-0.1, 0.8, 1.05}),    // E: a short stub on the head
  };
  ConnectSummary summary;
  const auto model = ConnectCanes(canes, trunk, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.attached, 3);
  EXPECT_EQ(summary.unattached, 1);
  EXPECT_EQ(summary.inside_trunk_or_head, 1);
  ASSERT_EQ(model->canes.size(), 4u);
  EXPECT_EQ(model->canes[0].kind, CaneKind::kTrunk);
  EXPECT_EQ(model->head.spheres.size(), 1u);
  // The stub and A hang on the head (parent: the trunk); B on A, its base the end near A.
  const Cane* a = nullptr;
  const Cane* b = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.kind == CaneKind::kSpur) {
      EXPECT_EQ(cane.parent_id, CaneId(1));
    }
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.6, 0.8, 1.1))) a = &cane;
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.3, 0.8, 1.5))) b = &cane;
  }
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(a->parent_id, CaneId(1));
  EXPECT_EQ(a->kind, CaneKind::kCane);
  EXPECT_EQ(b->parent_id, a->id);
  // B's first point lies on A.
  const Eigen::Vector3d base = b->polyline.points.front();
  EXPECT_LT(PointSegmentDistance(base, {0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}), 1e-9);
}

// A cane from the head broken where another cane crosses in front of it: the outer piece's end
// touches the crossing cane, but it continues the inner piece 3 cm on. The outer piece is
// appended to the inner one (one whole cane), not hung on the cane it touches.
TEST(ConnectCanes, ACaneBrokenAtACrossingComesOutWhole) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  // The crossing cane grows from the trunk below the head and passes 1 cm in front of the
  // break at (0.44, 0.79, 1.0).
  const std::vector<Polyline3> input = {
      Line({0.45, 0.8, 1.0}, {0.85, 0.8, 1.02}, 0.004),    // outer piece, listed first
      Line({0.06, 0.8, 1.0}, {0.42, 0.8, 1.0}, 0.0045),    // inner piece, from the head
      Line({0.03, 0.79, 0.7}, {0.64, 0.79, 1.1545}, 0.005),  // the crossing cane
  };
  ConnectSummary summary;
  const auto model = ConnectCanes(input, trunk, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  const Cane* whole = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.85, 0.8, 1.02))) whole = &cane;
  }
  ASSERT_NE(whole, nullptr);
  EXPECT_EQ(whole->parent_id, CaneId(1));  // from the head, not from the crossing cane
  EXPECT_LT((whole->polyline.points.front() - Eigen::Vector3d(0.06, 0.8, 1.0)).norm(), 0.03);
  EXPECT_GT(whole->polyline.Length(), 0.75);
}

// Two pieces that continue each other could each be the other's parent; the tree has no cycle
// and a piece far from everything is left out with whatever hangs on it.
TEST(ConnectCanes, LeavesOutWhatDoesNotReachTheVine) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  const std::vector<Polyline3> canes = {
      Line({0.8, 0.9, 1.5}, {1.0, 0.9, 1.5}),  // far from the vine: a neighbour's cane
      Line({1.02, 0.9, 1.5}, {1.2, 0.9, 1.5}),  // continuing it
  };
  ConnectSummary summary;
  const auto model = ConnectCanes(canes, trunk, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 1u);  // the trunk alone
  EXPECT_EQ(summary.unattached, 2);
}

// B's base was seen 6 cm above A: B hangs on A either way, but the gap is drawn only where the
// images show wood along it (the base was there, unmatched).
TEST(ConnectCanes, ASeenGapIsDrawnAndAnUnseenOneIsNot) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  const std::vector<Polyline3> canes = {
      Line({0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}),       // A: from the head
      Line({0.3, 0.8, 1.5}, {0.3, 0.8, 1.1044}),     // B: lower end 6 cm above A
  };
  const Eigen::Vector3d on_a(0.3, 0.8, 1.0 + 0.1 * 0.24 / 0.54);  // A below B's base
  ConnectOptions options;
  options.min_join_probability = 1e-3;  // whatever the classifier makes of a 6 cm gap
  options.crossing_factor = 1.0;        // no crossing test: every call below is for the gap
  for (const double support : {1.0, 0.5}) {
    int calls = 0;
    const GapSupportFn gap_support = [&](const Eigen::Vector3d& base, const Eigen::Vector3d& at) {
      ++calls;
      EXPECT_LT((base - Eigen::Vector3d(0.3, 0.8, 1.1044)).norm(), 1e-9);
      EXPECT_LT(PointSegmentDistance(at, {0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}), 1e-3);
      EXPECT_LT((at - on_a).norm(), 0.02);
      return support;
    };
    const auto model = ConnectCanes(canes, trunk, Head(), options, nullptr, gap_support);
    ASSERT_TRUE(model.ok()) << model.status();
    ASSERT_TRUE(model->Validate().ok()) << model->Validate();
    ASSERT_EQ(model->canes.size(), 3u);
    const Cane& b = model->canes[2];
    EXPECT_EQ(b.parent_id, model->canes[1].id);
    EXPECT_EQ(calls, 1);
    if (support >= options.min_gap_support) {
      EXPECT_LT(PointSegmentDistance(b.polyline.points.front(), {0.06, 0.8, 1.0}, {0.6, 0.8, 1.1}),
                1e-3);
    } else {
      EXPECT_LT((b.polyline.points.front() - Eigen::Vector3d(0.3, 0.8, 1.1044)).norm(), 1e-9);
    }
  }
  ConnectOptions bad;
  bad.min_gap_support = 1.5;
  EXPECT_EQ(ConnectCanes(canes, trunk, Head(), bad).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(ConnectCanes, BuildTreeRejectsJoinsOutOfRange) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  const auto prepared = PrepareCanes({Line({0.06, 0.8, 1.0}, {0.6, 0.8, 1.1})}, trunk, Head(),
                                     ConnectOptions());
  ASSERT_TRUE(prepared.ok());
  std::vector<JoinCandidate> joins = FindJoins(*prepared, Head(), ConnectOptions());
  ASSERT_FALSE(joins.empty());
  EXPECT_TRUE(BuildTree(*prepared, joins, Head(), ConnectOptions()).ok());
  joins[0].child = 5;
  EXPECT_EQ(BuildTree(*prepared, joins, Head(), ConnectOptions()).status().code(),
            absl::StatusCode::kInvalidArgument);
  joins[0].child = 0;
  joins[0].probability = 2.0;
  EXPECT_EQ(BuildTree(*prepared, joins, Head(), ConnectOptions()).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// Step 6: canes whose every join is unlikely. Near the vine's centre along the row they are
// this vine's and hang on their likeliest join (B after A, on which alone it can hang); one
// reaching 0.7 m along the row may be a neighbour's and stays out, and so does a short one.
TEST(ConnectCanes, ACaneNearTheVineWithOnlyUnlikelyJoinsIsKept) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  PreparedCanes prepared;
  prepared.trunk = trunk;
  prepared.canes = {Line({0.1, 0.8, 1.2}, {0.3, 0.8, 1.4}),    // A, wholly near
                    Line({0.28, 0.8, 1.42}, {0.18, 0.8, 1.6}),  // B, near, joins A only
                    Line({0.4, 0.8, 1.3}, {0.7, 0.8, 1.35}),    // C, reaches 0.7 m
                    Line({-0.2, 0.8, 1.3}, {-0.2, 0.8, 1.38})};  // D, near but 8 cm short
  auto join = [](int child, int parent, double p) {
    JoinCandidate c;
    c.child = child;
    c.parent = parent;
    c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
    c.point = parent < 0 ? Eigen::Vector3d(0.05, 0.8, 1.05) : Eigen::Vector3d(0.3, 0.8, 1.4);
    c.probability = p;
    return c;
  };
  const std::vector<JoinCandidate> joins = {join(0, -1, 0.02), join(0, 1, 0.01),
                                            join(1, 0, 0.03), join(2, -1, 0.04),
                                            join(3, -1, 0.05)};
  ConnectOptions off;
  off.keep_within_m = 0.0;
  ConnectSummary summary;
  auto model = BuildTree(prepared, joins, Head(), off, &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->canes.size(), 1u);
  EXPECT_EQ(summary.unattached, 4);

  model = BuildTree(prepared, joins, Head(), ConnectOptions(), &summary);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok()) << model->Validate();
  EXPECT_EQ(summary.kept_near, 2);
  EXPECT_EQ(summary.attached, 2);
  EXPECT_EQ(summary.unattached, 2);
  const Cane* a = nullptr;
  const Cane* b = nullptr;
  for (const Cane& cane : model->canes) {
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.3, 0.8, 1.4))) a = &cane;
    if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.18, 0.8, 1.6))) b = &cane;
    EXPECT_FALSE(cane.polyline.points.back().isApprox(Eigen::Vector3d(0.7, 0.8, 1.35)));
    EXPECT_FALSE(cane.polyline.points.back().isApprox(Eigen::Vector3d(-0.2, 0.8, 1.38)));
  }
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(a->parent_id, CaneId(1));  // on the head
  EXPECT_EQ(b->parent_id, a->id);
  // B leaves A's tip at 74 degrees (not a continuation); its base, 2.8 cm away, is drawn on A.
  EXPECT_TRUE(b->polyline.points.front().isApprox(Eigen::Vector3d(0.3, 0.8, 1.4)));

  ConnectOptions bad;
  bad.keep_within_m = -0.1;
  const auto rejected = BuildTree(prepared, joins, Head(), bad);
  EXPECT_EQ(rejected.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(rejected.status().message()).find("keep_within_m"), std::string::npos);
}

// A cane from the head broken where another cane X crosses 1.5 cm in front of it: the outer
// piece B touches X, and the join classifier likes that better than B's 6 cm gap to the inner
// piece A. Where the images show B's line going on across X (wood beyond it), X is a crossing,
// not B's parent: B hangs on A and is appended to it. Where they show nothing beyond X, B forks
// from X. A crossing that is B's only likely join is kept.
TEST(ConnectCanes, ACaneThatVisiblyGoesOnAcrossAnotherDoesNotHangOnIt) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  PreparedCanes prepared;
  prepared.trunk = trunk;
  prepared.canes = {Line({0.05, 0.8, 1.0}, {0.40, 0.8, 1.0}, 0.005),     // A, from the head
                    Line({0.43, 0.785, 0.85}, {0.43, 0.785, 1.3}, 0.005),  // X, crossing
                    Line({0.46, 0.8, 1.0}, {0.80, 0.8, 1.0}, 0.0045)};   // B, A's outer piece
  auto join = [](int child, int parent, const Eigen::Vector3d& at, double p) {
    JoinCandidate c;
    c.child = child;
    c.parent = parent;
    c.target = parent < 0 ? JoinTarget::kHead : JoinTarget::kCane;
    c.point = at;
    c.probability = p;
    return c;
  };
  const Eigen::Vector3d on_head(0.05, 0.8, 1.0);
  const std::vector<JoinCandidate> joins = {
      join(0, -1, on_head, 0.9), join(1, -1, on_head, 0.9),
      join(2, 1, {0.43, 0.785, 1.0}, 0.6),  // B on X, where it passes
      join(2, 0, {0.40, 0.8, 1.0}, 0.35)};  // B on A's tip
  // Wood along the stretch of B's line beyond X (x 0.417 .. 0.387), where A is.
  int crossing_calls = 0;
  auto images = [&](bool wood_beyond) -> GapSupportFn {
    return [&, wood_beyond](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      const bool beyond = a.x() < 0.425 && b.x() < 0.425 && b.x() > 0.35;
      crossing_calls += beyond;
      return beyond && wood_beyond ? 1.0 : 0.0;
    };
  };
  ConnectOptions options;
  options.crossing_factor = 0.5;
  const CrossingEvidence e = MeasureCrossing(prepared.canes[2], false, prepared.canes[1],
                                             joins[2].point, options, images(true));
  EXPECT_NEAR(e.miss_m, 0.015, 0.002);
  EXPECT_DOUBLE_EQ(e.past_support, 1.0);
  // A stretch along the parent (B continuing A from its tip) is not a crossing, wood or not.
  EXPECT_DOUBLE_EQ(MeasureCrossing(prepared.canes[2], false, prepared.canes[0], joins[3].point,
                                   options, [](const Eigen::Vector3d&, const Eigen::Vector3d&) {
                                     return 1.0;
                                   }).past_support,
                   0.0);
  // A fork meets its parent's axis.
  EXPECT_LT(MeasureCrossing(Line({0.46, 0.785, 1.0}, {0.80, 0.785, 1.0}), false,
                            prepared.canes[1], joins[2].point, ConnectOptions(), {})
                .miss_m,
            1e-3);

  auto parent_of_b = [](const VineModel& model) -> std::optional<CaneId> {
    for (const Cane& cane : model.canes)
      if (cane.polyline.points.back().isApprox(Eigen::Vector3d(0.80, 0.8, 1.0)))
        return cane.parent_id;
    return std::nullopt;
  };
  for (const bool wood_beyond : {true, false}) {
    crossing_calls = 0;
    ConnectSummary summary;
    const auto model =
        BuildTree(prepared, joins, Head(), options, &summary, images(wood_beyond));
    ASSERT_TRUE(model.ok()) << model.status();
    ASSERT_TRUE(model->Validate().ok()) << model->Validate();
    EXPECT_GT(crossing_calls, 0);
    const std::optional<CaneId> parent = parent_of_b(*model);
    ASSERT_TRUE(parent.has_value()) << wood_beyond;
    if (wood_beyond) {  // appended to A, which hangs on the head
      EXPECT_EQ(*parent, CaneId(1));
      EXPECT_EQ(model->canes.size(), 3u);
    } else {  // on X, which reaches z 0.85 .. 1.3
      const Cane& p = model->canes[*model->IndexOf(*parent)];
      EXPECT_NEAR(p.polyline.points.back().z(), 1.3, 1e-9);
      EXPECT_EQ(model->canes.size(), 4u);
    }
  }
  // Without the join to A, the crossing is B's only likely join: B keeps it.
  const std::vector<JoinCandidate> only_crossing(joins.begin(), joins.begin() + 3);
  ConnectSummary summary;
  const auto model =
      BuildTree(prepared, only_crossing, Head(), options, &summary, images(true));
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(summary.unattached, 0);
  EXPECT_EQ(model->canes.size(), 4u);

  for (auto [factor, support, miss, field] :
       {std::tuple{0.0, 0.9, 0.0, "crossing_factor"}, std::tuple{1.5, 0.9, 0.0, "crossing_factor"},
        std::tuple{0.5, 1.5, 0.0, "crossing_min_support"},
        std::tuple{0.5, 0.9, -0.01, "crossing_min_miss_m"}}) {
    ConnectOptions bad;
    bad.crossing_factor = factor;
    bad.crossing_min_support = support;
    bad.crossing_min_miss_m = miss;
    const auto rejected = BuildTree(prepared, joins, Head(), bad);
    EXPECT_EQ(rejected.status().code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(std::string(rejected.status().message()).find(field), std::string::npos) << field;
  }
}

TEST(ConnectCanes, TheStereoTrunkReplacesTheSilhouetteAxis) {
  const Polyline3 silhouette = Line({0.01, 0.8, 0}, {0.01, 0.8, 0.95}, 0.03);
  const std::vector<Polyline3> canes = {Line({0.0, 0.8, 0.9}, {0.0, 0.8, 0.35}, 0.02)};
  const auto model = ConnectCanes(canes, silhouette, Head(), ConnectOptions());
  ASSERT_TRUE(model.ok());
  ASSERT_EQ(model->canes.size(), 1u);
  const Polyline3& trunk = model->canes[0].polyline;
  EXPECT_NEAR(trunk.points.front().z(), 0.0, 1e-9);   // reaches the ground
  EXPECT_NEAR(trunk.points.back().z(), 0.9, 1e-9);    // oriented upward
  EXPECT_NEAR(trunk.points.back().x(), 0.0, 1e-9);    // the stereo axis
}

TEST(ConnectCanes, WithoutATrunkTheLowestThickCaneStandsIn) {
  const std::vector<Polyline3> canes = {Line({0, 0.8, 0.9}, {0, 0.8, 0.2}, 0.02),
                                        Line({0, 0.8, 0.9}, {0.4, 0.8, 1.0})};
  const auto model = ConnectCanes(canes, std::nullopt, HeadModel(), ConnectOptions());
  ASSERT_TRUE(model.ok());
  ASSERT_EQ(model->canes.size(), 2u);
  EXPECT_EQ(model->canes[0].kind, CaneKind::kTrunk);
  EXPECT_LT(model->canes[0].polyline.points.front().z(), 0.25);
  EXPECT_EQ(model->canes[1].parent_id, CaneId(1));
}

TEST(ConnectCanes, EmptyInputAndBadCanes) {
  const auto empty = ConnectCanes({}, std::nullopt, HeadModel(), ConnectOptions());
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->canes.empty());
  Polyline3 bad = Line({0, 0, 0}, {1, 0, 0});
  bad.points[3].x() = std::nan("");
  const auto result = ConnectCanes({bad}, std::nullopt, HeadModel(), ConnectOptions());
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(result.status().message()).find("canes[0]"), std::string::npos);
  ConnectOptions options;
  options.max_attach_m = -1;
  EXPECT_FALSE(ConnectCanes({}, std::nullopt, HeadModel(), options).ok());
}

}  // namespace
}  // namespace vb::reconstruct
