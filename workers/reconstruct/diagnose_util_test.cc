// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/diagnose_util.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/match_segments_test_util.h"

namespace vb::reconstruct {
namespace {

TEST(SegmentMaps, FindsTheSegmentWithin3PixelsALaterSegmentWinning) {
  View2D view;
  view.width = 20;
  view.height = 10;
  Segment2D a, b;
  a.points = {{5.0, 5.0}};
  a.widths_px = {1.0};
  b.points = {{8.0, 5.0}};
  b.widths_px = {1.0};
  view.segments = {a, b};
  const SegmentMaps maps({view});
  EXPECT_EQ(maps.At(0, 2, 5), 0);   // 3 px from a
  EXPECT_EQ(maps.At(0, 1, 5), -1);  // 4 px from a
  EXPECT_EQ(maps.At(0, 4, 8), 0);   // 3 px from a either way, 4 from b
  EXPECT_EQ(maps.At(0, 5, 5), 1);   // near both: the later one
  EXPECT_EQ(maps.At(0, 11, 2), 1);
  EXPECT_EQ(maps.At(0, 12, 5), -1);
  EXPECT_EQ(maps.At(0, -1, 5), -1);  // outside the image
  EXPECT_EQ(maps.At(0, 20, 5), -1);
}

TEST(LocateSample, APointOnACaneIsOnItsSegmentInEveryViewAndAPointOffItIsNot) {
  const auto [model, rig, views] =
      DrawOneCane({-0.15, 0.78, 0.9}, {0.1, 0.85, 1.25}, 3);
  const SegmentMaps maps(views);
  const Polyline3& cane = model.canes[0].polyline;
  const SampleInViews on = LocateSample(0.5 * (cane.points[0] + cane.points[1]), rig, views, maps);
  EXPECT_EQ(on.in_image, 3);
  EXPECT_EQ(on.foreground, 3);
  EXPECT_EQ(on.skeleton, 3);
  for (int v = 0; v < 3; ++v) {
    EXPECT_TRUE(on.inside[v]);
    EXPECT_EQ(on.segment[v], 0);
  }
  // 10 cm above the cane's middle: in the images, away from the wood.
  const SampleInViews off = LocateSample(
      0.5 * (cane.points[0] + cane.points[1]) + Eigen::Vector3d(0, 0, 0.1), rig, views, maps);
  EXPECT_EQ(off.foreground, 0);
  EXPECT_EQ(off.skeleton, 0);
  for (int v = 0; v < 3; ++v) EXPECT_EQ(off.segment[v], -1);
  // Behind the cameras: in no image.
  const SampleInViews behind = LocateSample(Eigen::Vector3d(0, -2.0, 1.0), rig, views, maps);
  EXPECT_EQ(behind.in_image, 0);
  EXPECT_EQ(behind.skeleton, 0);
}

// The horizontal pair's epipolar lines run across the image: a cane along them cannot be placed
// (|sin| near 0), an upright one can (near 1).
TEST(EpipolarSin, SmallAlongTheHorizontalPairsEpipolarLinesLargeAcrossThem) {
  const RigCalibration rig = Rig(2);
  const Eigen::Vector3d p(0.0, 0.8, 1.0);
  const auto px = rig.cameras[0].Project(p);
  ASSERT_TRUE(px.has_value());
  const auto along = EpipolarSin(rig, 0, 1, p, Eigen::Vector3d::UnitX(), *px);
  const auto across = EpipolarSin(rig, 0, 1, p, Eigen::Vector3d::UnitZ(), *px);
  ASSERT_TRUE(along.has_value());
  ASSERT_TRUE(across.has_value());
  EXPECT_LT(*along, 0.2);
  EXPECT_GT(*across, 0.9);
}

// A polyline holds a cane when both its ends are among its points, in either order, with more
// around them; one end alone, or ends 1 mm off, is not enough.
TEST(HoldsEnds, BothEndsAmongThePointsInAnyOrder) {
  Polyline3 cane;
  cane.points = {{0, 0, 1}, {0.1, 0, 1.1}, {0.2, 0, 1.2}};
  Polyline3 connected;
  connected.points = {{0, 0, 0.9}, {0.2, 0, 1.2}, {0.1, 0, 1.1}, {0, 0, 1}};
  EXPECT_TRUE(HoldsEnds(cane, connected));
  connected.points.pop_back();
  EXPECT_FALSE(HoldsEnds(cane, connected));
  connected.points.push_back({0, 0, 1.001});
  EXPECT_FALSE(HoldsEnds(cane, connected));
  EXPECT_TRUE(HoldsEnds(cane, cane));
  EXPECT_FALSE(HoldsEnds(cane, Polyline3{}));
}

// The ladder of the loss reports: with everything seen, each stage's grid filled in pipeline
// order moves the first lost stage one on; whatever the grids hold, the views' evidence decides
// first. A grid counts within 10 mm only, and the fitted one only above the threshold.
TEST(FirstLostStage, TheFirstStageThatFailsInPipelineOrder) {
  const Eigen::Vector3d p(0.1, 0.8, 1.0);
  SampleEvidence seen;
  seen.in_image = seen.foreground = seen.skeleton = 3;
  seen.conditioned = true;
  StageGrids grids;
  const double threshold = 0.5;
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossRaw);
  grids.raw.Add(p + Eigen::Vector3d(0.02, 0, 0), 1.0);  // 20 mm away
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossRaw);
  grids.raw.Add(p + Eigen::Vector3d(0.005, 0, 0), 1.0);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossFitted);
  grids.fitted.Add(p, 0.5);  // at the threshold, not above it
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossProbable);
  grids.fitted.Add(p, 0.6);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossPiece);
  grids.piece.Add(p, 1.0);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossAssembled);
  grids.assembled.Add(p, 1.0);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossConnected);
  grids.connected.Add(p, 1.0);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossFinal);
  grids.final.Add(p, 1.0);
  EXPECT_EQ(FirstLostStage(p, seen, grids, threshold), kLossKept);
  // The views' evidence, last to first.
  SampleEvidence e = seen;
  e.conditioned = false;
  EXPECT_EQ(FirstLostStage(p, e, grids, threshold), kLossConditioned);
  e.skeleton = 1;
  EXPECT_EQ(FirstLostStage(p, e, grids, threshold), kLossSkeleton);
  e.foreground = 1;
  EXPECT_EQ(FirstLostStage(p, e, grids, threshold), kLossForeground);
  e.in_image = 1;
  EXPECT_EQ(FirstLostStage(p, e, grids, threshold), kLossInImage);
}

