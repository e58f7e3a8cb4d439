// SPDX-License-Identifier: Apache-2.0
// The safety-margins stage alone (issue 5, docs/plan.md "Speed of cut motions and margins"),
// deterministic: for simulated vines (ground truth, default policy, default PlanOptions,
// secateur) it plans the first pass's cut motions and protects them as PlanVine does (home and
// where the arm is, every motion and alternative, each stroke's ends alone; the pass's stubs in
// the scene), then times InflateMargins on that scene (thread CPU time, the fastest of --repeat
// runs, so that a loaded machine changes little). The margins of every obstacle and plane are
// hashed (FNV-1a over their bits) into one fingerprint: two builds whose fingerprints agree gave
// the same margins bit for bit. Prints one JSON object. Run:
//   build/bench/vb_margins_bench [--seed-base 1110] [--vines 90] [--repeat 5] [--alternatives N]

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/deadline.h"
#include "core/measure.h"
#include "core/statistics.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/safety_margins.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

int Main(int argc, char** argv) {
  int seed_base = 1110, vines = 90, repeat = 5;
  PlanOptions options;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seed-base") && i + 1 < argc) seed_base = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--vines") && i + 1 < argc) vines = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--alternatives") && i + 1 < argc)
      options.cut_motion.alternatives = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: %s [--seed-base N] [--vines N] [--repeat N] [--alternatives N]\n",
                   argv[0]);
      return 2;
    }
  }
  if (vines < 1 || repeat < 1) {
    std::fprintf(stderr, "--vines and --repeat must be >= 1\n");
    return 2;
  }
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  std::vector<double> cpu_s;
  uint64_t fingerprint = kFnv1aOffset;
  int64_t configurations = 0, obstacles = 0;
  for (int v = 0; v < vines; ++v) {
    const uint64_t seed = seed_base + v;
    const auto vineyard = sim::GenerateScene(seed, 1);
    if (!vineyard.ok()) continue;
    const auto decision = decide::Decide(vineyard->vine, PruningPolicy{});
    if (!decision.ok()) continue;
    auto scene = CollisionScene::Build(vineyard->vine, platform, robot, options.scene);
    if (!scene.ok()) continue;
    const std::vector<Cut>& cuts = decision->plan.cuts;
    const std::vector<CutMotion> motions = PlanCutMotions(
        robot, vineyard->vine, *scene, cuts, options.cut_motion, Deadline::Infinite());
    std::vector<ProtectedMotion> protect;
    protect.push_back({{options.home, options.home}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
    for (size_t k = 0; k < motions.size(); ++k) {
      if (motions[k].outcome != CutMotionOutcome::kPlanned) continue;
      Cut made = cuts[k];
      made.point = motions[k].cut_point_in_platform;
      const auto stubs = StubChords(vineyard->vine, {}, made, robot, options.scene);
      if (stubs.ok()) scene->obstacles.insert(scene->obstacles.end(), stubs->begin(), stubs->end());
      const Eigen::Vector3d point = base_from_platform * motions[k].cut_point_in_platform;
      auto protect_motion = [&](const std::vector<Joints>& path) {
        protect.push_back(
            {path, cuts[k].cane_id, point, options.cut_motion.cut_cane_free_radius_m});
        protect.push_back({{path.front()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
        protect.push_back({{path.back()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
      };
      protect_motion(motions[k].path);
      for (const std::vector<Joints>& alternative : motions[k].alternatives)
        protect_motion(alternative);
    }
    double best = 1e30;
    CollisionScene inflated;
    MarginSummary summary;
    for (int r = 0; r < repeat; ++r) {
      inflated = *scene;
      const double t0 = ThreadCpuSeconds();
      summary = InflateMargins(robot, protect, options.margins, &inflated);
      best = std::min(best, ThreadCpuSeconds() - t0);
    }
    cpu_s.push_back(best);
    configurations += summary.configurations;
    obstacles += static_cast<int64_t>(inflated.obstacles.size());
    for (const Obstacle& o : inflated.obstacles) fingerprint = Fnv1a(o.margin_m, fingerprint);
    for (const HalfSpace& h : inflated.planes) fingerprint = Fnv1a(h.margin_m, fingerprint);
  }
  double total = 0;
  for (double s : cpu_s) total += s;
  std::printf(
      "{\"seed_base\": %d, \"vines\": %zu, \"repeat\": %d, \"alternatives\": %d,\n"
      " \"margins_cpu_s_median\": %.6g, \"margins_cpu_s_total\": %.6g,\n"
      " \"protected_configurations\": %lld, \"obstacles\": %lld,\n"
      " \"margins_fingerprint\": \"%016llx\"}\n",
      seed_base, cpu_s.size(), repeat, options.cut_motion.alternatives, Median(cpu_s), total,
      static_cast<long long>(configurations), static_cast<long long>(obstacles),
      static_cast<unsigned long long>(fingerprint));
  return 0;
}

}  // namespace
}  // namespace vb::plan

int main(int argc, char** argv) { return vb::plan::Main(argc, argv); }
