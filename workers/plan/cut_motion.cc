// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/cut_motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "workers/plan/flange_bodies.h"
#include "workers/plan/cut_stroke.h"
#include "workers/plan/motion_choice.h"
#include "workers/plan/primitive_checker.h"

namespace vb::plan {

absl::Status CutMotionOptions::Validate() const {
  if (orientations < 1) return absl::InvalidArgumentError("options.orientations: must be >= 1");
  if (approach_sides < 1 || approach_sides > 2) {
    return absl::InvalidArgumentError("options.approach_sides: must be 1 or 2");
  }
  if (tilt_steps < 0) return absl::InvalidArgumentError("options.tilt_steps: must be >= 0");
  if (roll_steps < 0) return absl::InvalidArgumentError("options.roll_steps: must be >= 0");
  if (alternatives < 0) return absl::InvalidArgumentError("options.alternatives: must be >= 0");
  if (!(max_tilt_rad >= 0 && max_tilt_rad < M_PI / 2)) {
    return absl::InvalidArgumentError("options.max_tilt_rad: must be in [0, pi/2)");
  }
  if (!(max_roll_rad >= 0 && max_roll_rad < M_PI / 2)) {
    return absl::InvalidArgumentError("options.max_roll_rad: must be in [0, pi/2)");
  }
  const std::pair<double, const char*> positive[] = {
      {sweep_m, "sweep_m"},
      {approach_m, "approach_m"},
      {cartesian_step_m, "cartesian_step_m"},
      {max_joint_jump_rad, "max_joint_jump_rad"},
      {cut_cane_free_radius_m, "cut_cane_free_radius_m"},
      {max_step_m, "max_step_m"}};
  for (const auto& [value, name] : positive) {
    if (!std::isfinite(value) || value <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("options.", name, ": must be finite and > 0, is ", value));
    }
  }
  if (!std::isfinite(min_clearance_m) || min_clearance_m < 0) {
    return absl::InvalidArgumentError("options.min_clearance_m: must be finite and >= 0");
  }
  if (!std::isfinite(max_slide_m) || max_slide_m < 0) {
    return absl::InvalidArgumentError("options.max_slide_m: must be finite and >= 0");
  }
  if (max_slide_m > 0 && !(std::isfinite(slide_step_m) && slide_step_m > 0)) {
    return absl::InvalidArgumentError("options.slide_step_m: must be finite and > 0");
  }
  return absl::OkStatus();
}

std::string_view CutMotionOutcomeName(CutMotionOutcome outcome) {
  switch (outcome) {
    case CutMotionOutcome::kPlanned:
      return "planned";
    case CutMotionOutcome::kUnreachable:
      return "unreachable";
    case CutMotionOutcome::kNoCollisionFreeMotion:
      return "no_collision_free_cut_motion";
    case CutMotionOutcome::kInvalidInput:
      return "invalid_input";
    case CutMotionOutcome::kDeadline:
      return "deadline";
  }
  return "invalid_input";
}

std::vector<Eigen::Vector3d> StrokeWaypoints(CutStroke stroke, const CutMotionOptions& options,
                                             int* cut_index) {
  std::vector<Eigen::Vector3d> points;
  if (stroke == CutStroke::kSweep) {
    // Symmetric about the cut so that the cut point itself is a waypoint.
    const double half = 0.5 * options.sweep_m;
    const int n = std::max(1, static_cast<int>(std::ceil(half / options.cartesian_step_m)));
    for (int k = -n; k <= n; ++k) points.push_back(Eigen::Vector3d(half * k / n, 0, 0));
    *cut_index = n;
  } else {
    const int n =
        std::max(1, static_cast<int>(std::ceil(options.approach_m / options.cartesian_step_m)));
    for (int k = 0; k <= n; ++k) {
      points.push_back(Eigen::Vector3d(0, 0, -options.approach_m * (n - k) / n));
    }
    for (int k = n - 1; k >= 0; --k) points.push_back(points[k]);
    *cut_index = n;
  }
  return points;
}

