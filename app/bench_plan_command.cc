// SPDX-License-Identifier: Apache-2.0
// vinebot bench plan: the planning benchmark of issue 5. For N simulated vines (seeds seed_base ..
// seed_base + N - 1, vine 1 of each vineyard; the ground-truth model and its cut plan decided
// under the default policy) it plans the whole vine with each collision checker on one core and
// prints one JSON object: per checker the per-path planning time (median, p95), the whole-vine
// time, checks per path, ns per configuration check and the fraction of reachable cuts planned;
// plus IK time, execution time per vine, the ordering's saving, and the dense re-check of every
// trajectory planned with our checker against FCL meshes with the margins removed. With
// --per-vine true, also each vine's stages (our checker); trajectory_fingerprint hashes every
// trajectory planned with our checker (equal fingerprints: the same trajectories).

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <numeric>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "app/commands.h"
#include "app/plan_flags.h"
#include "core/measure.h"
#include "core/statistics.h"
#include "core/status_macros.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/trajectory_check.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::app {
namespace {

using plan::CheckerKind;
using plan::Joints;

struct CheckerRecord {
  std::vector<double> path_s, solved_path_s, vine_s, checks_per_path;
  // Thread CPU time of each whole vine: what the vine costs on one core, steadier than the wall
  // time on a shared machine (which the time limits of the path queries still follow).
  std::vector<double> vine_cpu_s;
  // Vine times on the vines the baselines also plan whole (for the speed-up).
  std::vector<double> baseline_vines_vine_s;
  int direct = 0, without_margins = 0, walled_in = 0, repeated_failures = 0, flip_bound = 0;
  // Wall time summed over all vines' path queries, those that found a path and those that did not.
  double solved_paths_total_s = 0, failed_paths_total_s = 0;
  std::vector<double> median_margin_m;  // per vine, first pass (MarginSummary)
  std::map<std::string, std::vector<double>> stage_s;  // per vine
  int reachable = 0, planned = 0, passes = 0;
  std::map<std::string, int> unplanned;  // reason -> cuts
};

// Keeps a timed loop's result observable so that the compiler cannot drop the loop (what
// benchmark::DoNotOptimize does; GCC and Clang).
void Sink(int value) { asm volatile("" : : "r"(value) : "memory"); }

Joints RandomJoints(const plan::JointLimits& limits, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Joints q;
  for (int j = 0; j < 6; ++j) q[j] = limits.lower[j] + u(rng) * (limits.upper[j] - limits.lower[j]);
  return q;
}

// Mean ns per IsFree on random configurations within the limits (the checker's own scene).
double CheckNs(plan::CollisionChecker& checker, const plan::JointLimits& limits, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Joints> qs(4000);
  for (Joints& q : qs) q = RandomJoints(limits, rng);
  int free = 0;
  const auto t = std::chrono::steady_clock::now();
  for (const Joints& q : qs) free += checker.IsFree(q) ? 1 : 0;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  Sink(free);
  return 1e9 * s / qs.size();
}

// ns per call of InverseKinematics (all solutions) on poses of random configurations.
double IkNs(const plan::JointLimits& limits) {
  std::mt19937_64 rng(7);
  std::vector<Eigen::Isometry3d> poses(20000);
  for (auto& pose : poses) pose = plan::ForwardKinematics(RandomJoints(limits, rng));
  int solutions = 0;
  const auto t = std::chrono::steady_clock::now();
  for (const auto& pose : poses) solutions += plan::InverseKinematics(pose, limits).count;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  Sink(solutions);
  return 1e9 * s / poses.size();
}

// The same path queries replanned by one checker.
struct Replay {
  std::vector<double> path_s, checks, check_ns;
  int solved = 0;
};

nlohmann::json Summary(const CheckerRecord& r) {
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [name, values] : r.stage_s) stages[name] = Median(values);
  return {{"stage_median_s", stages},{"per_path_median_s", Median(r.path_s)},
          {"per_path_p95_s", Quantile(r.path_s, 0.95)},
          {"vine_median_s", Median(r.vine_s)},
          {"vine_cpu_median_s", Median(r.vine_cpu_s)},
          {"checks_per_path", Median(r.checks_per_path)},
          {"success_rate", r.reachable > 0 ? double(r.planned) / r.reachable : 0.0},
          {"paths", r.path_s.size()},
          {"solved_path_median_s", Median(r.solved_path_s)},
          {"solved_path_p95_s", Quantile(r.solved_path_s, 0.95)},
          {"direct_path_fraction", r.path_s.empty() ? 0.0 : double(r.direct) / r.path_s.size()},
          {"max_passes_used", r.passes},
          {"paths_without_margins", r.without_margins},
          // Failed queries given up as walled in, and refused as repeats (path_planner.h).
          {"failed_paths_walled_in", r.walled_in},
          {"failed_paths_repeated", r.repeated_failures},
          {"failed_paths_flip_bound", r.flip_bound},
          {"solved_paths_total_s", r.solved_paths_total_s},
          {"failed_paths", r.path_s.size() - r.solved_path_s.size()},
          {"failed_paths_total_s", r.failed_paths_total_s},
          {"median_margin_m", Median(r.median_margin_m)},
          {"unplanned_reasons", r.unplanned}};
}

}  // namespace

