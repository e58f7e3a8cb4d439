// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/cut_points.h"

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb::decide {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

Cane Straight(int id, std::optional<int> parent, CaneKind kind, const Eigen::Vector3d& base,
              const Eigen::Vector3d& tip, double base_radius, double tip_radius) {
  Cane cane;
  cane.id = CaneId(id);
  if (parent) cane.parent_id = CaneId(*parent);
  cane.kind = kind;
  // Several points, so that arc-length interpolation is exercised.
  for (int k = 0; k <= 4; ++k) {
    const double f = k / 4.0;
    cane.polyline.points.push_back(base + f * (tip - base));
    cane.polyline.radii.push_back(base_radius + f * (tip_radius - base_radius));
  }
  return cane;
}

// Head sphere at (0, 0.8, 1.0), radius 0.04, on a 1 m trunk.
//  2: right along the row from the head surface, 1.2 m (longer than max_kept_length_m 0.9).
//  3: left from the head surface, 0.6 m.
//  4: up from the head surface, 0.5 m, with secondary 5 from 0.2 m along it (0.4 m long) and
//     tertiary 6 from 0.1 m along 5.
//  7: a short cane (0.105 m) from the head; 8: an old spur; 9: a cane from 3 at 0.005 m.
VineModel TestVine() {
  VineModel m;
  m.canes.push_back(Straight(1, std::nullopt, CaneKind::kTrunk, {0, 0.8, 0}, {0, 0.8, 1.0}, 0.02,
                             0.02));
  m.canes.push_back(Straight(2, 1, CaneKind::kCane, {0.04, 0.8, 1.0}, {1.24, 0.8, 1.0}, 0.005,
                             0.002));
  m.canes.push_back(Straight(3, 1, CaneKind::kCane, {-0.04, 0.8, 1.0}, {-0.64, 0.8, 1.0}, 0.004,
                             0.002));
  m.canes.push_back(Straight(4, 1, CaneKind::kCane, {0, 0.8, 1.04}, {0, 0.8, 1.54}, 0.004, 0.002));
  m.canes.push_back(Straight(5, 4, CaneKind::kCane, {0, 0.8, 1.24}, {0.4, 0.8, 1.24}, 0.003,
                             0.0015));
  m.canes.push_back(Straight(6, 5, CaneKind::kCane, {0.1, 0.8, 1.24}, {0.1, 0.8, 1.54}, 0.002,
                             0.001));
  m.canes.push_back(Straight(7, 1, CaneKind::kCane, {0.0, 0.76, 1.0}, {0.0, 0.655, 1.0}, 0.004,
                             0.003));
  m.canes.push_back(Straight(8, 1, CaneKind::kSpur, {0.0, 0.84, 1.0}, {0.0, 0.9, 1.0}, 0.006,
                             0.005));
  m.canes.push_back(Straight(9, 3, CaneKind::kCane, {-0.045, 0.8, 1.0}, {-0.045, 0.8, 1.4}, 0.002,
                             0.001));
  m.head.spheres = {{Eigen::Vector3d(0, 0.8, 1.0), 0.04}};
  return m;
}

std::vector<Candidate> Candidates(const VineModel& m) {
  auto c = FindCandidates(m, PruningPolicy{});
  EXPECT_TRUE(c.ok()) << c.status();
  return *c;
}

std::vector<CaneId> Ids(std::initializer_list<int> ids) {
  std::vector<CaneId> out;
  for (int id : ids) out.push_back(CaneId(id));
  return out;
}

const Cut* CutOn(const CutPlacement& p, int cane_id) {
  for (const Cut& c : p.cuts) {
    if (c.cane_id == CaneId(cane_id)) return &c;
  }
  return nullptr;
}

double DistanceToCane(const VineModel& m, const Cut& cut) {
  double d = 0.0;
  m.canes[*m.IndexOf(cut.cane_id)].polyline.Project(cut.point, &d);
  return d;
}

CutPlacement Place(const VineModel& m, const Scheme& scheme, const PruningPolicy& policy = {},
                   double slide = 0.05) {
  auto p = PlaceCuts(m, Candidates(m), policy, scheme, slide);
  EXPECT_TRUE(p.ok()) << p.status();
  return p.ok() ? *p : CutPlacement{};
}

TEST(PlaceCuts, RemovesEveryOtherCaneNearItsBaseOnItsAxis) {
  const VineModel m = TestVine();
  const CutPlacement p = Place(m, {Ids({2, 3}), {}});
  // 4 is removed (5 and 6 fall with it); 7 is removed; 9 grows from 3 within 1 cm of its base,
  // below any cut, so it needs its own.
  ASSERT_EQ(p.cuts.size(), 4u);
  const Cut* c4 = CutOn(p, 4);
  ASSERT_NE(c4, nullptr);
  EXPECT_EQ(c4->reason, CutReason::kRemove);
  EXPECT_TRUE(c4->point.isApprox(Eigen::Vector3d(0, 0.8, 1.05), 1e-12));
  EXPECT_TRUE(c4->direction.isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_NEAR(c4->diameter_m, 2 * (0.004 - 0.002 * 0.01 / 0.5), 1e-12);
  EXPECT_EQ(CutOn(p, 5), nullptr);
  EXPECT_EQ(CutOn(p, 6), nullptr);
  ASSERT_NE(CutOn(p, 7), nullptr);
  ASSERT_NE(CutOn(p, 9), nullptr);
  EXPECT_EQ(CutOn(p, 9)->reason, CutReason::kRemove);
  // 2 is kept but 1.2 m long: shortened at 0.9 m.
  const Cut* c2 = CutOn(p, 2);
  ASSERT_NE(c2, nullptr);
  EXPECT_EQ(c2->reason, CutReason::kShorten);
  EXPECT_TRUE(c2->point.isApprox(Eigen::Vector3d(0.94, 0.8, 1.0), 1e-12));
  EXPECT_EQ(CutOn(p, 3), nullptr);  // kept, 0.6 m
  EXPECT_EQ(CutOn(p, 1), nullptr);  // trunk
  EXPECT_EQ(CutOn(p, 8), nullptr);  // old spur
  for (const Cut& cut : p.cuts) {
    EXPECT_LT(DistanceToCane(m, cut), 1e-9) << cut.cane_id.value;
    EXPECT_NEAR(cut.direction.norm(), 1.0, 1e-12);
    EXPECT_GT(cut.diameter_m, 0.0);
  }
}

TEST(PlaceCuts, IdsFollowCaneIds) {
  const CutPlacement p = Place(TestVine(), {Ids({2, 3}), {}});
  for (size_t i = 0; i < p.cuts.size(); ++i) {
    EXPECT_EQ(p.cuts[i].id, CutId(static_cast<int64_t>(i) + 1));
    if (i > 0) {
      EXPECT_LT(p.cuts[i - 1].cane_id, p.cuts[i].cane_id);
    }
  }
}

TEST(PlaceCuts, SpursAreCutAtTheirLengthUnlessShortAlready) {
  const VineModel m = TestVine();
  const CutPlacement p = Place(m, {Ids({2}), Ids({3, 7})});
  const Cut* c3 = CutOn(p, 3);
  ASSERT_NE(c3, nullptr);
  EXPECT_EQ(c3->reason, CutReason::kSpur);
  EXPECT_TRUE(c3->point.isApprox(Eigen::Vector3d(-0.14, 0.8, 1.0), 1e-12));
  EXPECT_TRUE(c3->direction.isApprox(-Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_EQ(CutOn(p, 7), nullptr);  // 0.105 m: not longer than 0.10 + 0.01
  EXPECT_THAT(p.notes, Contains(HasSubstr("cane 7: spur left uncut")));
}

TEST(PlaceCuts, KeptSecondaryCaneShortensItsParentInsteadOfRemovingIt) {
  const VineModel m = TestVine();
  const CutPlacement p = Place(m, {Ids({2, 5}), {}});
  // 4 must stay up to just beyond 5's base (0.2 m along 4): 0.2 + 0.003 + 0.01.
  const Cut* c4 = CutOn(p, 4);
  ASSERT_NE(c4, nullptr);
  EXPECT_EQ(c4->reason, CutReason::kShorten);
  EXPECT_TRUE(c4->point.isApprox(Eigen::Vector3d(0, 0.8, 1.04 + 0.213), 1e-12));
  EXPECT_THAT(p.notes, Contains(HasSubstr("cane 4: shortened to 0.213 m instead of removed")));
  EXPECT_EQ(CutOn(p, 5), nullptr);  // kept, 0.4 m
  // 6 grows from kept 5 and is removed at its own base.
  ASSERT_NE(CutOn(p, 6), nullptr);
  EXPECT_EQ(CutOn(p, 6)->reason, CutReason::kRemove);
}

TEST(PlaceCuts, SpurOnATertiaryCaneHoldsBothAncestors) {
  const VineModel m = TestVine();
  const CutPlacement p = Place(m, {Ids({2, 3}), Ids({6})});
  ASSERT_NE(CutOn(p, 4), nullptr);
  ASSERT_NE(CutOn(p, 5), nullptr);
  EXPECT_EQ(CutOn(p, 4)->reason, CutReason::kShorten);
  EXPECT_EQ(CutOn(p, 5)->reason, CutReason::kShorten);
  EXPECT_NEAR(CutOn(p, 5)->point.x(), 0.1 + 0.002 + 0.01, 1e-12);
  EXPECT_EQ(CutOn(p, 6)->reason, CutReason::kSpur);
}

TEST(PlaceCuts, ParentTooShortToShortenIsLeftWhole) {
  VineModel m = TestVine();
  // Make 5 grow from 4 near its tip: holding 4 beyond it leaves less than 1 cm to cut.
  m.canes[4] = Straight(5, 4, CaneKind::kCane, {0, 0.8, 1.535}, {0.4, 0.8, 1.535}, 0.003, 0.0015);
  m.canes[5] = Straight(6, 5, CaneKind::kCane, {0.1, 0.8, 1.535}, {0.1, 0.8, 1.8}, 0.002, 0.001);
  const CutPlacement p = Place(m, {Ids({2, 5}), {}});
  EXPECT_EQ(CutOn(p, 4), nullptr);
  EXPECT_THAT(p.notes, Contains(HasSubstr("cane 4: left uncut instead of removed")));
}

TEST(PlaceCuts, CutsInsideTheHeadSlideOut) {
  VineModel m = TestVine();
  m.head.spheres.push_back({Eigen::Vector3d(0.07, 0.8, 1.0), 0.025});  // over cane 2's base
  const CutPlacement p = Place(m, {Ids({3, 4}), {}}, PruningPolicy{}, 0.1);
  const Cut* c2 = CutOn(p, 2);
  ASSERT_NE(c2, nullptr);
  EXPECT_EQ(c2->reason, CutReason::kRemove);
  // Leaves the sphere at x = 0.095, within one slide step.
  EXPECT_GE(c2->point.x(), 0.095);
  EXPECT_LE(c2->point.x(), 0.095 + 0.0005 + 1e-12);
  EXPECT_LT(DistanceToCane(m, *c2), 1e-9);
  EXPECT_THAT(p.notes, Contains(HasSubstr("cane 2: cut slid 0.04")));
  // With a 1 cm limit it stays inside, 1 cm further, and says so.
  const CutPlacement limited = Place(m, {Ids({3, 4}), {}}, PruningPolicy{}, 0.01);
  ASSERT_NE(CutOn(limited, 2), nullptr);
  EXPECT_NEAR(CutOn(limited, 2)->point.x(), 0.06, 1e-12);
  EXPECT_THAT(limited.notes, Contains(HasSubstr("cane 2: cut still inside the head")));
  // No head: no slide.
  m.head.spheres.clear();
  const CutPlacement bare = Place(m, {Ids({3, 4}), {}});
  EXPECT_NEAR(CutOn(bare, 2)->point.x(), 0.05, 1e-12);
  EXPECT_THAT(bare.notes, IsEmpty());
}

TEST(PlaceCuts, RejectsSchemesThatDoNotFitTheCandidates) {
  const VineModel m = TestVine();
  const std::vector<Candidate> cands = Candidates(m);
  const PruningPolicy policy;
  struct Case {
    Scheme scheme;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{Ids({2, 8}), {}}, "scheme.keep[1]: cane 8 is not a candidate"},
      {{Ids({2}), Ids({2})}, "scheme.spurs[0]: cane 2 is already scheme.keep[0]"},
      {{Ids({2, 4}), Ids({6})}, "cane 6 grows from cane 4 (scheme.keep[1])"},
  };
  for (const Case& c : cases) {
    auto p = PlaceCuts(m, cands, policy, c.scheme, 0.05);
    EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(p.status().message(), HasSubstr(c.message));
  }
  EXPECT_THAT(PlaceCuts(m, cands, policy, {}, -1.0).status().message(),
              HasSubstr("max_head_slide_m"));
  std::vector<Candidate> wrong = cands;
  wrong[1].cane_index = 0;
  EXPECT_THAT(PlaceCuts(m, wrong, policy, {}, 0.05).status().message(),
              HasSubstr("candidates[1]: cane 3 at index 0 is not a cane of this model"));
  PruningPolicy bad;
  bad.spur_length_m = -1;
  EXPECT_THAT(PlaceCuts(m, cands, bad, {}, 0.05).status().message(), HasSubstr("spur_length_m"));
}

}  // namespace
}  // namespace vb::decide

namespace vb::decide {
namespace {

// A water shoot grows from the trunk's axis (as the simulator and reconstruction start canes);
// its removal cut lies cut_offset_m beyond the trunk's surface, not inside the trunk.
TEST(PlaceCuts, RemovalCutIsMeasuredFromTheParentsSurface) {
  VineModel m = TestVine();
  m.canes.push_back(Straight(10, 1, CaneKind::kCane, {0, 0.8, 0.5}, {0.5, 0.8, 0.5}, 0.004,
                             0.002));
  const auto cands = Candidates(m);
  Scheme scheme;
  scheme.keep = Ids({2, 3});
  scheme.spurs = Ids({4, 7});
  const auto placed = PlaceCuts(m, cands, PruningPolicy{}, scheme, 0.05);
  ASSERT_TRUE(placed.ok()) << placed.status();
  const Cut* cut = CutOn(*placed, 10);
  ASSERT_NE(cut, nullptr);
  EXPECT_EQ(cut->reason, CutReason::kRemove);
  // Trunk radius 0.02 m, offset 0.01 m: x = 0.03 m, within the 2 mm search step.
  EXPECT_NEAR(cut->point.x(), 0.03, 0.0025);
  EXPECT_GT(cut->point.x(), 0.02);
}

}  // namespace
}  // namespace vb::decide
