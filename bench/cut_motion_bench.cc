// SPDX-License-Identifier: Apache-2.0
// The cut-motion stage alone (issue 5, docs/plan.md "Cut motions"), deterministic: plans the cut
// motions of simulated vines (ground truth, default policy, default PlanOptions, secateur) in
// passes as PlanVine does, assuming every planned cut is made (its wood falls, fallen_wood.h) and
// retrying the cuts left no_collision_free_cut_motion on the vine after them, up to --passes
// passes or until a pass plans nothing. No paths are planned, so the result does not depend on
// RRT-Connect's time limit: the outcomes, clearances and motions of two builds can be compared
// exactly (--fingerprint FILE writes one line per cut and pass with a hash of every joint value
// of the motion and its alternatives).
// Prints one JSON object: per vine the stage's thread CPU time and wall time summed over the
// passes (--repeat R plans each pass R times and keeps the fastest), their medians, and the
// outcomes. Run:
//   build/bench/vb_cut_motion_bench [--seed-base 1110] [--vines 90] [--passes 6] [--repeat 1]
//                                   [--fingerprint FILE] [--orientations N] [--max-roll-deg D]
//                                   [--roll-steps N] [--max-tilt-deg D] [--tilt-steps N]
//                                   [--max-slide-m M] [--alternatives N]
//                                   [--last-resort-max-slide-m M] [--last-resort-max-roll-deg D]
//                                   [--last-resort-roll-steps N] [--share-rolled-twins 0|1]
//                                   [--per-cut 0|1]
// The cuts of a pass are planned in one PlanCutMotions call, as PlanVine does; --per-cut 1 plans
// them one call each (each with its own checker) and reports the CPU time by outcome.
// Cuts left without a motion by a pass that plans none are tried once more, as PlanVine does,
// sliding up to PlanOptions' last_resort_max_slide_m (--last-resort-max-slide-m; 0: off), with
// --last-resort-max-roll-deg / --last-resort-roll-steps wider rolls there too.

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "core/deadline.h"
#include "core/measure.h"
#include "core/statistics.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/fallen_wood.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

// FNV-1a over every joint value rounded to 1e-7 rad: equal for motions that differ by rounding
// only (--share-rolled-twins 0 against 1).
uint64_t RoundedHash(const std::vector<Joints>& path) {
  uint64_t h = kFnv1aOffset;
  for (const Joints& q : path) {
    for (int j = 0; j < 6; ++j) h = Fnv1a(static_cast<long long>(std::llround(q[j] * 1e7)), h);
  }
  return h;
}

// FNV-1a over the bits of every joint value.
uint64_t Hash(const std::vector<Joints>& path, uint64_t h) {
  for (const Joints& q : path) {
    for (int j = 0; j < 6; ++j) h = Fnv1a(q[j], h);
  }
  return h;
}

