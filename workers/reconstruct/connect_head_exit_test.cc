// SPDX-License-Identifier: Apache-2.0
// Step 6c of connection (connect.h, ConnectOptions::head_exit_reach_m): canes whose inner part is
// hidden in the head's thick foreground hang on the head, not on a cane they pass.
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/connect_test_util.h"

namespace vb::reconstruct {
namespace {

using connect_test::Line;
using connect_test::Head;

Polyline3 Trunk() { return Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025); }

// The images show wood (the thick region and the canes in it) within 0.35 m of the head's
// centre, background elsewhere.
double ThickNearHead(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d centre(0, 0.8, 1.0);
  return (a - centre).norm() <= 0.35 && (b - centre).norm() <= 0.35 ? 1.0 : 0.0;
}

ConnectOptions WithHeadExit(double reach_m) {
  ConnectOptions options;
  options.head_exit_reach_m = reach_m;
  options.head_exit_min_cos = 0.8;
  options.head_exit_min_support = 0.0;
  options.head_exit_min_radius_m = 0.0;  // no radius test (session 17's rule)
  return options;
}

// The cane whose last point is `tip`, or null.
const Cane* EndingAt(const VineModel& model, const Eigen::Vector3d& tip) {
  for (const Cane& cane : model.canes)
    if (cane.polyline.points.back().isApprox(tip, 1e-9)) return &cane;
  return nullptr;
}

// Two canes leave the head together along +x. The first was matched from the head's surface
// out; of the second only the outer piece was, from 20 cm out (beyond max_attach_m of the head:
// it has no candidate join to it), its inner end touching the first cane 4 mm below it and
// pointing back at the head.
std::vector<Polyline3> TwoCanesLeavingTogether() {
  return {
      Line({0.05, 0.8, 1.0}, {0.6, 0.8, 1.02}, 0.005),    // N: from the head surface
      Line({0.25, 0.8, 1.003}, {0.5, 0.8, 0.93}, 0.004),  // H: its inner part hidden
  };
}
const Eigen::Vector3d kHTip(0.5, 0.8, 0.93);
const Eigen::Vector3d kNTip(0.6, 0.8, 1.02);

TEST(ConnectHeadExit, WithoutItTheHiddenCaneHangsOnTheCaneItPasses) {
  const auto model = ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), WithHeadExit(0.0),
                                  nullptr, ThickNearHead);
  ASSERT_TRUE(model.ok()) << model.status();
  const Cane* h = EndingAt(*model, kHTip);
  const Cane* n = EndingAt(*model, kNTip);
  ASSERT_NE(h, nullptr);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(h->parent_id, n->id);  // the case step 6c is for
}

TEST(ConnectHeadExit, ACaneWhoseInnerPartIsHiddenInTheHeadHangsOnTheHead) {
  ConnectSummary summary;
  const auto model = ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), WithHeadExit(0.3),
                                  &summary, ThickNearHead);
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Validate().ok());
  const Cane* h = EndingAt(*model, kHTip);
  const Cane* n = EndingAt(*model, kNTip);
  ASSERT_NE(h, nullptr);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(h->parent_id, CaneId(1));  // the trunk: canes of the head name it
  EXPECT_EQ(n->parent_id, CaneId(1));
  EXPECT_EQ(summary.head_exits, 1);
  // Its base is carried to the head's surface (the line there is wood in the images).
  EXPECT_NEAR((h->polyline.points.front() - Eigen::Vector3d(0, 0.8, 1.0)).norm(), 0.05, 1e-6);
  EXPECT_EQ(h->polyline.points.size(), 12u);
}

TEST(ConnectHeadExit, WithoutImagesItHangsOnTheHeadButItsGapIsNotDrawn) {
  // No GapSupportFn: head_exit_min_support 0 needs none, but the 20 cm gap is not drawn.
  const auto model =
      ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), WithHeadExit(0.3), nullptr);
  ASSERT_TRUE(model.ok()) << model.status();
  const Cane* h = EndingAt(*model, kHTip);
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->parent_id, CaneId(1));
  EXPECT_EQ(h->polyline.points.size(), 11u);
}

TEST(ConnectHeadExit, ACaneOfACaneBesideTheHeadStillHangsOnThatCane) {
  // C forks upward off N 27 cm from the head's surface: its inner end lies within reach of the
  // head, on wood, but points down at N, not at the head.
  std::vector<Polyline3> canes = TwoCanesLeavingTogether();
  canes.push_back(Line({0.32, 0.8, 1.015}, {0.37, 0.8, 1.4}, 0.003));
  const Eigen::Vector3d c_tip(0.37, 0.8, 1.4);
  ConnectSummary summary;
  const auto model =
      ConnectCanes(canes, Trunk(), Head(), WithHeadExit(0.3), &summary, ThickNearHead);
  ASSERT_TRUE(model.ok()) << model.status();
  const Cane* c = EndingAt(*model, c_tip);
  const Cane* n = EndingAt(*model, kNTip);
  ASSERT_NE(c, nullptr);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(c->parent_id, n->id);
  EXPECT_EQ(summary.head_exits, 1);  // H only
}

