// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/strand_halves.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/match_segments_test_util.h"

namespace vb::reconstruct {
namespace {

constexpr int kWidth = 200;
constexpr int kHeight = 120;

// A horizontal lit cylinder seen side on: its luminance across the axis, brightest on the axis.
struct Cylinder {
  double axis_y;
  double radius_px;
};

// An rgb8 image of grey background with `cylinders` from x = 30 to 170 (the brighter wins where
// they overlap), and a view of the same size whose skeleton is the strand's middle line (y =
// `strand_y`, `strand_width` wide, points 1 px apart) plus a long thin cane elsewhere, so that the
// view's median width is the thin cane's.
struct Scene {
  Image image{kWidth, kHeight, PixelFormat::kRgb8};
  View2D view;
};
Scene MakeScene(const std::vector<Cylinder>& cylinders, double strand_y, double strand_width,
                double x_end = 170.0) {
  Scene s;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      double luma = 60.0;
      for (const Cylinder& c : cylinders) {
        const double u = (y - c.axis_y) / c.radius_px;
        if (x >= 30 && x <= x_end && std::abs(u) < 1.0) {
          luma = std::max(luma, 80.0 + 120.0 * std::sqrt(1.0 - u * u));
        }
      }
      uint8_t* p = s.image.at(x, y);
      p[0] = p[1] = p[2] = static_cast<uint8_t>(std::lround(luma));
    }
  }
  s.view.width = kWidth;
  s.view.height = kHeight;
  Segment2D strand, thin;
  for (double x = 30; x <= x_end; x += 1.0) {
    strand.points.emplace_back(x, strand_y);
    strand.widths_px.push_back(strand_width);
  }
  for (double x = 5; x <= 195; x += 0.5) {
    thin.points.emplace_back(x, 100.0);
    thin.widths_px.push_back(4.0);
  }
  s.view.segments = {strand, thin};
  return s;
}

// The default options, switched on (the option is off by default).
StrandHalfOptions On() {
  StrandHalfOptions options;
  options.enabled = true;
  return options;
}

// Two 6 px canes side by side, axes at y = 55 and 61: a strand 12 px wide along y = 58.
Scene SideBySide() { return MakeScene({{55.0, 3.0}, {61.0, 3.0}}, 58.0, 12.0); }

TEST(StrandHalves, TwoCanesSideBySideGetAHalfOnEachAxis) {
  const Scene s = SideBySide();
  const auto halves = FindStrandHalves(s.view, s.image, On());
  ASSERT_TRUE(halves.ok()) << halves.status();
  ASSERT_EQ(halves->size(), 2u);
  std::vector<double> axes;
  for (int h = 0; h < 2; ++h) {
    const StrandHalf& half = (*halves)[h];
    EXPECT_EQ(half.parent, 0);
    EXPECT_EQ(half.sibling, 1 - h);
    ASSERT_EQ(half.to_sibling_px.size(), half.path.points.size());
    ASSERT_EQ(half.path.widths_px.size(), half.path.points.size());
    EXPECT_GT(half.path.points.back().x() - half.path.points.front().x(), 120.0);
    for (size_t i = 0; i < half.path.points.size(); ++i) {
      EXPECT_NEAR(half.path.widths_px[i], 6.0, 1e-9);
      // The step lands on the sibling's point.
      const Eigen::Vector2d there = half.path.points[i] + half.to_sibling_px[i];
      EXPECT_NEAR((there - (*halves)[1 - h].path.points[i]).norm(), 0.0, 1e-9);
    }
    axes.push_back(half.path.points[half.path.points.size() / 2].y());
  }
  std::sort(axes.begin(), axes.end());
  EXPECT_NEAR(axes[0], 55.0, 0.5);
  EXPECT_NEAR(axes[1], 61.0, 0.5);
}

TEST(StrandHalves, OneWideCaneHasNoSeamAndStaysWhole) {
  const Scene s = MakeScene({{58.0, 6.0}}, 58.0, 12.0);
  const auto halves = FindStrandHalves(s.view, s.image, On());
  ASSERT_TRUE(halves.ok()) << halves.status();
  EXPECT_TRUE(halves->empty());
  // The width alone would halve it: the same strand drawn flat (no shading across it) passes a
  // seam test of 0 grey levels and is halved, and fails the default 2.
  Scene flat = s;
  for (int y = 52; y <= 64; ++y) {
    for (int x = 30; x <= 170; ++x) {
      uint8_t* p = flat.image.at(x, y);
      p[0] = p[1] = p[2] = 150;
    }
  }
  StrandHalfOptions no_dip = On();
  no_dip.min_seam_dip = 0.0;
  const auto split = FindStrandHalves(flat.view, flat.image, no_dip);
  ASSERT_TRUE(split.ok());
  EXPECT_EQ(split->size(), 2u);
  EXPECT_TRUE(FindStrandHalves(flat.view, flat.image, On())->empty());
}

