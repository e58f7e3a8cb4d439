// SPDX-License-Identifier: Apache-2.0
// Cut motions on simulated vines (tuning seeds 1100-1109, ground truth, default UR5) with the real
// checker: re-checked densely with FCL, and the half-turn twins against sampling both sides. The
// synthetic scenes are in cut_motion_test.cc.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

// Remove-style cuts 0.03 m from the base of every cane at least 0.2 m long, so the test needs no
// decide stage (workers do not depend on each other).
std::vector<Cut> CutsNearCaneBases(const VineModel& model) {
  std::vector<Cut> cuts;
  for (const Cane& cane : model.canes) {
    if (cane.kind != CaneKind::kCane || cane.polyline.Length() < 0.2) continue;
    Cut cut;
    cut.id = CutId(static_cast<int64_t>(cuts.size()) + 1);
    cut.cane_id = cane.id;
    cut.point = cane.polyline.PointAt(0.03);
    cut.direction = cane.polyline.TangentAt(0.03);
    cut.diameter_m = 2 * cane.polyline.RadiusAt(0.03);
    cuts.push_back(cut);
  }
  return cuts;
}

// One simulated stop (vine 0 of `seed`, no neighbours): its ground-truth vine, the collision
// scene for `robot` and cuts near its canes' bases.
struct VineStop {
  VineModel vine;
  CollisionScene scene;
  std::vector<Cut> cuts;
};

VineStop MakeVineStop(uint64_t seed, const RobotModel& robot) {
  sim::VineGeneratorOptions vine_options;
  vine_options.neighbours = false;
  auto generated = sim::GenerateScene(seed, 0, vine_options);
  EXPECT_TRUE(generated.ok()) << generated.status();
  if (!generated.ok()) return {};
  auto scene = CollisionScene::Build(generated->vine, DefaultPlatform(), robot);
  EXPECT_TRUE(scene.ok()) << scene.status();
  if (!scene.ok()) return {};
  std::vector<Cut> cuts = CutsNearCaneBases(generated->vine);
  return {std::move(generated->vine), *std::move(scene), std::move(cuts)};
}

TEST(CutMotion, MotionsOnSimulatedVinesAreFreeWhenRecheckedDenselyWithFcl) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const CutMotionOptions options;
  int cuts = 0, planned = 0;
  for (uint64_t seed = 1100; seed < 1110; ++seed) {
    const VineStop stop = MakeVineStop(seed, robot);
    ASSERT_FALSE(stop.vine.canes.empty()) << "seed " << seed;
    const std::vector<Cut>& vine_cuts = stop.cuts;
    const auto motions =
        PlanCutMotions(robot, stop.vine, stop.scene, vine_cuts, options, Deadline::Infinite());
    ASSERT_EQ(motions.size(), vine_cuts.size());
    cuts += static_cast<int>(vine_cuts.size());
    for (size_t i = 0; i < motions.size(); ++i) {
      const CutMotion& m = motions[i];
      EXPECT_EQ(m.cut_id, vine_cuts[i].id);
      if (m.outcome != CutMotionOutcome::kPlanned) {
        EXPECT_TRUE(m.outcome == CutMotionOutcome::kNoCollisionFreeMotion ||
                    m.outcome == CutMotionOutcome::kUnreachable)
            << m.message;
        continue;
      }
      ++planned;
      EXPECT_LE(m.slid_m, options.max_slide_m + 1e-12);
      // The TCP is on the (slid) cut point, on the cut cane's axis, sweeping across it.
      const Cane& cane = stop.vine.canes[*stop.vine.IndexOf(vine_cuts[i].cane_id)];
      double off_axis = 1;
      const double s = cane.polyline.Project(m.cut_point_in_platform, &off_axis);
      EXPECT_LT(off_axis, 1e-9);
      const Eigen::Isometry3d tcp =
          ForwardKinematics(m.path[m.cut_index]) * robot.tool.flange_from_tcp;
      EXPECT_LT((tcp.translation() - base_from_platform * m.cut_point_in_platform).norm(), 1e-9);
      const Eigen::Vector3d tangent = base_from_platform.linear() * cane.polyline.TangentAt(s);
      EXPECT_NEAR(tcp.linear().col(0).dot(tangent), 0.0, 1e-6);
      // An independent checker (FCL primitives), 1 mm resolution, on the scene the planner was
      // allowed: everything but the cut cane near the cut.
      const CollisionScene allowed =
          stop.scene.WithoutCaneNear(vine_cuts[i].cane_id, base_from_platform * m.cut_point_in_platform,
                                 options.cut_cane_free_radius_m);
      auto fcl = MakeFclChecker(robot, allowed, FclMode::kPrimitives);
      for (size_t k = 1; k < m.path.size(); ++k) {
        EXPECT_TRUE(fcl->IsMotionFree(m.path[k - 1], m.path[k], 0.001))
            << "seed " << seed << " cut " << m.cut_id.value << " step " << k;
      }
    }
  }
  RecordProperty("planned", planned);
  RecordProperty("cuts", cuts);
  std::printf("cut motions on seeds 1100-1109: %d of %d planned\n", planned, cuts);
  ASSERT_GT(cuts, 50);
  EXPECT_GE(planned, cuts / 5);  // measured: see docs/plan.md; a broken planner plans none
}

