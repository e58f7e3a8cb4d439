// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/cane_assembly.h"

#include <algorithm>
#include <limits>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "sim/vine_random.h"

namespace vb::reconstruct {
namespace {

constexpr double kLongCaneM = 0.3;

double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& line) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    best = std::min(best, PointSegmentDistance(p, line.points[i], line.points[i + 1]));
  }
  return best;
}

// A piece of `cane` over arc lengths [s0, s1], points every ~1.5 cm with isotropic Gaussian noise
// of `noise_m` per axis and radii with 10% noise.
Piece3D Cut(const Polyline3& cane, double s0, double s1, double noise_m, sim::VineRng& rng) {
  Piece3D piece;
  const int n = std::max(2, static_cast<int>(std::ceil((s1 - s0) / 0.015)) + 1);
  for (int k = 0; k < n; ++k) {
    const double s = s0 + (s1 - s0) * k / (n - 1);
    piece.polyline.points.push_back(cane.PointAt(s) +
                                    noise_m * Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal()));
    piece.polyline.radii.push_back(cane.RadiusAt(s) * (1.0 + 0.1 * rng.Normal()));
  }
  piece.probability = rng.Uniform(0.6, 1.0);
  piece.support = rng.Uniform(0.7, 1.0);
  return piece;
}

// Pieces as correspondence would report them for one cane: two "view pairs", each cutting the
// cane into pieces of 8-30 cm that overlap by up to 5 cm or leave gaps of 1-2 cm.
void CutCane(const Polyline3& cane, double noise_m, sim::VineRng& rng, std::vector<Piece3D>* out) {
  const double length = cane.Length();
  for (int pair = 0; pair < 2; ++pair) {
    double s = rng.Uniform(0.0, 0.02);
    while (s < length - 0.02) {
      const double end = std::min(length, s + rng.Uniform(0.08, 0.3));
      out->push_back(Cut(cane, s, end, noise_m, rng));
      s = rng.Bernoulli(0.5) ? end - rng.Uniform(0.0, 0.05) : end + rng.Uniform(0.01, 0.02);
    }
  }
}

struct Truth {
  std::vector<Polyline3> canes;  // every cane, trunk and spur of the vine
};

Truth TruthOf(uint64_t seed) {
  const sim::Scene scene = sim::GenerateScene(seed, 0).value();
  Truth truth;
  for (const Cane& cane : scene.vine.canes) truth.canes.push_back(cane.polyline);
  return truth;
}

// Ghosts: short random straight pieces at least 5 cm from every true cane.
std::vector<Piece3D> Ghosts(const Truth& truth, int count, sim::VineRng& rng) {
  std::vector<Piece3D> ghosts;
  while (static_cast<int>(ghosts.size()) < count) {
    const Eigen::Vector3d a(rng.Uniform(-0.8, 0.8), rng.Uniform(0.6, 1.0), rng.Uniform(0.5, 1.8));
    const Eigen::Vector3d dir =
        Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal()).normalized();
    const Eigen::Vector3d b = a + rng.Uniform(0.04, 0.1) * dir;
    bool clear = true;
    for (const Polyline3& cane : truth.canes) {
      if (DistanceToPolyline(a, cane) < 0.05 || DistanceToPolyline(b, cane) < 0.05) clear = false;
    }
    if (!clear) continue;
    Piece3D ghost;
    ghost.polyline.points = {a, 0.5 * (a + b), b};
    ghost.polyline.radii = {0.004, 0.004, 0.004};
    ghost.probability = rng.Uniform(0.3, 0.7);
    ghost.support = rng.Uniform(0.5, 1.0);
    ghosts.push_back(ghost);
  }
  return ghosts;
}

// Fraction of `cane`'s length (1 cm samples) within `tolerance_m` of `line`.
double Coverage(const Polyline3& cane, const Polyline3& line, double tolerance_m) {
  const std::vector<Eigen::Vector3d> samples = cane.Sample(0.01);
  int covered = 0;
  for (const Eigen::Vector3d& p : samples) covered += DistanceToPolyline(p, line) <= tolerance_m;
  return static_cast<double>(covered) / samples.size();
}