// The middle half of a drawn cane, one piece seen by views 0 and 1, and a piece outside the
// working volume: the outside one is dropped, the other assembled and, when grow runs before
// connection (the default), grown along the drawn cane beyond its ends; the hints are the canes'
// points in order.
TEST(AssembleAndGrow, DropsCanesOutsideTheVolumeAndGrowsBeforeConnectionOnly) {
  const Eigen::Vector3d a(-0.15, 0.78, 0.9), b(0.1, 0.85, 1.25);
  const auto [model, rig, views] = DrawOneCane(a, b, 3);
  auto piece = [](const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
    Piece3D out;
    for (int k = 0; k <= 20; ++k) {
      out.polyline.points.push_back(from + (to - from) * (k / 20.0));
      out.polyline.radii.push_back(0.004);
    }
    out.probability = 0.9;
    out.support = 1.0;
    out.view_a = 0;
    out.view_b = 1;
    out.segment_a = out.segment_b = 0;
    return out;
  };
  const Eigen::Vector3d far(0.0, 3.0, 1.0);  // beyond the volume's y <= 1.2
  const std::vector<Piece3D> pieces = {piece(a + 0.25 * (b - a), a + 0.75 * (b - a)),
                                       piece(far, far + Eigen::Vector3d(0.0, 0.0, 0.2))};
  ReconstructOptions options;
  ASSERT_FALSE(options.grow.after_connection);
  const auto grown = AssembleAndGrow(views, rig, pieces, options);
  ASSERT_TRUE(grown.ok()) << grown.status();
  ASSERT_EQ(grown->canes.size(), 1u);
  const Polyline3& cane = grown->canes[0];
  EXPECT_GT(cane.Length(), 0.5 * (b - a).norm() + 0.05);
  for (const Eigen::Vector3d& p : cane.points) {
    EXPECT_LT(DistanceToLines(p, {model.canes[0].polyline}), 0.003);
  }
  EXPECT_EQ(grown->hints, cane.points);

  options.grow.after_connection = true;
  const auto assembled = AssembleAndGrow(views, rig, pieces, options);
  ASSERT_TRUE(assembled.ok()) << assembled.status();
  ASSERT_EQ(assembled->canes.size(), 1u);
  EXPECT_NEAR(assembled->canes[0].Length(), 0.5 * (b - a).norm(), 0.01);
  EXPECT_EQ(assembled->hints, assembled->canes[0].points);
}