int Main(int argc, char** argv) {
  int seed_base = 1110, vines = 90, passes = 6, repeat = 1;
  bool per_cut = false;
  const char* fingerprint = nullptr;
  PlanOptions options;
  // Cuts left without a motion by a pass that plans none are tried once more with these (as
  // PlanVine does with last_resort_max_slide_m).
  CutMotionOptions last_resort = options.cut_motion;
  last_resort.max_slide_m = options.last_resort_max_slide_m;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seed-base") && i + 1 < argc) seed_base = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--vines") && i + 1 < argc) vines = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--passes") && i + 1 < argc) passes = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--per-cut") && i + 1 < argc) per_cut = std::atoi(argv[++i]) != 0;
    else if (!std::strcmp(argv[i], "--fingerprint") && i + 1 < argc) fingerprint = argv[++i];
    // Cut-motion options (default: PlanOptions').
    else if (!std::strcmp(argv[i], "--orientations") && i + 1 < argc)
      options.cut_motion.orientations = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--max-roll-deg") && i + 1 < argc)
      options.cut_motion.max_roll_rad = std::atof(argv[++i]) * M_PI / 180.0;
    else if (!std::strcmp(argv[i], "--roll-steps") && i + 1 < argc)
      options.cut_motion.roll_steps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--max-tilt-deg") && i + 1 < argc)
      options.cut_motion.max_tilt_rad = std::atof(argv[++i]) * M_PI / 180.0;
    else if (!std::strcmp(argv[i], "--tilt-steps") && i + 1 < argc)
      options.cut_motion.tilt_steps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--max-slide-m") && i + 1 < argc)
      options.cut_motion.max_slide_m = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--last-resort-max-slide-m") && i + 1 < argc)
      last_resort.max_slide_m = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--last-resort-max-roll-deg") && i + 1 < argc)
      last_resort.max_roll_rad = std::atof(argv[++i]) * M_PI / 180.0;
    else if (!std::strcmp(argv[i], "--last-resort-roll-steps") && i + 1 < argc)
      last_resort.roll_steps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--alternatives") && i + 1 < argc)
      options.cut_motion.alternatives = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--share-rolled-twins") && i + 1 < argc)
      options.cut_motion.share_rolled_twins = last_resort.share_rolled_twins =
          std::atoi(argv[++i]) != 0;
    else {
      std::fprintf(stderr,
                   "usage: %s [--seed-base N] [--vines N] [--passes N] [--repeat N]"
                   " [--fingerprint FILE] [--orientations N] [--max-roll-deg D] [--roll-steps N]"
                   " [--max-tilt-deg D] [--tilt-steps N] [--max-slide-m M] [--alternatives N]"
                   " [--last-resort-max-slide-m M] [--last-resort-max-roll-deg D]"
                   " [--last-resort-roll-steps N] [--share-rolled-twins 0|1] [--per-cut 0|1]\n",
                   argv[0]);
      return 2;
    }
  }
  // Off when it would search no wider than the passes (--last-resort-max-slide-m 0).
  const bool use_last_resort = last_resort.max_slide_m > options.cut_motion.max_slide_m ||
                               last_resort.max_roll_rad > options.cut_motion.max_roll_rad ||
                               last_resort.roll_steps > options.cut_motion.roll_steps;
  if (const absl::Status s = last_resort.Validate(); !s.ok()) {
    std::fprintf(stderr, "last resort %s\n", std::string(s.message()).c_str());
    return 2;
  }
  if (const absl::Status s = options.cut_motion.Validate(); !s.ok()) {
    std::fprintf(stderr, "%s\n", std::string(s.message()).c_str());
    return 2;
  }
  if (vines < 1 || passes < 1 || repeat < 1) {
    std::fprintf(stderr, "--vines, --passes and --repeat must be >= 1\n");
    return 2;
  }
  FILE* out = fingerprint ? std::fopen(fingerprint, "w") : nullptr;
  if (fingerprint && !out) {
    std::fprintf(stderr, "cannot write %s\n", fingerprint);
    return 2;
  }
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  std::vector<double> cpu_s, wall_s;
  std::map<std::string, int> outcomes;  // final outcome of every cut
  std::map<std::string, double> cpu_by_outcome;  // CPU time of every cut motion search, by outcome
  int cuts_total = 0, slid = 0, slid_past_child = 0;
  std::map<std::string, int> slid_by_reason;  // planned cuts by reason, head or not, and slide
  double clearance_sum = 0;
  for (int v = 0; v < vines; ++v) {
    const uint64_t seed = seed_base + v;
    const auto scene = sim::GenerateScene(seed, 1);
    if (!scene.ok()) continue;
    const auto decision = decide::Decide(scene->vine, PruningPolicy{});
    if (!decision.ok()) continue;
    std::vector<Cut> pending = decision->plan.cuts, made;
    cuts_total += static_cast<int>(pending.size());
    double cpu = 0, wall = 0;
    for (int pass = 0; pass < passes && !pending.empty(); ++pass) {
      const VineModel model = WithoutFallenWood(scene->vine, made);
      const auto collision_scene = CollisionScene::Build(model, platform, robot, options.scene);
      if (!collision_scene.ok()) break;
      std::vector<Cut> here;
      for (const Cut& c : pending) {
        if (model.IndexOf(c.cane_id)) here.push_back(c);
        else ++outcomes["cane_fell_with_an_earlier_cut"];
      }
      std::vector<CutMotion> motions;
      double best_cpu = 1e30, best_wall = 1e30;
      for (int r = 0; r < repeat; ++r) {
        const double c0 = ThreadCpuSeconds();
        const auto w0 = std::chrono::steady_clock::now();
        // All the pass's cuts in one call, as PlanVine makes it (one checker for them all,
        // cut_motion.cc SharedChecker); with --per-cut one cut at a time: CPU time by outcome.
        motions.clear();
        std::vector<double> cut_cpu;
        if (per_cut) {
          for (const Cut& c : here) {
            const double t0 = ThreadCpuSeconds();
            motions.push_back(PlanCutMotions(robot, model, *collision_scene, std::span(&c, 1),
                                             options.cut_motion, Deadline::Infinite())[0]);
            cut_cpu.push_back(ThreadCpuSeconds() - t0);
          }
        } else {
          motions = PlanCutMotions(robot, model, *collision_scene, here, options.cut_motion,
                                   Deadline::Infinite());
        }
        best_cpu = std::min(best_cpu, ThreadCpuSeconds() - c0);
        if (r == 0 && per_cut) {
          for (size_t k = 0; k < motions.size(); ++k)
            cpu_by_outcome[std::string(CutMotionOutcomeName(motions[k].outcome))] += cut_cpu[k];
        }
        best_wall = std::min(
            best_wall,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count());
      }
      cpu += best_cpu;
      wall += best_wall;
      std::vector<Cut> retry, made_now;
      for (size_t k = 0; k < motions.size(); ++k) {
        const CutMotion& m = motions[k];
        if (out) {
          uint64_t h = Hash(m.path, kFnv1aOffset);
          for (const auto& a : m.alternatives) h = Hash(a, h);
          // Then the motion rounded, and the set of motions rounded, in any order (a sum).
          uint64_t set = m.path.empty() ? 0 : RoundedHash(m.path);
          for (const auto& a : m.alternatives) set += RoundedHash(a);
          std::fprintf(out, "%llu %d %lld %s %.12g %.6g %d %zu %016llx %016llx %016llx\n",
                       static_cast<unsigned long long>(seed), pass,
                       static_cast<long long>(m.cut_id.value),
                       std::string(CutMotionOutcomeName(m.outcome)).c_str(), m.clearance_m,
                       m.slid_m, m.cut_index, m.alternatives.size(),
                       static_cast<unsigned long long>(h),
                       static_cast<unsigned long long>(m.path.empty() ? 0 : RoundedHash(m.path)),
                       static_cast<unsigned long long>(set));
        }
        const bool last = pass + 1 == passes;
        if (m.outcome == CutMotionOutcome::kPlanned) {
          Cut c = here[k];
          c.point = m.cut_point_in_platform;
          made_now.push_back(c);
          ++outcomes["planned"];
          clearance_sum += m.clearance_m;
          slid += m.slid_m > 0;
          // A slide past the base of a child of the cut cane leaves that child on the vine.
          const Polyline3& cane = model.canes[*model.IndexOf(c.cane_id)].polyline;
          const double s_given = cane.Project(here[k].point), s_made = cane.Project(c.point);
          for (CaneId child : model.ChildrenOf(c.cane_id)) {
            const double at =
                cane.Project(model.canes[*model.IndexOf(child)].polyline.points.front());
            if (at > s_given && at <= s_made) {
              ++slid_past_child;
              break;
            }
          }
          const Cane& cut_cane = model.canes[*model.IndexOf(c.cane_id)];
          const bool from_head = cut_cane.parent_id.has_value() &&
                                 model.canes[*model.IndexOf(*cut_cane.parent_id)].kind ==
                                     CaneKind::kTrunk;
          ++slid_by_reason[std::string(CutReasonName(c.reason)) + (from_head ? "_head" : "") +
                           (m.slid_m > 0.1 + 1e-9   ? "_over_0.10"
                            : m.slid_m > 0.05 + 1e-9 ? "_0.06-0.10"
                            : m.slid_m > 0         ? "_0.01-0.05"
                                                   : "_0")];
        } else if (m.outcome == CutMotionOutcome::kNoCollisionFreeMotion && !last) {
          retry.push_back(here[k]);
        } else {
          ++outcomes[std::string(CutMotionOutcomeName(m.outcome))];
        }
      }
      if (made_now.empty() && use_last_resort && !retry.empty()) {
        const double t0 = ThreadCpuSeconds();
        for (const Cut& c : retry) {
          const CutMotion m = PlanCutMotions(robot, model, *collision_scene, std::span(&c, 1),
                                             last_resort, Deadline::Infinite())[0];
          if (out) {
            std::fprintf(out, "%llu %d %lld last_resort_%s %.12g %.6g %d %zu\n",
                         static_cast<unsigned long long>(seed), pass,
                         static_cast<long long>(m.cut_id.value),
                         std::string(CutMotionOutcomeName(m.outcome)).c_str(), m.clearance_m,
                         m.slid_m, m.cut_index, m.alternatives.size());
          }
          if (m.outcome != CutMotionOutcome::kPlanned) continue;
          Cut made_cut = c;
          made_cut.point = m.cut_point_in_platform;
          made_now.push_back(made_cut);
          ++outcomes["planned"];
          ++outcomes["planned_as_last_resort"];
          clearance_sum += m.clearance_m;
          slid += m.slid_m > 0;
        }
        cpu += ThreadCpuSeconds() - t0;
        std::vector<Cut> still;
        for (const Cut& c : retry) {
          if (std::none_of(made_now.begin(), made_now.end(),
                           [&](const Cut& m) { return m.id == c.id; }))
            still.push_back(c);
        }
        retry = still;
        if (pass + 1 == passes) {
          outcomes["no_collision_free_cut_motion"] += static_cast<int>(retry.size());
          retry.clear();
        }
      }
      if (made_now.empty()) {
        outcomes["no_collision_free_cut_motion"] += static_cast<int>(retry.size());
        retry.clear();
      }
      made.insert(made.end(), made_now.begin(), made_now.end());
      pending = retry;
    }
    cpu_s.push_back(cpu);
    wall_s.push_back(wall);
  }
  if (out) std::fclose(out);
  std::printf("{\"vines\": %zu, \"seed_base\": %d, \"cuts\": %d, \"cpu_median_s\": %.6f, "
              "\"wall_median_s\": %.6f, \"cpu_total_s\": %.4f, \"slid\": %d, "
              "\"mean_clearance_m\": %.6f, \"outcomes\": {",
              cpu_s.size(), seed_base, cuts_total, Median(cpu_s), Median(wall_s),
              [&] { double s = 0; for (double c : cpu_s) s += c; return s; }(), slid,
              outcomes["planned"] ? clearance_sum / outcomes["planned"] : 0.0);
  bool first = true;
  for (const auto& [name, n] : outcomes) {
    std::printf("%s\"%s\": %d", first ? "" : ", ", name.c_str(), n);
    first = false;
  }
  std::printf("}, \"slid_past_child\": %d, \"planned_by_reason_and_slide\": {", slid_past_child);
  first = true;
  for (const auto& [name, n] : slid_by_reason) {
    std::printf("%s\"%s\": %d", first ? "" : ", ", name.c_str(), n);
    first = false;
  }
  std::printf("}, \"cpu_s_by_outcome\": {");
  first = true;
  for (const auto& [name, s] : cpu_by_outcome) {
    std::printf("%s\"%s\": %.4f", first ? "" : ", ", name.c_str(), s);
    first = false;
  }
  std::printf("}}\n");
  return 0;
}

}  // namespace
}  // namespace vb::plan

int main(int argc, char** argv) { return vb::plan::Main(argc, argv); }