struct Scored {
  int long_canes = 0;         // long and separable (not bundled along a wire with another)
  int long_canes_whole = 0;   // of those, one output polyline covers >= 90%
  double covered_length = 0.0;  // of long canes, by any output polyline, within 1 cm
  double long_length = 0.0;
  int ghost_outputs = 0;      // outputs lying mostly > 2 cm from every true cane
};

// Canes draped along the same wire lie within a few mm of each other for long stretches: in 3D
// they are one bundle and cannot be told apart, so only canes with less than 10% of their length
// within 1.5 cm of another cane are required to come out whole.
bool Separable(const Truth& truth, size_t i) {
  double bundled = 0.0;
  for (size_t j = 0; j < truth.canes.size(); ++j) {
    if (j != i) bundled = std::max(bundled, Coverage(truth.canes[i], truth.canes[j], 0.015));
  }
  return bundled < 0.1;
}

Scored Score(const Truth& truth, const std::vector<Polyline3>& out) {
  Scored score;
  for (size_t i = 0; i < truth.canes.size(); ++i) {
    const Polyline3& cane = truth.canes[i];
    const double length = cane.Length();
    if (length < kLongCaneM) continue;
    score.long_length += length;
    if (Separable(truth, i)) {
      ++score.long_canes;
      double best = 0.0;
      for (const Polyline3& line : out) best = std::max(best, Coverage(cane, line, 0.01));
      if (best >= 0.9) ++score.long_canes_whole;
    }
    const std::vector<Eigen::Vector3d> samples = cane.Sample(0.01);
    int covered = 0;
    for (const Eigen::Vector3d& p : samples) {
      for (const Polyline3& line : out) {
        if (DistanceToPolyline(p, line) <= 0.01) {
          ++covered;
          break;
        }
      }
    }
    score.covered_length += length * covered / samples.size();
  }
  for (const Polyline3& line : out) {
    int far = 0;
    for (const Eigen::Vector3d& p : line.points) {
      double d = std::numeric_limits<double>::infinity();
      for (const Polyline3& cane : truth.canes) d = std::min(d, DistanceToPolyline(p, cane));
      far += d > 0.02;
    }
    if (far * 2 > static_cast<int>(line.points.size())) ++score.ghost_outputs;
  }
  return score;
}

// A piece through `points`, radius `radius_m` everywhere, with `probability` and full support.
Piece3D PieceThrough(std::vector<Eigen::Vector3d> points, double radius_m, double probability) {
  Piece3D piece;
  piece.polyline.radii.assign(points.size(), radius_m);
  piece.polyline.points = std::move(points);
  piece.probability = probability;
  piece.support = 1.0;
  return piece;
}

// A straight piece from a to b: 21 points, radius 5 mm, probability 0.9.
Piece3D StraightPiece(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= 20; ++i) points.push_back(a + (b - a) * i / 20.0);
  return PieceThrough(std::move(points), 0.005, 0.9);
}

// How many canes AssembleCanes makes of `pieces` (no deadline); -1 if it fails.
int CaneCount(const std::vector<Piece3D>& pieces, const AssemblyOptions& options = {}) {
  const absl::StatusOr<std::vector<Polyline3>> canes =
      AssembleCanes(pieces, options, Deadline::Infinite());
  return canes.ok() ? static_cast<int>(canes->size()) : -1;
}