// Each stage's output lands in its own grid, at its own place (1 m apart along x).
TEST(MakeStageGrids, EachStagesPointsInItsGrid) {
  auto at = [](double x) { return Eigen::Vector3d(x, 0.8, 1.0); };
  auto line = [&](double x) {
    Polyline3 l;
    l.points = {at(x), at(x) + Eigen::Vector3d(0, 0, 0.05)};
    l.radii = {0.004, 0.004};
    return l;
  };
  MatchCandidate raw;
  for (double z : {0.0, 0.004, 0.008}) {
    EpipolarHit hit;
    hit.point = at(0) + Eigen::Vector3d(0, 0, z);
    raw.hits.push_back(hit);
  }
  ScoredCandidate scored;
  scored.fit.control_points = line(1).points;
  scored.probability = 0.7;
  Piece3D piece;
  piece.polyline = line(2);
  AssembledStop assembled;
  assembled.canes = {line(3)};
  assembled.head.trunk = line(4);
  ConnectedStop connected;
  connected.connected.canes.push_back(MakeCane(1, at(5), at(5) + Eigen::Vector3d(0, 0, 0.05),
                                               0.004));
  connected.refined.canes.push_back(MakeCane(1, at(6), at(6) + Eigen::Vector3d(0, 0, 0.05),
                                             0.004));
  const StageGrids grids = MakeStageGrids({raw}, {scored}, {piece}, assembled, connected);
  const PointGrid* by_place[] = {&grids.raw,       &grids.fitted,    &grids.piece,
                                 &grids.assembled, &grids.assembled, &grids.connected,
                                 &grids.final};
  for (int x = 0; x <= 6; ++x) {
    const Eigen::Vector3d mid = at(x) + Eigen::Vector3d(0, 0, x == 0 ? 0.004 : 0.025);
    EXPECT_EQ(by_place[x]->MaxNear(mid), x == 1 ? 0.7 : 1.0) << "place " << x;
    // Nothing of the other stages there.
    for (const PointGrid* g : {&grids.raw, &grids.fitted, &grids.piece, &grids.assembled,
                               &grids.connected, &grids.final}) {
      if (g != by_place[x]) {
        EXPECT_LT(g->MaxNear(mid), 0) << "place " << x;
      }
    }
  }
}