std::vector<Eigen::Isometry3d> SampleCutPoses(const Eigen::Vector3d& p, const Eigen::Vector3d& d,
                                              const CutMotionOptions& options) {
  // theta = 0: the tool axis points from the arm base toward the cane, the natural reach.
  Eigen::Vector3d toward_base = -p - (-p).dot(d) * d;
  if (toward_base.norm() < 1e-6) toward_base = d.unitOrthogonal();
  const Eigen::Vector3d e1 = toward_base.normalized();
  const Eigen::Vector3d e2 = d.cross(e1);
  std::vector<Eigen::Isometry3d> poses;
  // Tilts (and rolls) 0, +t, -t, +2t, -2t, ... up to their maximum: perpendicular cuts first.
  auto signed_steps = [](double max_rad, int steps) {
    std::vector<double> out = {0.0};
    for (int k = 1; k <= steps; ++k) {
      out.push_back(max_rad * k / steps);
      out.push_back(-max_rad * k / steps);
    }
    return out;
  };
  const std::vector<double> tilts = signed_steps(options.max_tilt_rad, options.tilt_steps);
  const std::vector<double> rolls = signed_steps(options.max_roll_rad, options.roll_steps);
  // The axes about the cane, computed once (sampling is called per slide).
  std::vector<Eigen::Vector3d> z_perpendiculars;
  for (int i = 0; i < options.orientations; ++i) {
    const double theta = 2.0 * M_PI * i / options.orientations;
    z_perpendiculars.push_back(-(std::cos(theta) * e1 + std::sin(theta) * e2));
  }
  poses.reserve(rolls.size() * tilts.size() * z_perpendiculars.size() * options.approach_sides);
  for (double roll : rolls) {
    const double cos_roll = std::cos(roll), sin_roll = std::sin(roll);
    for (double tilt : tilts) {
      const double cos_tilt = std::cos(tilt), sin_tilt = std::sin(tilt);
      for (const Eigen::Vector3d& z_perpendicular : z_perpendiculars) {
        for (int side = 0; side < options.approach_sides; ++side) {
          const Eigen::Vector3d y_along = side == 0 ? d : Eigen::Vector3d(-d);
          // Rotation by `tilt` about x = y cross z: x stays across the cane.
          const Eigen::Vector3d y_tilted = cos_tilt * y_along + sin_tilt * z_perpendicular;
          const Eigen::Vector3d z = -sin_tilt * y_along + cos_tilt * z_perpendicular;
          const Eigen::Vector3d x_tilted = y_tilted.cross(z);
          // Then by `roll` about z: the jaws' plane turns about the tool axis.
          Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
          pose.linear().col(0) = cos_roll * x_tilted + sin_roll * y_tilted;
          pose.linear().col(1) = -sin_roll * x_tilted + cos_roll * y_tilted;
          pose.linear().col(2) = z;
          pose.translation() = p;
          poses.push_back(pose);
        }
      }
    }
  }
  return poses;
}