TEST(AssembleCanes, RecoversWholeCanesFromNoisyDuplicatedPieces) {
  int long_canes = 0, whole = 0, outputs = 0, true_canes = 0;
  for (uint64_t seed : {1011u, 1234u, 1777u}) {
    SCOPED_TRACE(seed);
    const Truth truth = TruthOf(seed);
    sim::VineRng rng(seed);
    std::vector<Piece3D> pieces;
    for (const Polyline3& cane : truth.canes) CutCane(cane, 0.002, rng, &pieces);
    const std::vector<Piece3D> ghosts = Ghosts(truth, 6, rng);
    pieces.insert(pieces.end(), ghosts.begin(), ghosts.end());
    // Correspondence reports pieces in no particular order.
    for (size_t i = pieces.size(); i > 1; --i) std::swap(pieces[i - 1], pieces[rng.Next() % i]);

    const absl::StatusOr<std::vector<Polyline3>> canes =
        AssembleCanes(pieces, AssemblyOptions(), Deadline::Infinite());
    ASSERT_TRUE(canes.ok()) << canes.status();
    const Scored score = Score(truth, *canes);
    EXPECT_GE(score.covered_length, 0.95 * score.long_length);
    EXPECT_EQ(score.ghost_outputs, 0);
    long_canes += score.long_canes;
    whole += score.long_canes_whole;
    outputs += static_cast<int>(canes->size());
    true_canes += static_cast<int>(truth.canes.size());
    for (const Polyline3& line : *canes) {
      EXPECT_TRUE(line.Validate("cane").ok());
      for (size_t i = 0; i + 1 < line.points.size(); ++i) {
        const double step = (line.points[i + 1] - line.points[i]).norm();
        EXPECT_GT(step, 0.005);
        EXPECT_LT(step, 0.015);
      }
    }
  }
  // Nearly every separable long cane comes out whole. Bundles come out as one polyline with the
  // canes leaving them as separate pieces, and short spurs are dropped, so the count is near the
  // truth's but not equal.
  EXPECT_GE(whole, long_canes * 9 / 10) << whole << " of " << long_canes;
  EXPECT_GE(long_canes, 15);
  EXPECT_LE(outputs, true_canes * 13 / 10) << outputs << " vs " << true_canes;
  EXPECT_GE(outputs, true_canes * 7 / 10) << outputs << " vs " << true_canes;
}

TEST(AssembleCanes, MergesExactDuplicatesIntoOne) {
  Polyline3 cane;
  for (int i = 0; i <= 40; ++i) {
    cane.points.push_back({-0.2 + 0.01 * i, 0.8, 1.0 + 0.05 * std::sin(0.1 * i)});
    cane.radii.push_back(0.005);
  }
  std::vector<Piece3D> pieces(3, PieceThrough(cane.points, 0.005, 0.9));
  std::reverse(pieces[1].polyline.points.begin(), pieces[1].polyline.points.end());
  const auto canes = AssembleCanes(pieces, AssemblyOptions(), Deadline::Infinite());
  ASSERT_TRUE(canes.ok()) << canes.status();
  ASSERT_EQ(canes->size(), 1u);
  EXPECT_NEAR((*canes)[0].Length(), cane.Length(), 0.01);
  EXPECT_GT(Coverage(cane, (*canes)[0], 0.002), 0.99);
}

TEST(AssembleCanes, ChainsAcrossAGapButNotAcrossACorner) {
  // Collinear with a 2 cm gap: one cane of 0.42 m.
  const auto canes = AssembleCanes(
      {StraightPiece({0, 0.8, 1}, {0.2, 0.8, 1}), StraightPiece({0.42, 0.8, 1}, {0.22, 0.8, 1})},
      AssemblyOptions(), Deadline::Infinite());
  ASSERT_TRUE(canes.ok());
  ASSERT_EQ(canes->size(), 1u);
  EXPECT_NEAR((*canes)[0].Length(), 0.42, 0.005);
  // At right angles, ends 1 cm apart: two canes (a crossing or a branch, not a continuation).
  EXPECT_EQ(CaneCount({StraightPiece({0, 0.8, 1}, {0.2, 0.8, 1}),
                       StraightPiece({0.21, 0.8, 1.0}, {0.21, 0.8, 1.2})}),
            2);
  // Two canes crossing in an X are not merged.
  EXPECT_EQ(CaneCount({StraightPiece({-0.2, 0.8, 1}, {0.2, 0.8, 1}),
                       StraightPiece({0, 0.8, 0.8}, {0, 0.8, 1.2})}),
            2);
  // Parallel canes 3 cm apart stay apart.
  EXPECT_EQ(CaneCount({StraightPiece({0, 0.8, 1}, {0.3, 0.8, 1}),
                       StraightPiece({0, 0.8, 1.03}, {0.3, 0.8, 1.03})}),
            2);
  // A radius jump (5 mm -> 20 mm) is a different structure, not a continuation.
  std::vector<Piece3D> pieces = {StraightPiece({0, 0.8, 1}, {0.2, 0.8, 1}),
                                 StraightPiece({0.22, 0.8, 1}, {0.42, 0.8, 1})};
  for (double& r : pieces[1].polyline.radii) r = 0.02;
  EXPECT_EQ(CaneCount(pieces), 2);
}