// The horizontal pair of Rig(2) (EpipolarSin above): a sample with skeleton on foreground in both
// views is placeable by that pair, conditioned when the cane runs across the epipolar lines; a
// segment where the view shows no foreground does not count.
TEST(EvidenceOf, SkeletonCountsOnForegroundAndThePairIsConditionedAcrossTheEpipolarLines) {
  const RigCalibration rig = Rig(2);
  const Eigen::Vector3d p(0.0, 0.8, 1.0);
  SampleInViews at;
  at.in_image = at.foreground = 2;
  at.inside = {true, true};
  at.on_foreground = {true, true};
  at.segment = {4, 7};
  for (int v = 0; v < 2; ++v) {
    const auto px = rig.cameras[v].Project(p);
    ASSERT_TRUE(px.has_value());
    at.px.push_back(*px);
  }
  const SampleEvidence across = EvidenceOf(at, rig, p, Eigen::Vector3d::UnitZ(), 0.5);
  EXPECT_EQ(across.in_image, 2);
  EXPECT_EQ(across.foreground, 2);
  EXPECT_EQ(across.skeleton, 2);
  EXPECT_EQ(across.segment, std::vector<int>({4, 7}));
  EXPECT_EQ(across.pairs, (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_TRUE(across.conditioned);
  const SampleEvidence along = EvidenceOf(at, rig, p, Eigen::Vector3d::UnitX(), 0.5);
  EXPECT_EQ(along.pairs.size(), 1u);
  EXPECT_FALSE(along.conditioned);
  at.on_foreground[1] = false;
  at.foreground = 1;
  const SampleEvidence one = EvidenceOf(at, rig, p, Eigen::Vector3d::UnitZ(), 0.5);
  EXPECT_EQ(one.skeleton, 1);
  EXPECT_EQ(one.segment, std::vector<int>({4, -1}));
  EXPECT_TRUE(one.pairs.empty());
  EXPECT_FALSE(one.conditioned);
}

// Two upright canes 3 mm apart (along each other in every view) and one 30 cm to the side; a
// neighbour's cane along the third. Each cane's samples weigh its length in all (ends half),
// and say along what each lies.
TEST(SampleTrueLength, WeightsAddUpToTheLengthAndSayAlongWhatEachSampleLies) {
  SimulatedStop stop;
  stop.true_rig = Rig(3);
  stop.scene.vine.canes = {MakeCane(1, {0.0, 0.8, 0.9}, {0.0, 0.8, 1.1}, 0.004),
                           MakeCane(2, {0.003, 0.8, 0.9}, {0.003, 0.8, 1.1}, 0.004),
                           MakeCane(3, {0.3, 0.8, 0.9}, {0.3, 0.8, 1.1}, 0.004)};
  stop.drawn = stop.scene.vine;
  stop.drawn.canes.push_back(MakeCane(4, {0.303, 0.8, 0.9}, {0.303, 0.8, 1.1}, 0.004));
  const std::vector<LengthSample> own = SampleTrueLength(stop, 0.005, false);
  const std::vector<LengthSample> all = SampleTrueLength(stop, 0.005, true);
  ASSERT_EQ(own.size(), all.size());
  double length[3] = {};
  int middle_own[3] = {}, middle_all[3] = {};
  for (size_t k = 0; k < all.size(); ++k) {
    const LengthSample& s = all[k];
    ASSERT_LT(s.cane, 3u);
    length[s.cane] += s.weight_m;
    EXPECT_EQ(own[k].along, 0);
    EXPECT_EQ(own[k].along_own, s.along_own);
    EXPECT_EQ(s.in_image, 3);
    EXPECT_NEAR(std::abs(s.tangent.z()), 1.0, 1e-9);
    EXPECT_NEAR(s.p.z(), 0.9 + s.step_m * s.index, 1e-9);
    // Away from the ends, where LyingAlongAnother's runs are whole.
    if (s.p.z() > 0.95 && s.p.z() < 1.05) {
      middle_own[s.cane] = std::max(middle_own[s.cane], s.along_own);
      middle_all[s.cane] = std::max(middle_all[s.cane], s.along);
    }
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(length[c], 0.2, 1e-9) << "cane " << c;
  EXPECT_EQ(middle_own[0], 3);
  EXPECT_EQ(middle_own[1], 3);
  EXPECT_EQ(middle_own[2], 0);
  EXPECT_EQ(middle_all[2], 3);
  EXPECT_EQ(middle_all[0], 3);
}

TEST(DistanceToCanes, NearestPointOfTheNearestCane) {
  std::vector<Cane> canes = {MakeCane(1, {0, 0, 0}, {1, 0, 0}, 0.004),
                             MakeCane(2, {0, 1, 0}, {1, 1, 0}, 0.004)};
  Eigen::Vector3d nearest;
  EXPECT_NEAR(DistanceToCanes({0.5, 0.005, 0}, canes, &nearest), 0.005, 1e-12);
  EXPECT_NEAR((nearest - Eigen::Vector3d(0.5, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(DistanceToCanes({0.5, 0.9, 0}, canes), 0.1, 1e-12);
  EXPECT_TRUE(NearAnyCane({0.5, 0.005, 0}, canes));
  EXPECT_FALSE(NearAnyCane({0.5, 0.02, 0}, canes));
  EXPECT_TRUE(NearAnyCane({0.5, 0.02, 0}, canes, 0.03));
  EXPECT_EQ(DistanceToCanes({0, 0, 0}, {}), 1e9);
  // The index of the nearest cane, and the same over bare polylines.
  int index = -1;
  EXPECT_NEAR(DistanceToCanes({0.5, 0.9, 0}, canes, nullptr, &index), 0.1, 1e-12);
  EXPECT_EQ(index, 1);
  EXPECT_NEAR(DistanceToCanes({0.5, 0.2, 0}, canes, nullptr, &index), 0.2, 1e-12);
  EXPECT_EQ(index, 0);
  const std::vector<Polyline3> lines = {canes[0].polyline, canes[1].polyline};
  EXPECT_NEAR(DistanceToLines({0.5, 0.995, 0}, lines, &nearest, &index), 0.005, 1e-12);
  EXPECT_EQ(index, 1);
  EXPECT_NEAR((nearest - Eigen::Vector3d(0.5, 1, 0)).norm(), 0.0, 1e-12);
  index = 7;
  EXPECT_EQ(DistanceToLines({0, 0, 0}, {}, nullptr, &index), 1e9);
  EXPECT_EQ(index, 7);
}

TEST(Flat, FirstLineIsTheTrunkTheRestHangOnIt) {
  const std::vector<Cane> canes = {MakeCane(1, {0, 0, 0}, {0, 0, 1}, 0.01),
                                   MakeCane(2, {0, 0, 1}, {1, 0, 1}, 0.004),
                                   MakeCane(3, {0, 0, 1}, {-1, 0, 1}, 0.004)};
  const VineModel model = Flat({canes[0].polyline, canes[1].polyline, canes[2].polyline});
  ASSERT_EQ(model.canes.size(), 3u);
  EXPECT_EQ(model.canes[0].kind, CaneKind::kTrunk);
  EXPECT_FALSE(model.canes[0].parent_id.has_value());
  for (int i : {1, 2}) {
    EXPECT_EQ(model.canes[i].kind, CaneKind::kCane);
    EXPECT_EQ(model.canes[i].parent_id, model.canes[0].id);
    EXPECT_EQ(model.canes[i].polyline.points, canes[i].polyline.points);
  }
}

TEST(OverrideFromEnv, SetsOnlyWhatTheEnvironmentGives) {
  unsetenv("VB_DIAGNOSE_UTIL_TEST");
  double d = 1.5;
  int n = 3;
  bool b = true;
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d));
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &n));
  EXPECT_FALSE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &b));
  EXPECT_EQ(d, 1.5);
  EXPECT_EQ(n, 3);
  EXPECT_TRUE(b);
  setenv("VB_DIAGNOSE_UTIL_TEST", "0", 1);
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d));
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &n));
  EXPECT_TRUE(OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &b));
  EXPECT_EQ(d, 0.0);
  EXPECT_EQ(n, 0);
  EXPECT_FALSE(b);
  setenv("VB_DIAGNOSE_UTIL_TEST", "2.25", 1);
  OverrideFromEnv("VB_DIAGNOSE_UTIL_TEST", &d);
  EXPECT_EQ(d, 2.25);
  unsetenv("VB_DIAGNOSE_UTIL_TEST");
}

TEST(ListFromEnv, ParsesACommaListUpToTheFirstNonNumber) {
  unsetenv("VB_DIAGNOSE_UTIL_LIST");
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({7.0}));
  setenv("VB_DIAGNOSE_UTIL_LIST", "1,2.5,-0.1", 1);
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({1.0, 2.5, -0.1}));
  setenv("VB_DIAGNOSE_UTIL_LIST", "0.3,x,4", 1);
  EXPECT_EQ(ListFromEnv("VB_DIAGNOSE_UTIL_LIST", {7.0}), std::vector<double>({0.3}));
  unsetenv("VB_DIAGNOSE_UTIL_LIST");
}

}  // namespace
}  // namespace vb::reconstruct
