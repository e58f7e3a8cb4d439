// SPDX-License-Identifier: Apache-2.0
// The head's silhouette reaching into the foreground (HeadOptions::foreground_reach_px,
// foreground_reach_max_views; head_carve.h ReachIntoForeground; docs/reconstruction.md step 5,
// "Enclosing every head: the silhouette (s21)").
#include <algorithm>
#include <cmath>
#include <string>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/head_carve.h"
#include "workers/reconstruct/head_test_util.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

using head_internal::ReachIntoForeground;
using testing_util::CarveHead;
using testing_util::ErodeThickMask;
using testing_util::HeadMetrics;
using testing_util::RowOfSpheresOnATrunk;

// The largest x of the spheres.
double MaxX(const HeadModel& head) {
  double out = -1e9;
  for (const Sphere& s : head.spheres) out = std::max(out, s.center.x() + s.radius);
  return out;
}

// A 40 x 30 view: a thick 10 x 10 square at (5..14, 10..19); a foreground line 1 px high from
// its right side, x 15..34 at y 14; a foreground blob at (2..3, 2..3) touching nothing; the
// rest background.
View2D SquareWithATail() {
  View2D view;
  view.width = 40;
  view.height = 30;
  view.classes = ClassImage(40, 30);
  view.thick_mask.assign(40 * 30, 0);
  for (int y = 10; y < 20; ++y)
    for (int x = 5; x < 15; ++x) {
      view.thick_mask[y * 40 + x] = 1;
      view.classes.set(x, y, PixelClass::kForeground);
    }
  for (int x = 15; x < 35; ++x) view.classes.set(x, 14, PixelClass::kForeground);
  for (int y = 2; y < 4; ++y)
    for (int x = 2; x < 4; ++x) view.classes.set(x, y, PixelClass::kForeground);
  return view;
}

TEST(ReachIntoForeground, GrowsAlongTouchingForegroundByTheReachOnly) {
  const View2D view = SquareWithATail();
  const std::vector<uint8_t> grown = ReachIntoForeground(view, view.thick_mask, 5);
  ASSERT_EQ(grown.size(), view.thick_mask.size());
  // The tail: its first 5 px (x 15..19) and no more; every step reaches one pixel along a row.
  for (int x = 15; x < 35; ++x) EXPECT_EQ(grown[14 * 40 + x], x < 20 ? 1 : 0) << "x " << x;
  int added = 0;
  for (size_t i = 0; i < grown.size(); ++i) {
    if (grown[i] && !view.thick_mask[i]) ++added;
    if (view.thick_mask[i]) {
      EXPECT_EQ(grown[i], 1);  // the silhouette stays
    }
  }
  EXPECT_EQ(added, 5) << "background, and foreground not joined to the silhouette, stay out";
  EXPECT_EQ(grown[2 * 40 + 2], 0);
  EXPECT_EQ(ReachIntoForeground(view, view.thick_mask, 0), view.thick_mask);
}

// One view's thick mask loses a 9 px rim of the head to its opening, the image there being
// foreground (tuning stops 1470, 1699). The tight head leaves part of it outside; reaching 12 px
// into the foreground in that one view brings it back.
TEST(ReconstructHeadAndTrunk, ReachKeepsAHeadRimOneViewLoses) {
  const RigCalibration rig = sim::MakeRig().value();
  const VineModel vine = RowOfSpheresOnATrunk();
  std::vector<View2D> views = SyntheticViews(vine, rig);
  ErodeThickMask(9, &views[0]);
  auto enclosed = [&](int reach_px, int max_views) {
    HeadOptions options;
    options.foreground_reach_px = reach_px;
    options.foreground_reach_max_views = max_views;
    return HeadMetrics(CarveHead(views, rig, options), vine.head).head_enclosed_fraction;
  };
  EXPECT_LT(enclosed(0, 3), 0.97) << "the eroded view should shave this head";
  EXPECT_GE(enclosed(12, 3), 0.99);
  EXPECT_GE(enclosed(12, 1), 0.99) << "one view held by the reach is allowed";
}

// A cane 8 mm thick leaves the head along x: thin in every view, so held by the reach alone in
// all three. Reaching 20 px (about 3 cm at 0.8 m) unrestricted (max views 3), the head runs 2 cm
// further along the cane; with max views 1 the cane's cubes are carved where two views find them
// outside, and one rim leaf (1 cm: its sphere is held by the reach in one view, by the thick
// mask in the two others, which see the cane's root from a little aside) is all it adds.
TEST(ReconstructHeadAndTrunk, ReachInOneViewLeavesACaneOut) {
  const RigCalibration rig = sim::MakeRig().value();
  VineModel vine = RowOfSpheresOnATrunk();
  Cane cane;
  cane.id = CaneId(2);
  cane.kind = CaneKind::kCane;
  for (double t = 0.0; t <= 1.0001; t += 0.1) {
    cane.polyline.points.push_back({0.06 + 0.25 * t, 0.8, 0.89});
    cane.polyline.radii.push_back(0.004);
  }
  vine.canes.push_back(cane);
  const std::vector<View2D> views = SyntheticViews(vine, rig);
  auto max_x = [&](int reach_px, int max_views) {
    HeadOptions options;
    options.foreground_reach_px = reach_px;
    options.foreground_reach_max_views = max_views;
    return MaxX(CarveHead(views, rig, options));  // a failed carve already fails the test
  };
  const double without = max_x(0, 3);
  const double everywhere = max_x(20, 3);
  const double one_view = max_x(20, 1);
  EXPECT_GT(everywhere, without + 0.015) << "the unrestricted reach should swallow the base";
  EXPECT_LE(one_view, without + 0.0101) << "without " << without << " one view " << one_view;
  EXPECT_LT(one_view, everywhere - 0.005) << "one view " << one_view << " all " << everywhere;
}

TEST(HeadOptions, RejectsBadReachFields) {
  HeadOptions o;
  for (int bad : {-1, 101}) {
    o.foreground_reach_px = bad;
    EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(o.Validate().message().find("foreground_reach_px"), std::string::npos) << bad;
  }
  o = HeadOptions();
  o.foreground_reach_max_views = 0;
  EXPECT_NE(o.Validate().message().find("foreground_reach_max_views"), std::string::npos);
  o.foreground_reach_max_views = 1;
  o.foreground_reach_px = 10;
  EXPECT_TRUE(o.Validate().ok());
}

}  // namespace
}  // namespace vb::reconstruct
