// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/decide.h"

#include <atomic>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/decide/phenomics.h"

namespace vb::decide {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

Cane Straight(int id, std::optional<int> parent, CaneKind kind, const Eigen::Vector3d& base,
              const Eigen::Vector3d& tip, double radius) {
  Cane cane;
  cane.id = CaneId(id);
  if (parent) cane.parent_id = CaneId(*parent);
  cane.kind = kind;
  cane.polyline.points = {base, 0.5 * (base + tip), tip};
  cane.polyline.radii = {radius, radius, radius};
  return cane;
}

// A head at (0, 0.8, 0.9), the fruiting wire at 0.95. Canes 2 (right) and 3 (left) are what a
// pruner keeps: from the head, along the row, 9 mm thick, long. 4 is a thin water shoot, 5 a
// short cane near the head (a spur), 6 a cane growing straight up, 7 a secondary cane on 6.
VineModel SimpleVine() {
  VineModel m;
  m.canes.push_back(Straight(1, std::nullopt, CaneKind::kTrunk, {0, 0.8, 0}, {0, 0.8, 0.9}, 0.02));
  m.canes.push_back(Straight(2, 1, CaneKind::kCane, {0.04, 0.8, 0.9}, {1.04, 0.8, 0.93}, 0.0045));
  m.canes.push_back(Straight(3, 1, CaneKind::kCane, {-0.04, 0.8, 0.9}, {-1.0, 0.8, 0.95}, 0.0045));
  m.canes.push_back(Straight(4, 1, CaneKind::kCane, {0.02, 0.8, 0.4}, {0.3, 0.8, 0.9}, 0.002));
  m.canes.push_back(Straight(5, 1, CaneKind::kCane, {0.0, 0.76, 0.9}, {0.0, 0.56, 0.95}, 0.004));
  m.canes.push_back(Straight(6, 1, CaneKind::kCane, {0, 0.8, 0.94}, {0.05, 0.8, 1.6}, 0.004));
  m.canes.push_back(Straight(7, 6, CaneKind::kCane, {0.025, 0.8, 1.27}, {0.5, 0.8, 1.4}, 0.003));
  m.head.spheres = {{Eigen::Vector3d(0, 0.8, 0.9), 0.04}};
  m.wires = {{WireId(1), {{-2, 0.8, 0.95}, {2, 0.8, 0.95}}, 0.0015}};
  return m;
}

TEST(Decide, KeepsWhatAPrunerWouldOnASimpleVine) {
  PruningPolicy policy;
  policy.spurs = 1;
  auto decision = Decide(SimpleVine(), policy);
  ASSERT_TRUE(decision.ok()) << decision.status();
  const CutPlan& plan = decision->plan;
  EXPECT_EQ(plan.keep, (std::vector<CaneId>{CaneId(2), CaneId(3)}));
  EXPECT_EQ(plan.spurs, (std::vector<CaneId>{CaneId(5)}));
  EXPECT_EQ(PruningPolicyToJson(plan.policy), PruningPolicyToJson(policy));
  EXPECT_TRUE(plan.ValidateAgainst(SimpleVine()).ok());
  // 2 and 3 are shortened to 0.9 m; 4 and 6 removed; 7 falls with 6; spur 5 cut at 0.1 m.
  std::map<int64_t, CutReason> reasons;
  for (const Cut& c : plan.cuts) reasons[c.cane_id.value] = c.reason;
  EXPECT_EQ(reasons, (std::map<int64_t, CutReason>{{2, CutReason::kShorten},
                                                   {3, CutReason::kShorten},
                                                   {4, CutReason::kRemove},
                                                   {5, CutReason::kSpur},
                                                   {6, CutReason::kRemove}}));
  EXPECT_EQ(decision->scheme.keep, plan.keep);
  EXPECT_EQ(decision->stats.candidates, 6);
  EXPECT_GT(decision->stats.schemes_visited, 0);
}

// Left-out wood (VineModel::obstacles) is for the planner: lying across the head and along the
// canes a pruner keeps, it changes neither the plan nor the phenomics.
TEST(Decide, IgnoresLeftOutWood) {
  const VineModel vine = SimpleVine();
  VineModel with = vine;
  for (const auto& [a, b] : {std::pair{Eigen::Vector3d(-0.3, 0.78, 0.9), Eigen::Vector3d(0.3, 0.82, 0.92)},
                             std::pair{Eigen::Vector3d(0.2, 0.8, 0.93), Eigen::Vector3d(1.0, 0.8, 0.96)},
                             std::pair{Eigen::Vector3d(-0.6, 0.7, 1.3), Eigen::Vector3d(-0.2, 0.8, 1.1)}}) {
    WoodObstacle o;
    o.polyline.points = {a, 0.5 * (a + b), b};
    o.polyline.radii = {0.006, 0.005, 0.004};
    with.obstacles.push_back(o);
  }
  ASSERT_TRUE(with.Validate().ok());
  for (int spurs : {0, 1}) {
    PruningPolicy policy;
    policy.spurs = spurs;
    auto without_wood = Decide(vine, policy);
    auto with_wood = Decide(with, policy);
    ASSERT_TRUE(without_wood.ok()) << without_wood.status();
    ASSERT_TRUE(with_wood.ok()) << with_wood.status();
    EXPECT_FALSE(with_wood->plan.cuts.empty());
    EXPECT_EQ(CutPlanToJson(with_wood->plan), CutPlanToJson(without_wood->plan));
    EXPECT_EQ(with_wood->notes, without_wood->notes);
    auto p_without = ComputePhenomics(vine, &without_wood->plan);
    auto p_with = ComputePhenomics(with, &with_wood->plan);
    ASSERT_TRUE(p_without.ok()) << p_without.status();
    ASSERT_TRUE(p_with.ok()) << p_with.status();
    EXPECT_EQ(PhenomicsToJson(*p_with), PhenomicsToJson(*p_without));
  }
}

TEST(Decide, TrunkWithoutCanesGivesAnEmptyPlanAndANote) {
  VineModel m = SimpleVine();
  m.canes.resize(1);
  auto decision = Decide(m, PruningPolicy{});
  ASSERT_TRUE(decision.ok()) << decision.status();
  EXPECT_THAT(decision->plan.cuts, IsEmpty());
  EXPECT_THAT(decision->plan.keep, IsEmpty());
  EXPECT_THAT(decision->notes, Contains(HasSubstr("no candidate canes")));
}

TEST(Decide, NotesWhenFewerCanesCanBeKeptThanAsked) {
  PruningPolicy policy;
  policy.canes_to_keep = 4;
  policy.min_kept_length_m = 0.6;
  auto decision = Decide(SimpleVine(), policy);
  ASSERT_TRUE(decision.ok()) << decision.status();
  EXPECT_EQ(decision->plan.keep.size(), 3u);  // 2, 3 and 6 are long enough
  EXPECT_THAT(decision->notes, Contains(HasSubstr("only 3 cane(s) can be kept")));
}

TEST(Decide, RejectsMalformedModelsNamingTheProblem) {
  struct Case {
    std::function<void(VineModel&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](VineModel& m) { m.canes.clear(); }, "model: empty"},
      {[](VineModel& m) {
         m.canes[0].kind = CaneKind::kCane;
         m.canes[0].parent_id = CaneId(7);
       },
       "parent_id chain forms a cycle"},
      {[](VineModel& m) { m.canes[3].parent_id = CaneId(42); },
       "canes[3] (id 4): parent_id 42 is not a cane in this model"},
      {[](VineModel& m) { m.canes[2].polyline.points[1].y() = std::nan(""); },
       "canes[2] (id 3).points[1] is not finite"},
      {[](VineModel& m) { m.canes[5].polyline.radii.pop_back(); },
       "canes[5] (id 6).radii: has 2 entries for 3 points"},
      {[](VineModel& m) { m.canes[4].id = CaneId(2); }, "canes[4] (id 2): duplicate id"},
      {[](VineModel& m) { m.head.spheres[0].radius = -1; }, "head.spheres[0]"},
      {[](VineModel& m) {
         m.canes.erase(m.canes.begin());
         m.canes[0].parent_id.reset();  // a second root that is no trunk
       },
       "parent_id is null but kind is cane"},
  };
  for (const Case& c : cases) {
    VineModel m = SimpleVine();
    c.edit(m);
    auto decision = Decide(m, PruningPolicy{});
    EXPECT_EQ(decision.status().code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(decision.status().message(), HasSubstr(c.message));
  }
}

TEST(Decide, RejectsBadPolicyAndOptions) {
  PruningPolicy policy;
  policy.spurs = 30;
  EXPECT_THAT(Decide(SimpleVine(), policy).status().message(), HasSubstr("policy.spurs: 30"));
  DecideOptions options;
  options.weights.w[kImbalance] = INFINITY;
  EXPECT_THAT(Decide(SimpleVine(), PruningPolicy{}, options).status().message(),
              HasSubstr("options.weights.imbalance: not finite"));
  options = DecideOptions{};
  options.max_head_slide_m = -0.1;
  EXPECT_THAT(Decide(SimpleVine(), PruningPolicy{}, options).status().message(),
              HasSubstr("options.max_head_slide_m: -0.1"));
  EXPECT_TRUE(DecideOptions{}.Validate().ok());
}

TEST(Decide, HonoursDeadlineAndCancellation) {
  EXPECT_EQ(Decide(SimpleVine(), PruningPolicy{}, {}, Deadline::In(0.0)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  std::atomic<bool> cancelled{true};
  EXPECT_EQ(Decide(SimpleVine(), PruningPolicy{}, {}, Deadline::In(10.0, &cancelled))
                .status()
                .code(),
            absl::StatusCode::kCancelled);
}

// ---------------------------------------------------------------------------------------------
// Acceptance on ground-truth simulated vines (sim/vine_generator.h).

VineModel SimVine(uint64_t seed) {
  sim::VineGeneratorOptions options;
  options.neighbours = false;
  auto scene = sim::GenerateScene(seed, 0, options);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene->vine;
}

// Arc length on `line` of the point nearest to p.
double ArcOf(const Polyline3& line, const Eigen::Vector3d& p) { return line.Project(p); }

// Independent of cut_points.cc: the cut that makes cane i fall, if any (an ancestor cut below
// the point where i's line of descent leaves that ancestor).
std::optional<CaneId> FallsWith(const VineModel& m, size_t i,
                                const std::unordered_map<int64_t, const Cut*>& cut_on) {
  const Cane* child = &m.canes[i];
  while (child->parent_id.has_value()) {
    const Cane& parent = m.canes[*m.IndexOf(*child->parent_id)];
    auto it = cut_on.find(parent.id.value);
    if (it != cut_on.end()) {
      const double cut_s = ArcOf(parent.polyline, it->second->point);
      const double attach_s = ArcOf(parent.polyline, child->polyline.points.front());
      if (attach_s > cut_s) return parent.id;
    }
    child = &parent;
  }
  return std::nullopt;
}

void CheckPlanOnVine(const VineModel& m, const Decision& d, const PruningPolicy& policy) {
  const CutPlan& plan = d.plan;
  ASSERT_TRUE(plan.ValidateAgainst(m).ok()) << plan.ValidateAgainst(m);
  const std::set<CaneId> kept(plan.keep.begin(), plan.keep.end());
  const std::set<CaneId> spurs(plan.spurs.begin(), plan.spurs.end());
  std::unordered_map<int64_t, const Cut*> cut_on;
  for (const Cut& cut : plan.cuts) {
    EXPECT_TRUE(cut_on.emplace(cut.cane_id.value, &cut).second) << "two cuts on one cane";
    const Cane& cane = m.canes[*m.IndexOf(cut.cane_id)];
    EXPECT_EQ(cane.kind, CaneKind::kCane) << "cut on the trunk or an old spur";
    double distance = 0.0;
    const double s = cane.polyline.Project(cut.point, &distance);
    EXPECT_LT(distance, 0.001) << "cut " << cut.id.value << " is off its cane";
    EXPECT_NEAR(cut.direction.norm(), 1.0, 1e-9);
    EXPECT_GT(cut.direction.dot(cane.polyline.TangentAt(s)), 0.99);
    EXPECT_NEAR(cut.diameter_m, 2 * cane.polyline.RadiusAt(s), 1e-6);
    if (kept.contains(cut.cane_id)) {
      EXPECT_EQ(cut.reason, CutReason::kShorten) << "remove cut on kept cane " << cut.cane_id.value;
      EXPECT_NEAR(s, policy.max_kept_length_m, 1e-6);
    }
    if (spurs.contains(cut.cane_id)) {
      EXPECT_EQ(cut.reason, CutReason::kSpur);
    }
  }
  for (size_t i = 0; i < m.canes.size(); ++i) {
    const Cane& cane = m.canes[i];
    const std::optional<CaneId> falls = FallsWith(m, i, cut_on);
    EXPECT_FALSE(falls && cut_on.contains(cane.id.value))
        << "cane " << cane.id.value << " has a cut but falls with cane " << falls->value;
    EXPECT_FALSE(falls && (kept.contains(cane.id) || spurs.contains(cane.id)))
        << "kept or spur cane " << cane.id.value << " falls with cane " << falls->value;
    // Completeness: every other cane goes, by its own cut or its ancestor's, unless it holds a
    // kept cane or spur (then a note says so).
    if (cane.kind == CaneKind::kCane && !kept.contains(cane.id) && !spurs.contains(cane.id) &&
        !falls && !cut_on.contains(cane.id.value)) {
      EXPECT_THAT(d.notes, Contains(HasSubstr(absl::StrCat("cane ", cane.id.value, ": left uncut"))));
    }
  }
}

TEST(DecideOnSimulatedVines, IsDeterministicAndCutsOnlyWhereItShould) {
  int cuts = 0;
  int kept = 0;
  for (uint64_t seed = 1100; seed < 1120; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const VineModel m = SimVine(seed);
    const PruningPolicy policy;
    auto first = Decide(m, policy);
    auto second = Decide(m, policy);
    ASSERT_TRUE(first.ok() && second.ok()) << first.status() << second.status();
    EXPECT_EQ(CutPlanToJson(first->plan), CutPlanToJson(second->plan));
    EXPECT_EQ(first->notes, second->notes);
    CheckPlanOnVine(m, *first, policy);
    cuts += static_cast<int>(first->plan.cuts.size());
    kept += static_cast<int>(first->plan.keep.size());
  }
  EXPECT_GT(cuts, 20 * 4);   // vines have 8-25 canes: most go
  EXPECT_EQ(kept, 20 * 2);   // every simulated vine has two keepable canes
}

TEST(DecideOnSimulatedVines, HoldsForOtherPoliciesToo) {
  PruningPolicy many;
  many.canes_to_keep = 6;
  many.spurs = 6;
  PruningPolicy spur;
  spur.style = PruningStyle::kSpur;
  spur.canes_to_keep = 0;
  spur.spurs = 8;
  PruningPolicy long_canes;
  long_canes.max_kept_length_m = 1.5;
  long_canes.cut_offset_m = 0.02;
  for (const PruningPolicy& policy : {many, spur, long_canes}) {
    for (uint64_t seed = 1120; seed < 1130; ++seed) {
      SCOPED_TRACE(::testing::Message() << "seed " << seed << " policy "
                                        << PruningPolicyToJson(policy).dump());
      const VineModel m = SimVine(seed);
      auto d = Decide(m, policy);
      ASSERT_TRUE(d.ok()) << d.status();
      CheckPlanOnVine(m, *d, policy);
      if (policy.style == PruningStyle::kSpur) {
        EXPECT_THAT(d->plan.keep, IsEmpty());
      }
    }
  }
}

}  // namespace
}  // namespace vb::decide