namespace {

using stroke::Candidate;
using stroke::EvaluatePath;
using stroke::FollowStroke;
using stroke::IsMirrored;
using stroke::MakeTwinMap;
using stroke::StrokeResult;
using stroke::TwinMap;
using stroke::TwinPath;

// Same obstacles in the same order (so a checker built on one serves the other).
bool SameObstacles(const CollisionScene& a, const CollisionScene& b) {
  if (a.obstacles.size() != b.obstacles.size()) return false;
  for (size_t i = 0; i < a.obstacles.size(); ++i) {
    const Obstacle& x = a.obstacles[i];
    const Obstacle& y = b.obstacles[i];
    if (x.kind != y.kind || x.owner_id != y.owner_id || x.capsule.a != y.capsule.a ||
        x.capsule.b != y.capsule.b || x.capsule.radius != y.capsule.radius ||
        x.margin_m != y.margin_m) {
      return false;
    }
  }
  return true;
}

// A stroke whose configurations are all free, with its cut configuration's clearance (the bound
// it is ranked by) and its group: a stroke and its half-turn twin share one.
struct FreeStroke {
  double cut_clearance;
  std::vector<Joints> path;
  int group;
};

// Cut configurations closer than this in every joint are one choice, not two.
constexpr double kDistinctRad = 0.5;

CutMotion Fail(CutMotion motion, CutMotionOutcome outcome, std::string message) {
  motion.outcome = outcome;
  motion.message = std::move(message);
  motion.path.clear();
  motion.alternatives.clear();
  return motion;
}

// One checker on the whole scene for every cut of a PlanCutMotions call, when the factory makes
// primitive checkers: each slide leaves out the cut cane near its cut point with
// PrimitiveChecker::Exclude, which answers as a checker built on scene.WithoutCaneNear would
// (primitive_checker.h), instead of building one per slide. Built on first use.
struct SharedChecker {
  bool tried = false;
  std::unique_ptr<CollisionChecker> checker;
  PrimitiveChecker* primitive = nullptr;  // checker, when it is one
};

CutMotion PlanOne(const RobotModel& robot, const VineModel& model, const CollisionScene& scene,
                  const Cut& cut, const CutMotionOptions& options, const Deadline& deadline,
                  const CheckerFactory& make_checker, SharedChecker& shared) {
  CutMotion motion;
  motion.cut_id = cut.id;
  motion.cut_point_in_platform = cut.point;
  const std::string what = absl::StrCat("cut ", cut.id.value);
  if (!cut.point.allFinite() || !cut.direction.allFinite() ||
      std::abs(cut.direction.norm() - 1.0) > 1e-6) {
    return Fail(motion, CutMotionOutcome::kInvalidInput,
                what + ": point or direction not finite, or direction not unit");
  }
  const std::optional<size_t> cane_index = model.IndexOf(cut.cane_id);
  if (!cane_index.has_value()) {
    return Fail(motion, CutMotionOutcome::kInvalidInput,
                absl::StrCat(what, ": cane ", cut.cane_id.value, " is not in the model"));
  }
  const Polyline3& cane = model.canes[*cane_index].polyline;
  const double s0 = cane.Project(cut.point);
  // A cut is made at most up to the cane's tip, and short of the base of any child beyond the
  // given cut: that child falls with the cut as given (its own wood has no cut), and a cut slid
  // past its base would leave it on the vine.
  double slide_end_s = cane.Length();
  // (PlanVine never asks for a cut of the trunk, "cut_on_the_trunk"; called directly, the trunk's
  // children are not taken as limits.)
  const bool trunk = model.canes[*cane_index].kind == CaneKind::kTrunk;
  for (CaneId child : trunk ? std::vector<CaneId>{} : model.ChildrenOf(cut.cane_id)) {
    const std::optional<size_t> c = model.IndexOf(child);
    if (!c.has_value() || model.canes[*c].polyline.points.empty()) continue;
    const double at = cane.Project(model.canes[*c].polyline.points.front());
    if (at > s0) slide_end_s = std::min(slide_end_s, at);
  }
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Isometry3d tcp_from_flange = robot.tool.flange_from_tcp.inverse();
  int cut_index = 0;
  const std::vector<Eigen::Vector3d> waypoints =
      StrokeWaypoints(StrokeOf(robot.tool), options, &cut_index);
  const bool mirrored = IsMirrored(waypoints, cut_index);
  const TwinMap twins = MakeTwinMap(robot, options, waypoints);
  double stroke_travel_m = 0;  // farthest stroke waypoint from the cut
  for (const Eigen::Vector3d& w : waypoints) stroke_travel_m = std::max(stroke_travel_m, w.norm());
  const int slides = options.max_slide_m > 0
                         ? static_cast<int>(options.max_slide_m / options.slide_step_m + 1e-9)
                         : 0;

  FlangeBodies flange_bodies(robot);
  // A secateur's cane sits in the throat between the open jaws: no part of the tool may touch
  // the cut cane there either (only the closing blades cut it). The mill end's bit cuts through
  // it, so there the cut cane near the cut is free.
  const bool in_throat = StrokeOf(robot.tool) == CutStroke::kApproachCloseRetract;
  FlangeBodies cut_cane_bodies(robot);
  // Rolled poses (oblique to the jaws' plane) only where no unrolled pose gives a motion at the
  // same slide: cuts stay as square as they can, and a cut that rolls need not slide.
  const int unrolled_poses = options.orientations * options.approach_sides *
                             (1 + 2 * options.tilt_steps);
  const int stages = options.roll_steps > 0 && options.max_roll_rad > 0 ? 2 : 1;
  std::unique_ptr<CollisionChecker> checker;
  CollisionScene checker_scene;  // the scene `checker` was built on
  bool reachable = false;
  int free_at_cut = 0, strokes_followed = 0;  // over all slides, for the message
  // Strokes followed includes those stopped by a collision (IK did not fail first).
  // Per slide: the scene without the cut cane near the cut, the flange bodies' obstacles and the
  // sampled poses, shared by its unrolled and rolled stages.
  CollisionScene local;
  std::vector<int> local_excluded;  // indices into scene.obstacles that `local` leaves out
  std::vector<Eigen::Isometry3d> slide_poses;
  Eigen::Vector3d point = cut.point;
  for (int step = 0; step < (slides + 1) * stages; ++step) {
    const int k = step / stages, stage = step % stages;
    if (stage == 0) {
      Eigen::Vector3d direction = cut.direction;
      point = cut.point;
      if (k > 0) {
        const double s = s0 + k * options.slide_step_m;
        if (s > cane.Length()) break;  // slid off the tip
        if (s >= slide_end_s) break;    // the next child would stay on the vine
        point = cane.PointAt(s);
        direction = cane.TangentAt(s);
      }
      const Eigen::Vector3d point_in_base = base_from_platform * point;
      const Eigen::Vector3d direction_in_base = base_from_platform.linear() * direction;
      // Building a checker costs more than the checks at one slide. It is built only when some
      // cut pose survives the flange bodies' test, and consecutive slides often free the same
      // capsules of the cut cane: an unchanged scene keeps its checker.
      local = scene.WithoutCaneNear(cut.cane_id, point_in_base, options.cut_cane_free_radius_m);
      // The same obstacles by index, for the shared checker.
      local_excluded =
          scene.CaneNearIndices(cut.cane_id, point_in_base, options.cut_cane_free_radius_m);
      flange_bodies.Select(local, point_in_base, stroke_travel_m);
      if (in_throat) {
        CollisionScene cut_cane;  // the capsules of the cut cane that `local` leaves out
        for (const int i : local_excluded) cut_cane.obstacles.push_back(scene.obstacles[i]);
        cut_cane_bodies.Select(cut_cane, point_in_base, stroke_travel_m);
      }
      slide_poses = SampleCutPoses(point_in_base, direction_in_base, options);
    }
    // Every IK solution at every sampled pose of this stage, checked in one batch (AreFree checks
    // several configurations at once), in sampling order.
    std::vector<Candidate> solutions;
    std::span<const Eigen::Isometry3d> poses(slide_poses);
    if (stages == 2) {
      if (stage == 0) poses = poses.first(unrolled_poses);
      else poses = poses.subspan(unrolled_poses);
    }
    for (int pose_index = 0; pose_index < static_cast<int>(poses.size()); ++pose_index) {
      // Sides alternate (sampling order), and stage offsets are whole sets of sides.
      if (twins.on && pose_index % 2 == 1) continue;  // the other side: a twin of the first's
      const Eigen::Isometry3d& pose = poses[pose_index];
      if (deadline.Expired()) return Fail(motion, CutMotionOutcome::kDeadline, what + ": deadline");
      const Eigen::Isometry3d base_from_flange = pose * tcp_from_flange;
      // Reachability still needs the IK of a blocked pose, but only until one pose is reachable.
      const bool blocked = flange_bodies.Collides(base_from_flange, false) ||
                           (in_throat && cut_cane_bodies.Collides(base_from_flange, false));
      if (blocked && reachable) continue;
      const IkSolutions ik = InverseKinematics(base_from_flange, robot.limits);
      reachable = reachable || ik.count > 0;
      if (blocked) continue;
      for (int i = 0; i < ik.count; ++i)
        solutions.push_back({ik.q[i], 0.0, pose, pose_index, ik.branch[i]});
    }
    if (solutions.empty()) continue;
    if (!shared.tried) {
      shared.tried = true;
      shared.checker = make_checker(robot, scene);
      shared.primitive = dynamic_cast<PrimitiveChecker*>(shared.checker.get());
    }
    CollisionChecker* active = nullptr;
    PrimitiveChecker* active_primitive = nullptr;  // `active`, when it is the shared one
    if (shared.primitive != nullptr &&
        local.obstacles.size() + local_excluded.size() == scene.obstacles.size()) {
      shared.primitive->Exclude(local_excluded);
      active = active_primitive = shared.primitive;
    } else {
      if (checker == nullptr || !SameObstacles(local, checker_scene)) {
        checker = make_checker(robot, local);
        checker_scene = local;
      }
      active = checker.get();
    }
    std::vector<Joints> qs;
    qs.reserve(solutions.size());
    for (const Candidate& c : solutions) qs.push_back(c.q);
    std::unique_ptr<bool[]> free(new bool[qs.size()]);
    active->AreFree(qs, std::span<bool>(free.get(), qs.size()));
    std::vector<Candidate> candidates;
    for (size_t i = 0; i < solutions.size(); ++i) {
      if (free[i]) candidates.push_back(solutions[i]);
    }
    free_at_cut += static_cast<int>(candidates.size()) * (twins.on ? 2 : 1);
    // Boolean checks first, exact clearance only for strokes that are free: in clutter most
    // strokes collide, and Clearance costs several IsFree. A path's clearance is at most its cut
    // configuration's, which bounds the search once enough paths are found. The best
    // 1 + options.alternatives paths whose cut configurations differ are kept: a motion that is
    // free may still be out of the paths' reach (an arm threaded behind the wires), and the
    // planner then tries the next.
    const size_t keep = 1 + static_cast<size_t>(options.alternatives);
    std::vector<std::pair<double, std::vector<Joints>>> found;  // by decreasing clearance
    auto bar = [&] {
      return found.size() < keep ? -std::numeric_limits<double>::infinity() : found.back().first;
    };
    // Free strokes are evaluated by decreasing clearance of their cut configuration (the bound
    // on their path's clearance), so the bar rises early and the rest stop at one comparison.
    std::vector<FreeStroke> free_strokes;
    // Per original stroke: EvaluatePath's result once evaluated (shared with its twin).
    std::vector<std::optional<std::optional<double>>> evaluated;
    std::vector<Joints> path, twin_path;
    // The stroke's TCP poses are fixed by the cut pose too: where a flange body collides along
    // it, no IK branch can follow the stroke (decided once per pose, for all its branches).
    // Such strokes count as followed in the message, whether or not IK would have failed first.
    std::vector<signed char> stroke_blocked(poses.size(), -1);  // -1: not yet tested
    auto blocked = [&](const Candidate& c) {
      signed char& b = stroke_blocked[c.pose];
      if (b < 0) {
        b = 0;
        // A mirrored stroke's retract repeats its approach poses: test them once.
        const size_t end = mirrored ? static_cast<size_t>(cut_index) : waypoints.size();
        for (size_t i = 0; i < end && !b; ++i) {
          if (static_cast<int>(i) == cut_index) continue;
          Eigen::Isometry3d base_from_tcp = c.base_from_tcp;
          base_from_tcp.translation() += c.base_from_tcp.linear() * waypoints[i];
          b = flange_bodies.Collides(base_from_tcp * tcp_from_flange, true) ||
              (in_throat && cut_cane_bodies.Collides(base_from_tcp * tcp_from_flange, true));
        }
      }
      return b == 1;
    };
    const int per_candidate = twins.on ? 2 : 1;  // strokes a candidate stands for
    for (Candidate& candidate : candidates) {
      if (blocked(candidate)) {
        strokes_followed += per_candidate;
        continue;
      }
      if (deadline.Expired()) return Fail(motion, CutMotionOutcome::kDeadline, what + ": deadline");
      const StrokeResult stroke =
          FollowStroke(candidate, waypoints, cut_index, mirrored, tcp_from_flange, robot.limits,
                       options.max_joint_jump_rad, *active, &path);
      if (stroke == StrokeResult::kNoIk) continue;
      if (stroke == StrokeResult::kCollides) {
        strokes_followed += per_candidate;
        continue;
      }
      const bool has_twin = twins.on && TwinPath(twins, path, cut_index, robot.limits, &twin_path);
      strokes_followed += has_twin ? 2 : 1;
      candidate.clearance_m = active->ClearanceAbove(candidate.q, options.min_clearance_m,
                                                      std::numeric_limits<double>::infinity());
      // Exact (double): a batched float check may pass a configuration within ~1e-5 m of contact.
      if (!(candidate.clearance_m > options.min_clearance_m)) continue;
      const int group = static_cast<int>(evaluated.size());
      evaluated.emplace_back();
      // A stroke and its twin tie on clearance (sampling both sides, rounding broke the tie).
      // The twin goes first: the plan depends on that choice through its alternatives and
      // paths (tuning seeds 1110-1199: 0.978 of reachable cuts planned with the twin first,
      // 0.969 with the original first, 0.974 when rounding decided; docs/plan.md).
      if (has_twin) free_strokes.push_back({candidate.clearance_m, twin_path, group});
      free_strokes.push_back({candidate.clearance_m, path, group});
    }
    std::stable_sort(free_strokes.begin(), free_strokes.end(),
                     [](const FreeStroke& a, const FreeStroke& b) {
                       return a.cut_clearance > b.cut_clearance;
                     });
    for (FreeStroke& stroke : free_strokes) {
      const double cut_clearance = stroke.cut_clearance;
      std::vector<Joints>& path = stroke.path;
      if (deadline.Expired()) return Fail(motion, CutMotionOutcome::kDeadline, what + ": deadline");
      if (cut_clearance <= bar()) break;  // sorted: no later stroke can beat the bar either
      const double must_beat = std::max(bar(), options.min_clearance_m);
      std::optional<double> clearance;
      // A twin's path has its original's clearance and motions: evaluated once. The bar only
      // rises, so a result that was below it stays below it.
      std::optional<std::optional<double>>& known = evaluated[stroke.group];
      if (known.has_value()) {
        clearance = known->has_value() && **known > must_beat ? *known : std::nullopt;
      } else {
        clearance = EvaluatePath(*active, active_primitive, path, cut_index, mirrored, cut_clearance, must_beat,
                                 options.max_step_m);
        known = clearance;
      }
      if (!clearance.has_value()) continue;
      // A path whose cut configuration is near a better one adds no choice: keep the better.
      const Joints& q = path[cut_index];
      auto similar = std::find_if(found.begin(), found.end(), [&](const auto& f) {
        return (f.second[cut_index] - q).cwiseAbs().maxCoeff() < kDistinctRad;
      });
      if (similar != found.end()) {
        if (similar->first >= *clearance) continue;
        found.erase(similar);
      }
      found.insert(std::upper_bound(found.begin(), found.end(), *clearance,
                                    [](double c, const auto& f) { return c > f.first; }),
                   {*clearance, path});
      if (found.size() > keep) found.pop_back();
    }
    if (!found.empty()) {
      motion.outcome = CutMotionOutcome::kPlanned;
      motion.path = std::move(found.front().second);
      for (size_t i = 1; i < found.size(); ++i)
        motion.alternatives.push_back(std::move(found[i].second));
      motion.cut_index = cut_index;
      motion.clearance_m = found.front().first;
      motion.slid_m = k * options.slide_step_m;
      motion.cut_point_in_platform = point;
      motion.message = absl::StrCat(what, ": planned, clearance ", motion.clearance_m,
                                    " m, slid ", motion.slid_m, " m");
      return motion;
    }
  }
  if (!reachable) {
    return Fail(motion, CutMotionOutcome::kUnreachable,
                absl::StrCat(what, ": no sampled tool pose is reachable within the joint limits"));
  }
  return Fail(motion, CutMotionOutcome::kNoCollisionFreeMotion,
              absl::StrCat(what, ": no collision-free cut motion within ", options.max_slide_m,
                           " m of sliding (", free_at_cut, " collision-free cut configurations, ",
                           strokes_followed, " strokes within the joint limits, none free)"));
}

}  // namespace