TEST(StrandHalves, NoneWhenNarrowShortOnTheThickMaskOrOff) {
  // Narrow: the strand no wider than 1.5 x the median (the thin cane's 4 px).
  const Scene narrow = MakeScene({{55.0, 3.0}, {61.0, 3.0}}, 58.0, 5.5);
  EXPECT_TRUE(FindStrandHalves(narrow.view, narrow.image, On())->empty());
  // Short: 15 px of strand, under min_run_px 20.
  const Scene short_strand = MakeScene({{55.0, 3.0}, {61.0, 3.0}}, 58.0, 12.0, 45.0);
  EXPECT_TRUE(FindStrandHalves(short_strand.view, short_strand.image, On())->empty());
  // On the thick mask (the head and trunk).
  Scene thick = SideBySide();
  thick.view.thick_mask.assign(static_cast<size_t>(kWidth) * kHeight, 1);
  EXPECT_TRUE(FindStrandHalves(thick.view, thick.image, On())->empty());
  const Scene s = SideBySide();
  EXPECT_TRUE(FindStrandHalves(s.view, s.image, StrandHalfOptions{})->empty());  // off
}

TEST(StrandHalves, BadImagesAndOptionsAreNamed) {
  const Scene s = SideBySide();
  const Image small(kWidth - 1, kHeight, PixelFormat::kRgb8);
  auto status = FindStrandHalves(s.view, small, On()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("image"), std::string::npos) << status.message();
  const Image mono(kWidth, kHeight, PixelFormat::kMono8);
  status = FindStrandHalves(s.view, mono, On()).status();
  EXPECT_NE(status.message().find("rgb8"), std::string::npos) << status.message();

  const std::vector<std::pair<std::function<void(StrandHalfOptions*)>, std::string>> cases = {
      {[](StrandHalfOptions* o) { o->min_width_px = 0.5; }, "min_width_px"},
      {[](StrandHalfOptions* o) { o->min_width_ratio = NAN; }, "min_width_ratio"},
      {[](StrandHalfOptions* o) { o->min_run_px = 1.0; }, "min_run_px"},
      {[](StrandHalfOptions* o) { o->min_seam_dip = -1.0; }, "min_seam_dip"},
  };
  for (const auto& [set, field] : cases) {
    StrandHalfOptions options = On();
    set(&options);
    status = FindStrandHalves(s.view, s.image, options).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  }
}

// Two vertical canes 6 mm apart along the row at the vine's distance, seen by the simulator's
// horizontal pair: the halves of each view made from their projections, and candidates whose
// hits pair them in order (left with left) or crossed.
struct PairScene {
  RigCalibration rig = Rig(2);
  StrandHalf left[2], right[2];  // per view: the half on cane A (x -3 mm) and on cane B (+3 mm)
  std::vector<Eigen::Vector3d> a, b;

  PairScene() {
    for (int k = 0; k <= 20; ++k) {
      a.emplace_back(-0.003, 0.8, 0.9 + 0.01 * k);
      b.emplace_back(0.003, 0.8, 0.9 + 0.01 * k);
    }
    for (int v = 0; v < 2; ++v) {
      for (size_t k = 0; k < a.size(); ++k) {
        const Eigen::Vector2d pa = *rig.cameras[v].Project(a[k]);
        const Eigen::Vector2d pb = *rig.cameras[v].Project(b[k]);
        Add(&left[v], pa, pb - pa);
        Add(&right[v], pb, pa - pb);
      }
    }
  }
  static void Add(StrandHalf* half, const Eigen::Vector2d& p, const Eigen::Vector2d& step) {
    half->path.points.push_back(p);
    half->path.widths_px.push_back(3.0);
    half->to_sibling_px.push_back(step);
  }
  // Hits at `points`, at the arc of sample k along each half.
  static MatchCandidate Candidate(const StrandHalf& in_a, const StrandHalf& in_b,
                                  const std::vector<Eigen::Vector3d>& points) {
    MatchCandidate c;
    double arc_a = 0.0, arc_b = 0.0;
    for (size_t k = 0; k < points.size(); ++k) {
      if (k > 0) {
        arc_a += (in_a.path.points[k] - in_a.path.points[k - 1]).norm();
        arc_b += (in_b.path.points[k] - in_b.path.points[k - 1]).norm();
      }
      EpipolarHit hit;
      hit.point = points[k];
      hit.arc_a_px = arc_a;
      hit.arc_b_px = arc_b;
      c.hits.push_back(hit);
    }
    return c;
  }
};

TEST(StrandHalves, TheOrderingTestDropsCrossedPairingsOnly) {
  const PairScene s;
  const CameraCalibration& ca = s.rig.cameras[0];
  const CameraCalibration& cb = s.rig.cameras[1];
  // The halves are a few px apart, so the ordering is not trivially lost in the projection.
  EXPECT_GT(s.left[0].to_sibling_px[10].norm(), 3.0);
  EXPECT_FALSE(CrossesStrands(PairScene::Candidate(s.left[0], s.left[1], s.a), s.left[0],
                              s.left[1], ca, cb));
  EXPECT_FALSE(CrossesStrands(PairScene::Candidate(s.right[0], s.right[1], s.b), s.right[0],
                              s.right[1], ca, cb));
  std::vector<Eigen::Vector3d> between;
  for (size_t k = 0; k < s.a.size(); ++k) between.push_back(0.5 * (s.a[k] + s.b[k]));
  EXPECT_TRUE(CrossesStrands(PairScene::Candidate(s.left[0], s.right[1], between), s.left[0],
                             s.right[1], ca, cb));
  EXPECT_TRUE(CrossesStrands(PairScene::Candidate(s.right[0], s.left[1], between), s.right[0],
                             s.left[1], ca, cb));
}

}  // namespace
}  // namespace vb::reconstruct