absl::Status RunBenchPlan(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const int64_t vines, flags.Int("vines", 10));
  VB_ASSIGN_OR_RETURN(const int64_t seed_base, flags.Int("seed-base", 9000));
  VB_ASSIGN_OR_RETURN(const std::string checkers_flag,
                      flags.String("checkers", "primitives,fcl_primitives,fcl_mesh"));
  VB_ASSIGN_OR_RETURN(const bool verify, flags.Bool("verify", true));
  // Per path, every checker replans the same queries: the transits our planner attempted on the
  // first --baseline-vines vines, in the vine's scene without margins, with the time limit scaled
  // by --baseline-time-scale for FCL (~50x slower per check) so that it gets as many checks.
  // Whole vines with an FCL checker (cut motions included) take minutes each: only the first
  // --baseline-full-vines are planned whole with them (default 0: their vine_median_s is null).
  VB_ASSIGN_OR_RETURN(const int64_t baseline_vines, flags.Int("baseline-vines", 3));
  VB_ASSIGN_OR_RETURN(const double baseline_time_scale, flags.Double("baseline-time-scale", 50.0));
  VB_ASSIGN_OR_RETURN(const int64_t baseline_full_vines, flags.Int("baseline-full-vines", 0));
  // The output is always one JSON object; --json is accepted for scripts that pass it.
  VB_ASSIGN_OR_RETURN(const bool json_flag, flags.Bool("json", true));
  // --per-vine: also each vine's stages, cuts, passes and path queries (our checker).
  VB_ASSIGN_OR_RETURN(const bool per_vine, flags.Bool("per-vine", false));
  VB_ASSIGN_OR_RETURN(PlanSetup setup, ParsePlanSetup(flags));
  VB_RETURN_IF_ERROR(flags.Finish());
  (void)json_flag;
  if (vines < 1 || vines > 10000)
    return absl::InvalidArgumentError("--vines must be in [1, 10000]");
  if (seed_base < 0) return absl::InvalidArgumentError("--seed-base must be >= 0");
  if (baseline_vines < 0 || baseline_full_vines < 0)
    return absl::InvalidArgumentError("--baseline-vines and --baseline-full-vines must be >= 0");
  if (!(baseline_time_scale >= 1) || !std::isfinite(baseline_time_scale))
    return absl::InvalidArgumentError("--baseline-time-scale must be finite and >= 1");
  std::vector<CheckerKind> kinds;
  for (absl::string_view name : absl::StrSplit(checkers_flag, ',')) {
    VB_ASSIGN_OR_RETURN(const CheckerKind kind, ParseCheckerKind(std::string(name)));
    kinds.push_back(kind);
  }

  std::map<CheckerKind, CheckerRecord> records;
  nlohmann::json per_vine_json = nlohmann::json::array();
  std::map<CheckerKind, Replay> replays;
  std::vector<double> execution_s, saving, saving_vs_nn, cuts_per_vine, transit_s, cut_s,
      planned_per_vine;
  int verified = 0, verified_free = 0, failures = 0;
  int blend_vias = 0, blend_stops = 0, blend_shrinks = 0;  // transit timing, our checker
  // Every sample (time and joints) of every trajectory planned with our checker and every
  // unplanned cut, in order: two builds with the same fingerprint planned the same trajectories.
  uint64_t fingerprint = kFnv1aOffset;
  // Joint travel of the transits (rad, summed along their samples), our checker: per transit its
  // most-moving joint; per joint the total over all vines; per vine the wrist roll (joint 6).
  std::vector<double> transit_max_joint_rad, wrist_roll_rad_per_vine;
  std::array<double, 6> travel_per_joint{};
  for (int64_t v = 0; v < vines; ++v) {
    const uint64_t seed = static_cast<uint64_t>(seed_base + v);
    VB_ASSIGN_OR_RETURN(const sim::Scene scene, sim::GenerateScene(seed, 1));
    auto decision = decide::Decide(scene.vine, PruningPolicy{});
    if (!decision.ok()) {
      ++failures;
      std::cerr << "seed " << seed << ": decide: " << decision.status() << "\n";
      continue;
    }
    cuts_per_vine.push_back(decision->plan.cuts.size());
    // The vine's scene without margins: the dense re-check and the replayed path queries.
    const auto base_scene = plan::CollisionScene::Build(scene.vine, setup.platform, setup.robot);
    std::vector<plan::PathRecord> queries;  // our planner's transits on this vine
    for (CheckerKind kind : kinds) {
      const bool baseline = kind != CheckerKind::kPrimitives;
      if (baseline && v >= baseline_full_vines) continue;
      plan::PlanOptions options = setup.options;
      options.checker = kind;
      if (baseline) options.path.time_limit_s *= baseline_time_scale;
      const double cpu_start_s = ThreadCpuSeconds();
      auto result = plan::PlanVine(scene.vine, decision->plan, setup.robot, setup.platform,
                                   options, Deadline::In(60.0 * (baseline ? baseline_time_scale : 1)));
      const double cpu_s = ThreadCpuSeconds() - cpu_start_s;
      if (!result.ok()) {
        ++failures;
        std::cerr << "seed " << seed << " " << plan::CheckerKindName(kind) << ": "
                  << result.status() << "\n";
        continue;
      }
      CheckerRecord& r = records[kind];
      const plan::PlanStats& s = result->stats;
      r.vine_s.push_back(s.total_s);
      r.vine_cpu_s.push_back(cpu_s);
      if (v < baseline_full_vines) r.baseline_vines_vine_s.push_back(s.total_s);
      if (!baseline && v < baseline_vines) queries = s.paths;
      // "other": the whole vine less the six stages (setup_s and what no timer covers); the
      // medians of the stages do not add up to the whole vine's (a vine slow in one stage is
      // often slow in another), so the per-vine figures (--per-vine) show where a vine goes.
      const double other = s.total_s - (s.scene_s + s.cut_motions_s + s.margins_s +
                                        s.ordering_s + s.paths_s + s.timing_s);
      nlohmann::json vine_stages = nlohmann::json::object();
      for (const auto& [name, value] :
           {std::pair<const char*, double>{"scene", s.scene_s}, {"cut_motions", s.cut_motions_s},
            {"margins", s.margins_s}, {"ordering", s.ordering_s}, {"paths", s.paths_s},
            {"timing", s.timing_s}, {"other", other}, {"stubs", s.stubs_s},
            {"last_resort", s.last_resort_s}, {"home", s.home_s}, {"setup", s.setup_s}}) {
        r.stage_s[name].push_back(value);
        vine_stages[name] = value;
      }
      if (per_vine && !baseline) {
        int failed = 0;
        for (const plan::PathRecord& p : s.paths) failed += p.outcome != plan::PathOutcome::kSolved;
        per_vine_json.push_back({{"seed", seed}, {"total_s", s.total_s}, {"cpu_s", cpu_s},
                                 {"stages_s", vine_stages},
                                 {"cuts", s.cuts}, {"planned", s.planned}, {"passes", s.passes},
                                 {"paths", s.paths.size()}, {"failed_paths", failed},
                                 {"walled_in_undone", s.walled_in_undone},
                                 {"protected_configurations", s.margins.configurations},
                                 {"execution_s", result->trajectory.duration_s}});
      }
      for (const plan::PathRecord& p : s.paths) {
        r.path_s.push_back(p.planning_s);
        if (p.outcome == plan::PathOutcome::kSolved) {
          r.solved_path_s.push_back(p.planning_s);
          r.solved_paths_total_s += p.planning_s;
        } else {
          r.failed_paths_total_s += p.planning_s;
        }
        if (p.direct) ++r.direct;
        if (p.without_margins) ++r.without_margins;
        if (p.walled_in) ++r.walled_in;
        if (p.repeated_failure) ++r.repeated_failures;
        if (p.flip_bound) ++r.flip_bound;
        r.checks_per_path.push_back(static_cast<double>(p.checks));
      }
      r.reachable += s.cuts - s.unreachable;
      r.median_margin_m.push_back(s.margins.median_margin_m);
      r.planned += s.planned;
      r.passes = std::max(r.passes, s.passes);
      for (const UnplannedCut& u : result->trajectory.unplanned) ++r.unplanned[u.reason];
      if (kind != CheckerKind::kPrimitives) continue;
      for (const TrajectorySegment& segment : result->trajectory.segments) {
        fingerprint =
            Fnv1a(segment.cut_id.value, Fnv1a(static_cast<int>(segment.kind), fingerprint));
        for (const TrajectoryPoint& point : segment.points) {
          fingerprint = Fnv1a(point.t, fingerprint);
          for (double q : point.q) fingerprint = Fnv1a(q, fingerprint);
        }
      }
      for (const UnplannedCut& u : result->trajectory.unplanned) {
        fingerprint = Fnv1a(u.cut_id.value, fingerprint);
        for (char c : u.reason) fingerprint = Fnv1a(c, fingerprint);
      }
      execution_s.push_back(result->trajectory.duration_s);
      double transit = 0, cutting = 0;
      for (const TrajectorySegment& segment : result->trajectory.segments) {
        const double d = segment.points.back().t - segment.points.front().t;
        (segment.kind == SegmentKind::kCut ? cutting : transit) += d;
      }
      double wrist_roll = 0;
      for (const TrajectorySegment& segment : result->trajectory.segments) {
        if (segment.kind != SegmentKind::kTransit) continue;
        std::array<double, 6> travel{};
        for (size_t i = 1; i < segment.points.size(); ++i)
          for (int j = 0; j < 6; ++j)
            travel[j] += std::abs(segment.points[i].q[j] - segment.points[i - 1].q[j]);
        for (int j = 0; j < 6; ++j) travel_per_joint[j] += travel[j];
        transit_max_joint_rad.push_back(*std::max_element(travel.begin(), travel.end()));
        wrist_roll += travel[5];
      }
      wrist_roll_rad_per_vine.push_back(wrist_roll);
      transit_s.push_back(transit);
      cut_s.push_back(cutting);
      planned_per_vine.push_back(s.planned);
      blend_vias += s.blend_vias;
      blend_stops += s.blend_stops;
      blend_shrinks += s.blend_shrinks;
      if (s.given_order_cost_s > 0) saving.push_back(1.0 - s.order_cost_s / s.given_order_cost_s);
      if (s.nearest_neighbour_cost_s > 0)
        saving_vs_nn.push_back(1.0 - s.order_cost_s / s.nearest_neighbour_cost_s);
      if (verify && base_scene.ok()) {
        // Margins removed (the scene as built has none), 1 mm of travel between checks, against
        // the cameras where the simulator put them (its default rig, DefaultPlatform), not where
        // a --calibration says they are: a wrong calibration cannot hide a collision here.
        const int64_t collisions = plan::CountTrajectoryCollisions(
            result->trajectory, result->cuts, scene.vine, plan::DefaultPlatform(), setup.robot,
            CheckerKind::kFclMesh, 0.001, setup.options.cut_motion.cut_cane_free_radius_m);
        ++verified;
        if (collisions == 0) ++verified_free;
        else std::cerr << "seed " << seed << ": " << collisions << " colliding configurations\n";
      }
    }
    if (queries.empty()) continue;
    // The same queries for every checker, on the vine's scene without margins.
    if (!base_scene.ok()) continue;
    for (CheckerKind kind : kinds) {
      auto checker = plan::MakeChecker(kind, setup.robot, *base_scene);
      plan::PathOptions options = setup.options.path;
      if (kind != CheckerKind::kPrimitives) options.time_limit_s *= baseline_time_scale;
      plan::PathPlanner planner(*checker, setup.robot.limits, options);
      Replay& replay = replays[kind];
      replay.check_ns.push_back(CheckNs(*checker, setup.robot.limits, seed));
      for (const plan::PathRecord& q : queries) {
        const plan::PathResult path = planner.PlanToAny(q.start, q.goals, Deadline::Infinite());
        replay.path_s.push_back(path.planning_s);
        replay.checks.push_back(static_cast<double>(path.checks));
        replay.solved += path.outcome == plan::PathOutcome::kSolved;
      }
    }
  }

  nlohmann::json out = {{"vines", vines},
                        {"baseline_vines", std::min(vines, baseline_vines)},
                        {"baseline_time_scale", baseline_time_scale},
                        {"baseline_full_vines", std::min(vines, baseline_full_vines)},
                        {"seed_base", seed_base},
                        {"tool", setup.robot.tool.name},
                        {"failures", failures},
                        {"cuts_per_vine_mean", cuts_per_vine.empty() ? 0.0 :
                             std::accumulate(cuts_per_vine.begin(), cuts_per_vine.end(), 0.0) /
                                 cuts_per_vine.size()}};
  for (CheckerKind kind : kinds) {
    nlohmann::json j;
    const auto r = records.find(kind);
    if (r != records.end()) j["whole_vines"] = Summary(r->second);
    // The keys: per path on the replayed queries (identical for every checker), per vine
    // from whole vines (null where none were planned with this checker).
    const Replay& replay = replays[kind];
    j["per_path_median_s"] = Median(replay.path_s);
    j["per_path_p95_s"] = Quantile(replay.path_s, 0.95);
    j["checks_per_path"] = Median(replay.checks);
    j["path_solved_fraction"] =
        replay.path_s.empty() ? 0.0 : double(replay.solved) / replay.path_s.size();
    j["paths"] = replay.path_s.size();
    j["check_ns"] = Median(replay.check_ns);
    // Fraction of reachable cuts planned, and the whole-vine time: from whole vines only.
    j["success_rate"] = r != records.end() ? nlohmann::json(r->second.reachable > 0
                                                 ? double(r->second.planned) / r->second.reachable
                                                 : 0.0)
                                           : nlohmann::json();
    j["vine_median_s"] =
        r != records.end() ? nlohmann::json(Median(r->second.vine_s)) : nlohmann::json();
    out[std::string(plan::CheckerKindName(kind))] = j;
  }
  out["trajectory_fingerprint"] = absl::StrCat(absl::Hex(fingerprint, absl::kZeroPad16));
  out["ik_all_solutions_ns"] = IkNs(setup.robot.limits);
  out["execution_s_per_vine_median"] = Median(execution_s);
  out["transit_s_per_vine_median"] = Median(transit_s);
  out["cut_stroke_s_per_vine_median"] = Median(cut_s);
  out["planned_cuts_per_vine_median"] = Median(planned_per_vine);
  // Interior transit waypoints, those where the arm stops (every blend size collided), and the
  // bisection steps that made colliding blends smaller (all vines).
  out["transit_vias"] = blend_vias;
  out["transit_via_stops"] = blend_stops;
  out["transit_blend_shrinks"] = blend_shrinks;
  out["transit_max_joint_travel_rad_median"] = Median(transit_max_joint_rad);
  out["transit_wrist_roll_rad_per_vine_median"] = Median(wrist_roll_rad_per_vine);
  {
    double total = 0;
    for (double t : travel_per_joint) total += t;
    std::vector<double> share;
    for (double t : travel_per_joint) share.push_back(total > 0 ? t / total : 0.0);
    out["transit_travel_share_per_joint"] = share;
  }
  out["order_saving_fraction"] = Median(saving);
  out["order_saving_vs_nearest_neighbour_fraction"] = Median(saving_vs_nn);
  if (verify) {
    out["verified_trajectories"] = verified;
    out["verified_collision_free_fraction"] = verified > 0 ? double(verified_free) / verified : 0.0;
  }
  const auto fast = replays.find(CheckerKind::kPrimitives);
  const auto mesh = replays.find(CheckerKind::kFclMesh);
  if (fast != replays.end() && mesh != replays.end() && Median(fast->second.path_s) > 0)
    out["speedup_per_path_vs_fcl_mesh"] = Median(mesh->second.path_s) / Median(fast->second.path_s);
  const auto fast_vines = records.find(CheckerKind::kPrimitives);
  const auto mesh_vines = records.find(CheckerKind::kFclMesh);
  if (fast_vines != records.end() && mesh_vines != records.end()) {
    out["speedup_per_vine_vs_fcl_mesh"] = Median(mesh_vines->second.vine_s) /
                                          Median(fast_vines->second.baseline_vines_vine_s);
  }
  if (per_vine) out["per_vine"] = per_vine_json;
  std::cout << out.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