std::vector<CutMotion> PlanCutMotions(const RobotModel& robot, const VineModel& model,
                                      const CollisionScene& scene, std::span<const Cut> cuts,
                                      const CutMotionOptions& options, const Deadline& deadline,
                                      const CheckerFactory& make_checker) {
  std::vector<CutMotion> motions;
  SharedChecker shared;
  absl::Status status = options.Validate();
  if (status.ok()) status = robot.Validate();
  for (const Cut& cut : cuts) {
    if (status.ok() && deadline.Expired()) {
      CutMotion motion;
      motion.cut_id = cut.id;
      motion.cut_point_in_platform = cut.point;
      motions.push_back(Fail(motion, CutMotionOutcome::kDeadline,
                             absl::StrCat("cut ", cut.id.value, ": deadline")));
      continue;
    }
    if (!status.ok()) {
      CutMotion motion;
      motion.cut_id = cut.id;
      motion.cut_point_in_platform = cut.point;
      motions.push_back(
          Fail(motion, CutMotionOutcome::kInvalidInput, std::string(status.message())));
      continue;
    }
    motions.push_back(PlanOne(robot, model, scene, cut, options, deadline, make_checker, shared));
  }
  return motions;
}

std::vector<CutMotion> PlanCutMotions(const RobotModel& robot, const VineModel& model,
                                      const CollisionScene& scene, std::span<const Cut> cuts,
                                      const CutMotionOptions& options, const Deadline& deadline) {
  return PlanCutMotions(robot, model, scene, cuts, options, deadline, MakePrimitiveChecker);
}

}  // namespace vb::plan
