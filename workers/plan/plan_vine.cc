// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/plan_vine.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <cmath>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/plan/cut_order.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {

std::string_view CheckerKindName(CheckerKind kind) {
  switch (kind) {
    case CheckerKind::kPrimitives:
      return "primitives";
    case CheckerKind::kFclPrimitives:
      return "fcl_primitives";
    case CheckerKind::kFclMesh:
      return "fcl_mesh";
  }
  return "primitives";
}

std::unique_ptr<CollisionChecker> MakeChecker(CheckerKind kind, const RobotModel& robot,
                                              const CollisionScene& scene) {
  switch (kind) {
    case CheckerKind::kPrimitives:
      return MakePrimitiveChecker(robot, scene);
    case CheckerKind::kFclPrimitives:
      return MakeFclChecker(robot, scene, FclMode::kPrimitives);
    case CheckerKind::kFclMesh:
      return MakeFclChecker(robot, scene, FclMode::kMesh);
  }
  return MakePrimitiveChecker(robot, scene);
}

absl::Status PlanOptions::Validate() const {
  auto prefixed = [](const char* what, const absl::Status& status) {
    return status.ok() ? status
                       : absl::Status(status.code(), absl::StrCat("options.", what, ": ",
                                                                  status.message()));
  };
  VB_RETURN_IF_ERROR(prefixed("scene", scene.Validate()));
  VB_RETURN_IF_ERROR(prefixed("cut_motion", cut_motion.Validate()));
  VB_RETURN_IF_ERROR(prefixed("margins", margins.Validate()));
  VB_RETURN_IF_ERROR(prefixed("path", path.Validate()));
  if (!home.allFinite()) return absl::InvalidArgumentError("options.home: non-finite joint angle");
  if (!(cut_speed_fraction > 0) || !(cut_speed_fraction <= 1))
    return absl::InvalidArgumentError("options.cut_speed_fraction must be in (0, 1]");
  if (!(sample_dt_s > 0) || !std::isfinite(sample_dt_s))
    return absl::InvalidArgumentError("options.sample_dt_s must be finite and > 0");
  return absl::OkStatus();
}

namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Appends `waypoints` timed from the end of the trajectory so far as one segment.
absl::Status AppendSegment(SegmentKind kind, CutId cut_id, std::span<const Joints> waypoints,
                           const JointLimits& limits, double sample_dt_s, Trajectory* out) {
  const double start_s = out->duration_s;
  VB_ASSIGN_OR_RETURN(const std::vector<TimedJoints> timed,
                      TimeParameterize(waypoints, limits, start_s, sample_dt_s));
  TrajectorySegment segment;
  segment.kind = kind;
  segment.cut_id = cut_id;
  for (const TimedJoints& p : timed) {
    TrajectoryPoint point;
    point.t = p.t;
    for (int j = 0; j < 6; ++j) point.q[j] = p.q[j];
    segment.points.push_back(point);
  }
  if (!segment.points.empty()) out->duration_s = segment.points.back().t;
  out->segments.push_back(std::move(segment));
  return absl::OkStatus();
}

std::string_view PathReason(PathOutcome outcome) {
  switch (outcome) {
    case PathOutcome::kStartInCollision:
    case PathOutcome::kGoalInCollision:
      return "cut_motion_in_collision";
    case PathOutcome::kOutsideLimits:
      return "outside_joint_limits";
    default:
      return "no_path_within_deadline";
  }
}

std::string_view CutMotionReason(CutMotionOutcome outcome) {
  switch (outcome) {
    case CutMotionOutcome::kUnreachable:
      return "unreachable";
    case CutMotionOutcome::kNoCollisionFreeMotion:
      return "no_collision_free_cut_motion";
    case CutMotionOutcome::kDeadline:
      return "no_cut_motion_within_deadline";
    default:
      return "invalid_cut";
  }
}

}  // namespace