TEST(AssembleCanes, ChainsAcrossALongGapOnlyWhenStraight) {
  // The second piece starts `gap_m` beyond the first's end, turned by `bend_deg` about the end.
  auto pair = [&](double gap_m, double bend_deg) {
    const double t = bend_deg * 3.14159265358979 / 180.0;
    const Eigen::Vector3d start(0.2 + gap_m * std::cos(t), 0.8, 1.0 + gap_m * std::sin(t));
    const Eigen::Vector3d end = start + 0.2 * Eigen::Vector3d(std::cos(t), 0.0, std::sin(t));
    return std::vector<Piece3D>{StraightPiece({0, 0.8, 1}, {0.2, 0.8, 1}),
                                StraightPiece(start, end)};
  };
  AssemblyOptions options;
  options.max_gap_m = 0.10;
  options.max_long_gap_m = 0.15;
  options.max_long_gap_angle_deg = 12.0;
  // A post hides 13 cm of a straight cane: one cane across the gap.
  const auto canes = AssembleCanes(pair(0.13, 0.0), options, Deadline::Infinite());
  ASSERT_TRUE(canes.ok()) << canes.status();
  ASSERT_EQ(canes->size(), 1u);
  EXPECT_NEAR((*canes)[0].Length(), 0.53, 0.01);
  // The same gap with a 20 degree turn: two canes (20 degrees is within max_chain_angle_deg,
  // which a gap of 8 cm is allowed).
  EXPECT_EQ(CaneCount(pair(0.13, 20.0), options), 2);
  EXPECT_EQ(CaneCount(pair(0.08, 20.0), options), 1);
  // Beyond max_long_gap_m, or with long gaps turned off: two canes.
  EXPECT_EQ(CaneCount(pair(0.17, 0.0), options), 2);
  options.max_long_gap_m = options.max_gap_m;
  EXPECT_EQ(CaneCount(pair(0.13, 0.0), options), 2);
}

TEST(AssembleCanes, EmptyInputGivesNoCanes) {
  const auto canes = AssembleCanes({}, AssemblyOptions(), Deadline::Infinite());
  ASSERT_TRUE(canes.ok());
  EXPECT_TRUE(canes->empty());
}

TEST(AssembleCanes, NonFinitePieceRejects) {
  Piece3D piece = PieceThrough({{0, 0.8, 1}, {0.1, 0.8, std::nan("")}}, 0.004, 1.0);
  const auto canes = AssembleCanes({piece, piece}, AssemblyOptions(), Deadline::Infinite());
  ASSERT_EQ(canes.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(canes.status().message()).find("pieces[0]"), std::string::npos);
  piece.polyline.points[1].z() = 1.0;
  piece.probability = 1.5;
  EXPECT_EQ(AssembleCanes({piece}, AssemblyOptions(), Deadline::Infinite()).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(AssembleCanes, InvalidOptionsRejects) {
  AssemblyOptions options;
  options.step_m = 0.0;
  EXPECT_EQ(AssembleCanes({}, options, Deadline::Infinite()).status().code(),
            absl::StatusCode::kInvalidArgument);
  options = AssemblyOptions();
  options.max_radius_ratio = 0.5;
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  options = AssemblyOptions();
  options.merge_angle_deg = std::nan("");
  EXPECT_EQ(options.Validate().code(), absl::StatusCode::kInvalidArgument);
  options = AssemblyOptions();
  options.max_long_gap_m = options.max_gap_m - 0.01;
  EXPECT_NE(std::string(options.Validate().message()).find("max_long_gap_m"), std::string::npos);
  options = AssemblyOptions();
  options.max_long_gap_angle_deg = 95.0;
  EXPECT_NE(std::string(options.Validate().message()).find("max_long_gap_angle_deg"),
            std::string::npos);
}

TEST(AssembleCanes, ExpiredDeadlineFails) {
  const Piece3D piece = PieceThrough({{0, 0.8, 1}, {0.2, 0.8, 1}}, 0.004, 1.0);
  EXPECT_EQ(AssembleCanes({piece}, AssemblyOptions(), Deadline::In(0.0)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
}

}  // namespace
}  // namespace vb::reconstruct
