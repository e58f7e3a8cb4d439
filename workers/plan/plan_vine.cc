// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/plan_vine.h"

#include <algorithm>
#include <chrono>
#include <deque>
#include <numeric>
#include <optional>
#include <cmath>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/plan/blend.h"
#include "workers/plan/cut_order.h"
#include "workers/plan/fallen_wood.h"
#include "workers/plan/leg_timing.h"
#include "workers/plan/motion_choice.h"
#include "workers/plan/planning.h"
#include "workers/plan/stub_check.h"
#include "workers/plan/time_parameterization.h"
#include "workers/plan/tool.h"

namespace vb::plan {

namespace {

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

// The copy of `path` shifted by whole turns in the joints whose limits allow it that the arm can
// reach from `from` without folding onto itself: IK gives each joint its turn nearest zero, but
// the wrist links cannot pass through the forearm, so a wrist angle one turn away is often on the
// wrong side of that fold, and only its other turn is connected to `from`. Shifts are tried by
// increasing joint travel; the first whose straight joint segment from `from` is free of
// self-collision (`self_checker` has an empty scene) wins, else the path is returned unshifted.
std::vector<Joints> ShiftedForReach(const std::vector<Joints>& path, const Joints& from,
                                    const JointLimits& limits, CollisionChecker& self_checker,
                                    double max_step_m) {
  Joints lo = path.front(), hi = path.front();
  for (const Joints& q : path) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  std::vector<std::pair<double, Joints>> shifts;  // (travel, shift)
  std::vector<Joints> partial = {Joints::Zero()};
  for (int j = 0; j < 6; ++j) {
    std::vector<Joints> next;
    for (const Joints& shift : partial) {
      for (int k = -1; k <= 1; ++k) {
        const double d = 2.0 * M_PI * k;
        if (k != 0 && (lo[j] + d < limits.lower[j] || hi[j] + d > limits.upper[j])) continue;
        Joints s = shift;
        s[j] = d;
        next.push_back(s);
      }
    }
    partial = std::move(next);
  }
  for (const Joints& shift : partial)
    shifts.push_back({(path.front() + shift - from).cwiseAbs().sum(), shift});
  std::sort(shifts.begin(), shifts.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 0; i < shifts.size() && i < 8; ++i) {
    if (!self_checker.IsMotionFree(from, path.front() + shifts[i].second, max_step_m)) continue;
    std::vector<Joints> shifted = path;
    for (Joints& q : shifted) q += shifts[i].second;
    return shifted;
  }
  return path;
}

// Drops the motions of `motion` (its path and alternatives) that touch `scene` along their
// configurations, checked as PlanCutMotions checks them (stub_check.h: twins and mirrored halves
// once); the first free alternative replaces a path that touches. False (and `motion` unchanged)
// if every one does.
bool KeepMotionsFreeOf(const CollisionScene& scene, const PlanOptions& options,
                       const RobotModel& robot, CutMotion* motion) {
  const std::unique_ptr<CollisionChecker> checker = MakeChecker(options.checker, robot, scene);
  // Twins are exact for capsule checkers only (as in PlanCutMotions).
  const bool share_twins = options.checker != CheckerKind::kFclMesh &&
                           options.cut_motion.share_rolled_twins && RollSymmetric(robot);
  return KeepMotionsFreeOfStubs(*checker, options.cut_motion.max_step_m, share_twins, motion);
}

// One pass on the vine as `model` leaves it: cut motions for `pending` (indices into plan.cuts),
// margins, order, paths. Appends legs; returns the cuts to try again on the vine after them.
absl::StatusOr<std::vector<int>> PlanPass(const VineModel& model, const std::vector<int>& pending,
                                          bool last_pass, Planning& p) {
  PlanStats& stats = p.result.stats;
  const PlanOptions& options = p.options;
  auto t = std::chrono::steady_clock::now();
  CollisionScene scene;
  if (p.uncut_scene) {  // the first pass: the vine PlanVine built the scene of
    scene = std::move(*p.uncut_scene);
    p.uncut_scene.reset();
  } else {
    VB_ASSIGN_OR_RETURN(scene, CollisionScene::Build(model, p.platform, p.robot, options.scene));
  }
  stats.scene_s += Seconds(t);

  // Cut motions.
  t = std::chrono::steady_clock::now();
  std::vector<Cut> cuts;
  std::vector<int> pending_here;
  for (int i : pending) {
    const std::optional<size_t> on = model.IndexOf(p.plan.cuts[i].cane_id);
    if (!on) {
      p.Unplanned(p.plan.cuts[i].id, "cane_fell_with_an_earlier_cut");
      continue;
    }
    // The trunk is never cut (decide never asks): its fall (core/fallen_wood.h) would drop the
    // head and the canes on it, which the slide limits of cut_motion.cc do not model.
    if (model.canes[*on].kind == CaneKind::kTrunk) {
      p.Unplanned(p.plan.cuts[i].id, "cut_on_the_trunk");
      continue;
    }
    cuts.push_back(p.plan.cuts[i]);
    pending_here.push_back(i);
  }
  const CheckerFactory make_checker = [&](const RobotModel& r, const CollisionScene& s) {
    return MakeChecker(options.checker, r, s);
  };
  // Half-turn twins are exact for capsule models only: a tessellated mesh is not symmetric under
  // the roll (fcl_checker.cc), so with FCL meshes both sides are sampled and checked.
  CutMotionOptions cut_options = options.cut_motion;
  if (options.checker == CheckerKind::kFclMesh) cut_options.share_rolled_twins = false;
  std::vector<CutMotion> motions = PlanCutMotions(p.robot, model, scene, cuts, cut_options,
                                                  p.deadline, make_checker);
  if (options.last_resort_max_slide_m > options.cut_motion.max_slide_m &&
      std::none_of(motions.begin(), motions.end(), [](const CutMotion& m) {
        return m.outcome == CutMotionOutcome::kPlanned;
      })) {
    // No cut of this pass has a motion, so no wood falls and the passes end: the blocked cuts
    // (canes at the head that block each other) are searched once more, sliding further.
    const auto last_resort_start = std::chrono::steady_clock::now();
    p.last_resort_used = true;
    CutMotionOptions wider = cut_options;
    wider.max_slide_m = options.last_resort_max_slide_m;
    std::vector<Cut> blocked;
    std::vector<size_t> blocked_at;
    for (size_t k = 0; k < motions.size(); ++k) {
      if (motions[k].outcome != CutMotionOutcome::kNoCollisionFreeMotion) continue;
      blocked.push_back(cuts[k]);
      blocked_at.push_back(k);
    }
    std::vector<CutMotion> again =
        PlanCutMotions(p.robot, model, scene, blocked, wider, p.deadline, make_checker);
    for (size_t i = 0; i < again.size(); ++i) motions[blocked_at[i]] = std::move(again[i]);
    stats.last_resort_s += Seconds(last_resort_start);
  }
  std::vector<int> planned, retry;  // indices into cuts / motions; into plan.cuts
  for (size_t k = 0; k < motions.size(); ++k) {
    const CutMotionOutcome outcome = motions[k].outcome;
    if (outcome == CutMotionOutcome::kPlanned) {
      planned.push_back(static_cast<int>(k));
    } else if (outcome == CutMotionOutcome::kNoCollisionFreeMotion && !last_pass) {
      retry.push_back(pending_here[k]);
    } else {
      if (outcome == CutMotionOutcome::kUnreachable) ++stats.unreachable;
      p.Unplanned(cuts[k].id, CutMotionReason(outcome));
    }
  }
  // The stubs of the pass's cuts (StubChords): the transits, blends and strokes of the pass run
  // on the vine after any of its cuts made before them, so each must be free of all of them (a
  // stroke of those of the other cuts). A cut whose every motion touches another's stub waits for
  // the next pass, where that stub is part of the vine.
  const auto stubs_start = std::chrono::steady_clock::now();
  std::vector<Cut> made_before;
  for (const Leg& leg : p.legs) made_before.push_back(leg.cut);
  std::vector<std::vector<Obstacle>> stubs(motions.size());
  for (int k : planned) {
    Cut made = cuts[k];
    made.point = motions[k].cut_point_in_platform;
    VB_ASSIGN_OR_RETURN(stubs[k], StubChords(p.vine, made_before, made, p.robot, options.scene));
  }
  const Eigen::Isometry3d base_from_platform = p.robot.platform_from_arm_base.inverse();
  std::vector<int> free_of_stubs;
  for (int k : planned) {
    CollisionScene others;
    for (int j : planned)
      if (j != k) others.obstacles.insert(others.obstacles.end(), stubs[j].begin(), stubs[j].end());
    if (!others.obstacles.empty()) {
      others = others.WithoutCaneNear(cuts[k].cane_id,
                                      base_from_platform * motions[k].cut_point_in_platform,
                                      options.cut_motion.cut_cane_free_radius_m);
    }
    const size_t options_before = 1 + motions[k].alternatives.size();
    const bool kept = others.obstacles.empty() ||
                      KeepMotionsFreeOf(others, options, p.robot, &motions[k]);
    const size_t options_after = kept ? 1 + motions[k].alternatives.size() : 0;
    if (options_after < options_before)
      stats.notes.push_back(absl::StrCat("cut ", cuts[k].id.value, ": ",
                                         options_before - options_after, " of ", options_before,
                                         " motions touch the stub of another cut of the pass"));
    if (!kept) {
      if (last_pass)
        p.Unplanned(cuts[k].id, "no_collision_free_cut_motion");
      else
        retry.push_back(pending_here[k]);
      continue;
    }
    free_of_stubs.push_back(k);
  }
  planned = std::move(free_of_stubs);
  stats.stubs_s += Seconds(stubs_start);
  stats.cut_motions_s += Seconds(t);
  if (planned.empty()) {
    for (int i : retry) p.Unplanned(p.plan.cuts[i].id, "no_collision_free_cut_motion");
    return std::vector<int>{};
  }
  for (int k : planned)
    scene.obstacles.insert(scene.obstacles.end(), stubs[k].begin(), stubs[k].end());
  ++stats.passes;

  // Margins around where the arm is, home, and every chosen cut motion of this pass.
  t = std::chrono::steady_clock::now();
  std::vector<ProtectedMotion> protect;
  protect.push_back({{options.home, p.At()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
  for (int k : planned) {
    const Eigen::Vector3d point = base_from_platform * motions[k].cut_point_in_platform;
    // The stroke may touch its own cane near the cut; its ends, where transits arrive and
    // leave, must stay clear of everything (one protected motion each, nothing ignored).
    auto protect_motion = [&](const std::vector<Joints>& path) {
      protect.push_back({path, cuts[k].cane_id, point, options.cut_motion.cut_cane_free_radius_m});
      protect.push_back({{path.front()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
      protect.push_back({{path.back()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
    };
    protect_motion(motions[k].path);
    for (const std::vector<Joints>& alternative : motions[k].alternatives)
      protect_motion(alternative);
  }
  CollisionScene inflated = scene;
  const MarginSummary margins = InflateMargins(p.robot, protect, options.margins, &inflated);
  if (stats.passes == 1) stats.margins = margins;
  p.UsePassScenes(scene, inflated);
  p.scene_pass = stats.passes;
  stats.margins_s += Seconds(t);

  // The options of each planned cut: its motion, alternatives and their rolled twins (the same
  // geometry, hence the same clearance and margins), with their cut indices.
  t = std::chrono::steady_clock::now();
  const int n = static_cast<int>(planned.size());
  const JointLimits& limits = p.robot.limits;
  const bool twins = options.rolled_twins && RollSymmetric(p.robot);
  std::vector<std::vector<std::vector<Joints>>> choices(n);  // per node - 1, per option
  std::vector<std::vector<int>> cut_index_of(n);
  for (int node = 1; node <= n; ++node) {
    CutMotion& motion = motions[planned[node - 1]];
    auto& c = choices[node - 1];
    auto& index = cut_index_of[node - 1];
    c.push_back(std::move(motion.path));
    for (auto& alternative : motion.alternatives) c.push_back(std::move(alternative));
    motion.alternatives.clear();
    index.assign(c.size(), motion.cut_index);
    for (size_t a = 0, originals = c.size(); twins && a < originals; ++a) {
      int twin_index = -1;
      auto twin = RolledTwin(c[a], index[a], StrokeOf(p.robot.tool), limits, &twin_index);
      if (!twin || std::any_of(c.begin(), c.end(), [&](const std::vector<Joints>& other) {
            return SameUpToTurns(other.front(), twin->front(), 0.05) &&
                   SameUpToTurns(other.back(), twin->back(), 0.05);
          }))
        continue;
      c.push_back(std::move(*twin));
      index.push_back(twin_index);
    }
  }

  // Order: node 0 is where the arm is, node j the j-th planned cut (entered at an option's first
  // configuration, left at its last). Jointly with the options (OrderAndChoose), or on each cut's
  // best motion.
  const Joints from = p.At();
  const bool joint = options.choose_motions_with_order;
  auto move_cost = [&](int i, int a, int j, int b) {
    const Joints& exit = i == 0 ? from : choices[i - 1][a].back();
    if (j == 0)
      return joint ? TurnAwareMoveTimeS(options.home, exit, limits)
                   : MoveTimeS(exit, options.home, limits);
    const Joints& entry = choices[j - 1][b].front();
    return joint ? TurnAwareMoveTimeS(exit, entry, limits) : MoveTimeS(exit, entry, limits);
  };
  Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(n + 1, n + 1);  // on the best motions
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (i != j) cost(i, j) = move_cost(i, 0, j, 0);
  const bool home_after = options.return_home && (retry.empty() || last_pass);
  std::vector<int> order;
  if (joint) {
    std::vector<int> counts(n);
    for (int j = 0; j < n; ++j) counts[j] = static_cast<int>(choices[j].size());
    const OrderChoiceResult chosen = OrderAndChoose(counts, move_cost, home_after);
    order = chosen.order;
    stats.order_cost_s += chosen.cost;
    stats.order_exact = stats.order_exact && chosen.exact_order;
  } else {
    const OrderResult best = OrderCuts(cost, home_after);
    order = best.order;
    stats.order_cost_s += best.cost;
    stats.order_exact = stats.order_exact && best.exact;
  }
  std::vector<int> given(n);
  for (int j = 0; j < n; ++j) given[j] = j + 1;
  stats.given_order_cost_s += OrderCost(cost, given, home_after);
  stats.nearest_neighbour_cost_s += NearestNeighbourOrder(cost, home_after).cost;
  stats.ordering_s += Seconds(t);

  // Paths: a cut whose transit fails is given up, and the next one is joined to the last reached.
  // When `kWalledInFailures` cuts in a row fail from the cut the arm is at, that cut walls the
  // arm in (its exit is in a pocket of the vine): it is undone once, the failed cuts are tried
  // again from the cut before, and it goes to the end of the pass's order (undo_walled_in).
  constexpr int kWalledInFailures = 2;
  t = std::chrono::steady_clock::now();
  const size_t legs_before = p.legs.size();
  std::vector<int> unreached;  // into plan.cuts: no transit found, to try in the next pass
  std::deque<int> queue(order.begin(), order.end());
  std::vector<int> leg_nodes;                          // the node of each leg of this pass
  std::vector<std::pair<int, PathOutcome>> failed;     // in a row, from where the arm is
  std::vector<bool> undone(n + 1, false);
  auto give_up = [&](int node, PathOutcome outcome) {
    const int k = planned[node - 1];
    if (options.retry_unreached && !last_pass && outcome == PathOutcome::kNoPathWithinDeadline)
      unreached.push_back(pending_here[k]);
    else
      p.Unplanned(cuts[k].id, PathReason(outcome));
  };
  while (!queue.empty()) {
    const int node = queue.front();
    queue.pop_front();
    const int k = planned[node - 1];
    std::vector<std::vector<Joints>>& c = choices[node - 1];
    for (std::vector<Joints>& choice : c)
      choice = ShiftedForReach(choice, p.At(), limits, *p.self_checker, options.path.max_step_m);
    // Every option is collision-free, and the arm's execution time is mostly transits: the
    // cheapest remaining plan through an option first (from where the arm is, along the rest of
    // the order), or the nearest in move time; the next when no path reaches it.
    std::vector<double> rank(c.size());
    for (size_t b = 0; b < c.size(); ++b) rank[b] = MoveTimeS(p.At(), c[b].front(), limits);
    if (joint) {
      std::vector<Eigen::MatrixXd> transition = {Eigen::Map<Eigen::RowVectorXd>(
          rank.data(), static_cast<Eigen::Index>(rank.size()))};
      int at = node;
      for (size_t s = 0; s <= queue.size(); ++s) {
        const int next = s < queue.size() ? queue[s] : 0;
        if (next == 0 && !home_after) break;
        const int rows = static_cast<int>(choices[at - 1].size());
        const int cols = next == 0 ? 1 : static_cast<int>(choices[next - 1].size());
        Eigen::MatrixXd m(rows, cols);
        for (int a = 0; a < rows; ++a)
          for (int b = 0; b < cols; ++b) m(a, b) = move_cost(at, a, next, b);
        transition.push_back(std::move(m));
        at = next;
      }
      rank = ChooseAlongOrder(transition).first_costs;
    }
    std::vector<int> ranked(c.size());
    std::iota(ranked.begin(), ranked.end(), 0);
    std::stable_sort(ranked.begin(), ranked.end(),
                     [&](int a, int b) { return rank[a] < rank[b]; });
    // All of them in one query: a cut none of them can be reached at costs one time limit.
    std::vector<Joints> goals;
    for (int b : ranked) goals.push_back(c[b].front());
    auto reached = p.Path(std::move(goals), cuts[k].id);
    if (!reached) {
      failed.push_back({node, stats.paths.back().outcome});
      if (options.undo_walled_in && static_cast<int>(failed.size()) >= kWalledInFailures &&
          !leg_nodes.empty() && !undone[leg_nodes.back()]) {
        const int walled = leg_nodes.back();
        undone[walled] = true;
        ++stats.walled_in_undone;
        motions[planned[walled - 1]] = std::move(p.legs.back().motion);
        p.legs.pop_back();
        leg_nodes.pop_back();
        for (auto it = failed.rbegin(); it != failed.rend(); ++it) queue.push_front(it->first);
        failed.clear();
        queue.push_back(walled);
      }
      continue;
    }
    for (const auto& [failed_node, outcome] : failed) give_up(failed_node, outcome);
    failed.clear();
    const int option = ranked[reached->goal_index];
    motions[k].path = c[option];
    motions[k].cut_index = cut_index_of[node - 1][option];
    Cut made = cuts[k];
    made.point = motions[k].cut_point_in_platform;
    p.legs.push_back(
        {std::move(reached->waypoints), std::move(motions[k]), made, std::move(reached->checker),
         std::move(reached->proof), stats.passes});
    leg_nodes.push_back(node);
  }
  for (const auto& [failed_node, outcome] : failed) give_up(failed_node, outcome);
  for (size_t l = legs_before; l < p.legs.size(); ++l) {
    const Leg& leg = p.legs[l];
    if (leg.motion.slid_m > 0)
      stats.notes.push_back(absl::StrCat("cut ", leg.cut.id.value, ": slid ", leg.motion.slid_m,
                                         " m outward along cane ", leg.cut.cane_id.value));
  }
  stats.paths_s += Seconds(t);
  // The next pass sees the vine without the wood of this pass's cuts; with no cut made, it would
  // see this pass's vine again and fail the same way.
  if (p.legs.size() == legs_before) {
    if (!retry.empty() && !last_pass && !p.last_resort_used &&
        options.last_resort_max_slide_m > options.cut_motion.max_slide_m) {
      // Except for the last resort: the blocked cuts alone go to the next pass, where on the same
      // vine none of them has a motion and they are searched sliding further. The unreached
      // would fail the same way.
      for (int i : unreached) p.Unplanned(p.plan.cuts[i].id, "no_path_within_deadline");
      return retry;
    }
    for (int i : retry) p.Unplanned(p.plan.cuts[i].id, "no_collision_free_cut_motion");
    for (int i : unreached) p.Unplanned(p.plan.cuts[i].id, "no_path_within_deadline");
    return std::vector<int>{};
  }
  retry.insert(retry.end(), unreached.begin(), unreached.end());
  std::sort(retry.begin(), retry.end());
  return retry;
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
  if (options.max_passes < 1) return absl::InvalidArgumentError("options.max_passes must be >= 1");

  PlanResult result;
  result.trajectory.platform_from_arm_base = robot.platform_from_arm_base;
  result.trajectory.tool = robot.tool;
  PlanStats& stats = result.stats;
  stats.setup_s = Seconds(start);  // validation
  stats.cuts = static_cast<int>(plan.cuts.size());
  auto t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(CollisionScene uncut_scene,
                      CollisionScene::Build(model, platform, robot, options.scene));
  {
    auto checker = MakeChecker(options.checker, robot, uncut_scene);
    if (!checker->IsFree(options.home))
      return absl::FailedPreconditionError("options.home: the home configuration is in collision");
    stats.checks += checker->checks();
  }
  stats.scene_s += Seconds(t);
  VB_RETURN_IF_ERROR(deadline.Check("plan"));

  t = std::chrono::steady_clock::now();
  Planning p{model, plan, robot, platform, options, deadline, result};
  p.uncut_scene = std::move(uncut_scene);
  p.self_checker = MakeChecker(options.checker, robot, CollisionScene{});
  stats.setup_s += Seconds(t);
  std::vector<int> pending(plan.cuts.size());
  for (size_t i = 0; i < pending.size(); ++i) pending[i] = static_cast<int>(i);
  VineModel now = model;
  for (int pass = 0; pass < options.max_passes && !pending.empty(); ++pass) {
    VB_ASSIGN_OR_RETURN(pending, PlanPass(now, pending, pass + 1 == options.max_passes, p));
    if (!pending.empty()) {
      t = std::chrono::steady_clock::now();
      std::vector<Cut> made;
      for (const Leg& leg : p.legs) made.push_back(leg.cut);
      now = WithoutFallenWood(model, made);
      stats.setup_s += Seconds(t);
    }
  }

  // Home again; if no path leads home from the last cut, that cut is given up and the arm goes
  // home from the one before it (the arm never ends a vine stranded among the canes).
  t = std::chrono::steady_clock::now();
  std::vector<Joints> home_path;
  std::shared_ptr<CollisionChecker> home_checker;  // of the scene the way home was found in
  std::shared_ptr<MotionProver> home_proof;        // that scene without margins
  while (options.return_home && !p.legs.empty()) {
    auto path = p.Path({options.home}, CutId{0});
    if (path) {
      home_path = std::move(path->waypoints);
      home_checker = std::move(path->checker);
      home_proof = std::move(path->proof);
      break;
    }
    const CutId id = p.legs.back().cut.id;
    p.Unplanned(id, "no_path_home_within_deadline");
    stats.notes.push_back(
        absl::StrCat("cut ", id.value, ": dropped, no path home from it within the deadline"));
    const int dropped_pass = p.legs.back().pass;
    p.legs.pop_back();
    if (!p.legs.empty() && dropped_pass < p.scene_pass) {
      // The scenes in use took that cut, of an earlier pass, as made (its wood fallen): the way
      // home from the cuts before it is planned on the vine exactly as they leave it.
      std::vector<Cut> made;
      for (const Leg& leg : p.legs) made.push_back(leg.cut);
      VB_ASSIGN_OR_RETURN(const CollisionScene scene,
                          CollisionScene::Build(WithoutFallenWood(model, made), platform, robot,
                                                options.scene));
      p.UsePassScenes(scene, scene);
      p.scene_pass = dropped_pass + 1;  // it takes every leg left as made
    }
  }
  stats.home_s = Seconds(t);
  stats.paths_s += stats.home_s;

  // Timing: home -> (transit, cut)* -> home; every transit and stroke starts and ends at rest
  // (a stroke is approached from rest, and each segment can be executed on its own).
  t = std::chrono::steady_clock::now();
  Trajectory& trajectory = result.trajectory;
  for (const Leg& leg : p.legs) {
    VB_RETURN_IF_ERROR(AppendTransit(leg.transit, leg.checker.get(), leg.proof.get(), options,
                                     robot.limits, stats, &trajectory));
    VB_RETURN_IF_ERROR(AppendStroke(leg.motion, leg.cut, robot, options, &trajectory));
    result.cuts.push_back(leg.cut);
  }
  if (!home_path.empty()) {
    VB_RETURN_IF_ERROR(
        AppendTransit(home_path, home_checker.get(), home_proof.get(), options, robot.limits, stats,
                      &trajectory));
  }
  stats.timing_s = Seconds(t);
  stats.planned = static_cast<int>(result.cuts.size());
  for (const PathRecord& path : stats.paths) stats.checks += path.checks;
  stats.total_s = Seconds(start);
  std::sort(trajectory.unplanned.begin(), trajectory.unplanned.end(),
            [](const UnplannedCut& a, const UnplannedCut& b) {
              return a.cut_id.value < b.cut_id.value;
            });
  return result;
}

}  // namespace vb::plan

namespace vb::plan {

Joints DefaultHome() {
  Joints q;
  q << -0.0900, 0.3588, 0.6480, -0.2072, 0.3916, 0.7171;
  return q;
}

}  // namespace vb::plan