absl::StatusOr<PlanResult> PlanVine(const VineModel& model, const CutPlan& plan,
                                    const RobotModel& robot, const PlatformGeometry& platform,
                                    const PlanOptions& options, const Deadline& deadline) {
  const auto start = std::chrono::steady_clock::now();
  VB_RETURN_IF_ERROR(options.Validate());
  VB_RETURN_IF_ERROR(robot.Validate());
  VB_RETURN_IF_ERROR(platform.Validate());
  VB_RETURN_IF_ERROR(plan.ValidateAgainst(model));
  if (!robot.limits.Contains(options.home))
    return absl::InvalidArgumentError("options.home: outside the joint limits");

  PlanResult result;
  PlanStats& stats = result.stats;
  Trajectory& trajectory = result.trajectory;
  trajectory.platform_from_arm_base = robot.platform_from_arm_base;
  trajectory.tool = robot.tool;
  stats.cuts = static_cast<int>(plan.cuts.size());

  auto t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(CollisionScene scene,
                      CollisionScene::Build(model, platform, robot, options.scene));
  {
    auto checker = MakeChecker(options.checker, robot, scene);
    if (!checker->IsFree(options.home))
      return absl::FailedPreconditionError("options.home: the home configuration is in collision");
    stats.checks += checker->checks();
  }
  stats.scene_s = Seconds(t);
  VB_RETURN_IF_ERROR(deadline.Check("plan"));

  // 2. Cut motions.
  t = std::chrono::steady_clock::now();
  const CheckerFactory make_checker = [&](const RobotModel& r, const CollisionScene& s) {
    return MakeChecker(options.checker, r, s);
  };
  std::vector<CutMotion> motions = PlanCutMotions(robot, model, scene, plan.cuts,
                                                  options.cut_motion, deadline, make_checker);
  stats.cut_motions_s = Seconds(t);
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  std::vector<int> planned;  // indices into plan.cuts / motions
  std::unordered_map<int64_t, Cut> made;
  for (size_t i = 0; i < motions.size(); ++i) {
    const CutMotion& m = motions[i];
    const Cut& cut = plan.cuts[i];
    if (m.outcome != CutMotionOutcome::kPlanned) {
      if (m.outcome == CutMotionOutcome::kUnreachable) ++stats.unreachable;
      trajectory.unplanned.push_back({cut.id, std::string(CutMotionReason(m.outcome))});
      continue;
    }
    Cut as_made = cut;
    as_made.point = m.cut_point_in_platform;
    if (m.slid_m > 0)
      stats.notes.push_back(absl::StrCat("cut ", cut.id.value, ": slid ", m.slid_m,
                                         " m outward along cane ", cut.cane_id.value));
    made[cut.id.value] = as_made;
    planned.push_back(static_cast<int>(i));
  }

  // 3. Adaptive margins around the home configuration and every chosen cut motion.
  t = std::chrono::steady_clock::now();
  std::vector<ProtectedMotion> protected_motions;
  protected_motions.push_back({{options.home}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
  for (int i : planned) {
    const Cut& cut = made[plan.cuts[i].id.value];
    protected_motions.push_back({motions[i].path, cut.cane_id, base_from_platform * cut.point,
                                 options.cut_motion.cut_cane_free_radius_m});
  }
  CollisionScene inflated = scene;
  stats.margins = InflateMargins(robot, protected_motions, options.margins, &inflated);
  auto checker = MakeChecker(options.checker, robot, inflated);
  stats.margins_s = Seconds(t);

  // 4. Order: node 0 is home, node k the k-th planned cut (entered at its path's first
  // configuration, left at its last).
  t = std::chrono::steady_clock::now();
  const int n = static_cast<int>(planned.size());
  Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(n + 1, n + 1);
  auto exit_of = [&](int node) -> const Joints& {
    return node == 0 ? options.home : motions[planned[node - 1]].path.back();
  };
  auto entry_of = [&](int node) -> const Joints& {
    return node == 0 ? options.home : motions[planned[node - 1]].path.front();
  };
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (i != j) cost(i, j) = MoveTimeS(exit_of(i), entry_of(j), robot.limits);
  const OrderResult order = OrderCuts(cost, options.return_home);
  std::vector<int> given(n);
  for (int k = 0; k < n; ++k) given[k] = k + 1;
  stats.order_cost_s = order.cost;
  stats.order_exact = order.exact;
  stats.given_order_cost_s = OrderCost(cost, given, options.return_home);
  stats.nearest_neighbour_cost_s = NearestNeighbourOrder(cost, options.return_home).cost;
  stats.ordering_s = Seconds(t);

  // 5. Paths between consecutive cuts. A leg is the transit to a cut and the cut itself.
  t = std::chrono::steady_clock::now();
  struct Leg {
    std::vector<Joints> transit;
    int motion = -1;
  };
  std::vector<Leg> legs;
  PathPlanner planner(*checker, robot.limits, options.path);
  auto plan_path = [&](const Joints& from, const Joints& goal,
                       CutId to) -> std::optional<std::vector<Joints>> {
    PathResult path = planner.Plan(from, goal, deadline);
    stats.paths.push_back({to, path.outcome, path.planning_s, path.checks, path.direct});
    if (path.outcome != PathOutcome::kSolved) return std::nullopt;
    return std::move(path.waypoints);
  };
  auto end_of_legs = [&]() -> const Joints& {
    return legs.empty() ? options.home : motions[legs.back().motion].path.back();
  };
  for (int node : order.order) {
    const int i = planned[node - 1];
    const CutId id = plan.cuts[i].id;
    auto transit = plan_path(end_of_legs(), motions[i].path.front(), id);
    if (!transit) {
      trajectory.unplanned.push_back({id, std::string(PathReason(stats.paths.back().outcome))});
      continue;
    }
    legs.push_back({std::move(*transit), i});
  }
  // Home again; if no path leads home from the last cut, that cut is given up and the arm goes
  // home from the one before it (the arm never ends a vine stranded among the canes).
  std::vector<Joints> home_path;
  while (options.return_home && !legs.empty()) {
    auto path = plan_path(end_of_legs(), options.home, CutId{0});
    if (path) {
      home_path = std::move(*path);
      break;
    }
    const CutId id = plan.cuts[legs.back().motion].id;
    trajectory.unplanned.push_back({id, "no_path_home_within_deadline"});
    stats.notes.push_back(absl::StrCat("cut ", id.value,
                                       ": dropped, no path home from it within the deadline"));
    legs.pop_back();
  }
  stats.paths_s = Seconds(t);

  // 6. Timing: home -> (transit, cut)* -> home, each segment at rest at its ends.
  t = std::chrono::steady_clock::now();
  JointLimits cut_limits = robot.limits;
  cut_limits.max_velocity *= options.cut_speed_fraction;
  cut_limits.max_acceleration *= options.cut_speed_fraction;
  for (const Leg& leg : legs) {
    const Cut& cut = made[plan.cuts[leg.motion].id.value];
    VB_RETURN_IF_ERROR(AppendSegment(SegmentKind::kTransit, CutId{0}, leg.transit, robot.limits,
                                     options.sample_dt_s, &trajectory));
    VB_RETURN_IF_ERROR(AppendSegment(SegmentKind::kCut, cut.id, motions[leg.motion].path,
                                     cut_limits, options.sample_dt_s, &trajectory));
    result.cuts.push_back(cut);
  }
  if (!home_path.empty()) {
    VB_RETURN_IF_ERROR(AppendSegment(SegmentKind::kTransit, CutId{0}, home_path, robot.limits,
                                     options.sample_dt_s, &trajectory));
  }
  stats.timing_s = Seconds(t);
  stats.planned = static_cast<int>(result.cuts.size());
  for (const PathRecord& p : stats.paths) stats.checks += p.checks;
  stats.total_s = Seconds(start);
  std::sort(trajectory.unplanned.begin(), trajectory.unplanned.end(),
            [](const UnplannedCut& a, const UnplannedCut& b) { return a.cut_id.value < b.cut_id.value; });
  return result;
}

int64_t CountTrajectoryCollisions(const Trajectory& trajectory, std::span<const Cut> cuts,
                                  const RobotModel& robot, const CollisionScene& scene,
                                  CheckerKind kind, double max_step_m, double cut_radius_m,
                                  std::vector<int>* bad_segments) {
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  auto transit_checker = MakeChecker(kind, robot, scene);
  int64_t collisions = 0;
  if (bad_segments != nullptr) bad_segments->assign(trajectory.segments.size(), 0);
  for (size_t s = 0; s < trajectory.segments.size(); ++s) {
    const TrajectorySegment& segment = trajectory.segments[s];
    std::unique_ptr<CollisionChecker> cut_checker;
    CollisionChecker* checker = transit_checker.get();
    if (segment.kind == SegmentKind::kCut) {
      auto cut = std::find_if(cuts.begin(), cuts.end(),
                              [&](const Cut& c) { return c.id.value == segment.cut_id.value; });
      if (cut != cuts.end()) {
        cut_checker = MakeChecker(
            kind, robot,
            scene.WithoutCaneNear(cut->cane_id, base_from_platform * cut->point, cut_radius_m));
        checker = cut_checker.get();
      }
    }
    std::vector<Joints> configurations;
    for (size_t p = 0; p < segment.points.size(); ++p) {
      const Joints b = Eigen::Map<const Joints>(segment.points[p].q.data());
      if (p == 0) {
        configurations.push_back(b);
        continue;
      }
      const Joints a = Eigen::Map<const Joints>(segment.points[p - 1].q.data());
      const int steps = MotionSteps(a, b, max_step_m);
      for (int k = 1; k <= steps; ++k) configurations.push_back(a + (b - a) * (double(k) / steps));
    }
    for (size_t c = 0; c < configurations.size(); ++c) {
      if (!checker->IsFree(configurations[c])) {
        ++collisions;
        if (bad_segments != nullptr) ++(*bad_segments)[s];
      }
    }
  }
  return collisions;
}

}  // namespace vb::plan

namespace vb::plan {

Joints DefaultHome() {
  Joints q;
  q << -0.916958, 1.82058, 1.18997, -1.68409, -1.92803, -1.51915;  // provisional
  return q;
}

}  // namespace vb::plan