// a and b are the same motion, or half-turn twins (cut_motion.cc): joints 1-5 equal, joint 6
// equal or turned by the same half turn throughout (within 1e-9), in order or (a sweep's twin)
// reversed.
bool SameOrTwin(const std::vector<Joints>& a, const std::vector<Joints>& b) {
  if (a.size() != b.size() || a.empty()) return false;
  for (bool reversed : {false, true}) {
    const double turn = (reversed ? b.back() : b.front())[5] - a.front()[5];
    if (!(std::abs(turn) < 1e-9 || std::abs(std::abs(turn) - M_PI) < 1e-9)) continue;
    bool same = true;
    for (size_t i = 0; i < a.size() && same; ++i) {
      const Joints& y = b[reversed ? b.size() - 1 - i : i];
      same = (a[i].head<5>() - y.head<5>()).cwiseAbs().maxCoeff() < 1e-9 &&
             std::abs(y[5] - a[i][5] - turn) < 1e-9;
    }
    if (same) return true;
  }
  return false;
}

TEST(CutMotion, SharedTwinsGiveTheMotionsOfBothSidesOnSimulatedVines) {
  // share_rolled_twins samples one side of the cane and takes the other side's motions as the
  // half-turn twins of its own: the outcomes, slides and clearances must be those of sampling
  // both sides, and every motion the same up to which twin of a pair is listed.
  CutMotionOptions secateur_options;  // as PlanOptions: tilts and rolls
  secateur_options.max_tilt_rad = 30.0 * M_PI / 180.0;
  secateur_options.tilt_steps = 1;
  secateur_options.max_roll_rad = 45.0 * M_PI / 180.0;
  secateur_options.roll_steps = 2;
  // Room for every distinct motion: a list cut short may end on either motion of a tie.
  secateur_options.alternatives = 40;
  CutMotionOptions mill_end_options;
  mill_end_options.alternatives = 40;
  const std::pair<ToolGeometry, CutMotionOptions> setups[] = {
      {SecateurTool(), secateur_options}, {MillEndTool(), mill_end_options}};
  for (const auto& [tool, options] : setups) {
    const RobotModel robot = DefaultUr5(tool);
    CutMotionOptions both_sides = options;
    both_sides.share_rolled_twins = false;
    int planned = 0, alternatives = 0;
    for (uint64_t seed = 1100; seed < 1103; ++seed) {
      const VineStop stop = MakeVineStop(seed, robot);
      ASSERT_FALSE(stop.vine.canes.empty()) << "seed " << seed;
      const std::vector<Cut>& cuts = stop.cuts;
      const auto shared =
          PlanCutMotions(robot, stop.vine, stop.scene, cuts, options, Deadline::Infinite());
      const auto sampled =
          PlanCutMotions(robot, stop.vine, stop.scene, cuts, both_sides, Deadline::Infinite());
      ASSERT_EQ(shared.size(), sampled.size());
      for (size_t i = 0; i < shared.size(); ++i) {
        const CutMotion& m = shared[i];
        const CutMotion& ref = sampled[i];
        const std::string where =
            absl::StrCat(tool.name, " seed ", seed, " cut ", m.cut_id.value);
        ASSERT_EQ(m.outcome, ref.outcome) << where << ": " << m.message << " / " << ref.message;
        if (m.outcome != CutMotionOutcome::kPlanned) continue;
        ++planned;
        EXPECT_EQ(m.slid_m, ref.slid_m) << where;
        EXPECT_EQ(m.cut_index, ref.cut_index) << where;
        EXPECT_NEAR(m.clearance_m, ref.clearance_m, 1e-9) << where;
        ASSERT_EQ(m.alternatives.size(), ref.alternatives.size()) << where;
        // Motions that tie on clearance (twins; with the axisymmetric mill end also two arms
        // reaching the same tool pose, equal to ~1e-14 m) are listed in either order.
        auto listed = [&](const std::vector<Joints>& a) {
          return SameOrTwin(a, ref.path) ||
                 std::any_of(ref.alternatives.begin(), ref.alternatives.end(),
                             [&](const std::vector<Joints>& b) { return SameOrTwin(a, b); });
        };
        EXPECT_TRUE(listed(m.path)) << where;
        // The IK takes every joint nearest 0 at the cut, a twin's joint 6 too (not a turn off).
        EXPECT_LE(std::abs(m.path[m.cut_index][5]), M_PI + 1e-9) << where;
        for (const std::vector<Joints>& a : m.alternatives) {
          ++alternatives;
          EXPECT_TRUE(listed(a)) << where;
          EXPECT_LE(std::abs(a[m.cut_index][5]), M_PI + 1e-9) << where;
        }
        // The twin really puts the TCP on the cut: forward kinematics of the listed path.
        const Eigen::Isometry3d tcp =
            ForwardKinematics(m.path[m.cut_index]) * robot.tool.flange_from_tcp;
        EXPECT_LT((tcp.translation() - robot.platform_from_arm_base.inverse() *
                                           m.cut_point_in_platform).norm(),
                  1e-9)
            << where;
      }
    }
    EXPECT_GT(planned, 5) << tool.name;  // a broken planner plans none
    EXPECT_GT(alternatives, planned) << tool.name;
  }
}

}  // namespace
}  // namespace vb::plan