TEST(ConnectHeadExit, AnInnerEndBeyondReachOrOverBackgroundStaysOnItsCane) {
  // Beyond the reach, and within it but with background between it and the head.
  const auto far = ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), WithHeadExit(0.15),
                                nullptr, ThickNearHead);
  ASSERT_TRUE(far.ok());
  EXPECT_NE(EndingAt(*far, kHTip)->parent_id, CaneId(1));
  ConnectOptions seen = WithHeadExit(0.3);
  seen.head_exit_min_support = 0.9;
  const auto unseen =
      ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), seen, nullptr,
                   [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 0.5; });
  ASSERT_TRUE(unseen.ok());
  EXPECT_NE(EndingAt(*unseen, kHTip)->parent_id, CaneId(1));
}

TEST(ConnectHeadExit, AThinPieceStaysOnItsCaneWithARadiusTest) {
  // The same piece, 2.5 mm thick (a fork off a cane is thinner than the head's canes): with
  // head_exit_min_radius_m 3 mm it stays on N; 4 mm thick (TwoCanesLeavingTogether) it goes.
  ConnectOptions options = WithHeadExit(0.3);
  options.head_exit_min_radius_m = 0.003;
  std::vector<Polyline3> canes = TwoCanesLeavingTogether();
  canes[1] = Line({0.25, 0.8, 1.003}, {0.5, 0.8, 0.93}, 0.0025);
  ConnectSummary thin_summary;
  const auto thin =
      ConnectCanes(canes, Trunk(), Head(), options, &thin_summary, ThickNearHead);
  ASSERT_TRUE(thin.ok()) << thin.status();
  const Cane* h = EndingAt(*thin, kHTip);
  const Cane* n = EndingAt(*thin, kNTip);
  ASSERT_NE(h, nullptr);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(h->parent_id, n->id);
  EXPECT_EQ(thin_summary.head_exits, 0);
  // Without the radius test the thin piece goes to the head.
  const auto untested = ConnectCanes(canes, Trunk(), Head(), WithHeadExit(0.3), nullptr,
                                     ThickNearHead);
  ASSERT_TRUE(untested.ok()) << untested.status();
  EXPECT_EQ(EndingAt(*untested, kHTip)->parent_id, CaneId(1));
  ConnectSummary thick_summary;
  const auto thick = ConnectCanes(TwoCanesLeavingTogether(), Trunk(), Head(), options,
                                  &thick_summary, ThickNearHead);
  ASSERT_TRUE(thick.ok()) << thick.status();
  EXPECT_EQ(EndingAt(*thick, kHTip)->parent_id, CaneId(1));
  EXPECT_EQ(thick_summary.head_exits, 1);
}

TEST(ConnectHeadExit, APiecePointingAcrossTheHeadStaysOnItsCane) {
  // H's inner end 20 cm from the head as before, but the piece runs across the direction to the
  // head (along y): its outward tangent there is perpendicular to it (cosine 0 < 0.8).
  std::vector<Polyline3> canes = TwoCanesLeavingTogether();
  canes[1] = Line({0.25, 0.8, 1.003}, {0.25, 1.05, 1.003}, 0.004);
  const Eigen::Vector3d tip(0.25, 1.05, 1.003);
  ConnectSummary summary;
  const auto model =
      ConnectCanes(canes, Trunk(), Head(), WithHeadExit(0.3), &summary, ThickNearHead);
  ASSERT_TRUE(model.ok()) << model.status();
  const Cane* h = EndingAt(*model, tip);
  const Cane* n = EndingAt(*model, kNTip);
  ASSERT_NE(h, nullptr);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(h->parent_id, n->id);
  EXPECT_EQ(summary.head_exits, 0);
}

TEST(ConnectHeadExit, BadOptionsAreRejectedByName) {
  ConnectOptions options;
  options.head_exit_reach_m = -0.1;
  EXPECT_NE(options.Validate().message().find("head_exit_reach_m"), std::string::npos);
  options = ConnectOptions();
  options.head_exit_min_cos = 1.5;
  EXPECT_NE(options.Validate().message().find("head_exit_min_cos"), std::string::npos);
  options = ConnectOptions();
  options.head_exit_min_support = -0.1;
  EXPECT_NE(options.Validate().message().find("head_exit_min_support"), std::string::npos);
  options = ConnectOptions();
  options.head_exit_min_radius_m = -0.001;
  EXPECT_NE(options.Validate().message().find("head_exit_min_radius_m"), std::string::npos);
}

}  // namespace
}  // namespace vb::reconstruct
