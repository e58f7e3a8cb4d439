// SPDX-License-Identifier: Apache-2.0
// Mount study (issue 5, docs/plan.md "Mount study"): for candidate arm mounts
// platform_from_arm_base, the fraction of cuts that are reachable (some sampled cut pose has an IK
// solution) and that have a collision-free cut motion (PlanCutMotions with the primitive checker
// on the full scene: vine, trellis, neighbouring vines' canes and heads, platform). Cuts are the
// decide stage's default policy on the ground-truth models of tuning seeds 1100 + k. A mount whose
// base (a 0.075 m cylinder up to 0.15 m) projects into any camera of the default rig is flagged.
// Prints one JSON object per mount and line. Run:
//   build/bench/vb_plan_mount_study [--vines 100] [--ik_only] [--grid] [--tool secateur]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "nlohmann/json.hpp"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

struct Mount {
  std::string name;
  Eigen::Isometry3d platform_from_arm_base;
};

Mount MakeMount(const std::string& name, const Eigen::Vector3d& t, const Eigen::Matrix3d& r) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r;
  pose.translation() = t;
  return {name, pose};
}

Eigen::Matrix3d Rx(double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d Ry(double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

// Hand-picked layouts: upright on the floor in front of the cameras' lower edge, tilted toward
// the vine, hanging from the roof, on the camera-side wall facing the vine, beside the rig.
std::vector<Mount> NamedMounts() {
  return {
      MakeMount("floor_upright_y0.25_z0.45", {0, 0.25, 0.45}, Eigen::Matrix3d::Identity()),
      MakeMount("floor_upright_y0.35_z0.55", {0, 0.35, 0.55}, Eigen::Matrix3d::Identity()),
      MakeMount("floor_tilt30_y0.25_z0.45", {0, 0.25, 0.45}, Rx(-30)),
      MakeMount("behind_rig_upright_y0.0_z0.6", {0, 0.0, 0.6}, Eigen::Matrix3d::Identity()),
      MakeMount("wall_facing_vine_y-0.1_z0.6", {0, -0.1, 0.6}, Rx(-90)),
      MakeMount("roof_inverted_y0.3_z1.7", {0, 0.3, 1.7}, Rx(180)),
      MakeMount("roof_inverted_tilt30_y0.2_z1.6", {0, 0.2, 1.6}, Rx(180 + 30)),
      MakeMount("side_x-0.6_y0.35_z0.95_facing_x", {-0.6, 0.35, 0.95}, Ry(90)),
  };
}

// Floor mounts tilted toward the vine and roof mounts tilted toward it, on a grid.
std::vector<Mount> GridMounts() {
  std::vector<Mount> mounts;
  for (double y : {0.1, 0.2, 0.3, 0.4}) {
    for (double z : {0.35, 0.5, 0.65}) {
      for (double tilt : {0.0, 20.0, 40.0}) {
        mounts.push_back(MakeMount("floor_y" + std::to_string(y).substr(0, 4) + "_z" +
                                       std::to_string(z).substr(0, 4) + "_tilt" +
                                       std::to_string(static_cast<int>(tilt)),
                                   {0, y, z}, Rx(-tilt)));
      }
    }
    for (double z : {1.5, 1.7}) {
      for (double tilt : {0.0, 20.0, 40.0}) {
        mounts.push_back(MakeMount("roof_y" + std::to_string(y).substr(0, 4) + "_z" +
                                       std::to_string(z).substr(0, 4) + "_tilt" +
                                       std::to_string(static_cast<int>(tilt)),
                                   {0, y, z}, Rx(180 + tilt)));
      }
    }
  }
  return mounts;
}

struct Stop {
  VineModel model;
  std::vector<VineModel> neighbours;
  std::vector<Cut> cuts;
};

std::vector<Stop> LoadStops(int vines) {
  std::vector<Stop> stops;
  for (int k = 0; k < vines; ++k) {
    auto scene = sim::GenerateScene(1100 + k, 0);
    if (!scene.ok()) continue;
    auto decision = decide::Decide(scene->vine, PruningPolicy{});
    if (!decision.ok()) continue;
    stops.push_back({scene->vine, scene->neighbours, decision->plan.cuts});
  }
  return stops;
}

bool BaseInView(const Eigen::Isometry3d& platform_from_arm_base, const RigCalibration& rig) {
  for (double z = 0; z <= 0.15 + 1e-9; z += 0.025) {
    for (int a = 0; a < 16; ++a) {
      const double angle = 2 * M_PI * a / 16;
      const Eigen::Vector3d p =
          platform_from_arm_base *
          Eigen::Vector3d(0.075 * std::cos(angle), 0.075 * std::sin(angle), z);
      for (const CameraCalibration& camera : rig.cameras) {
        const auto uv = camera.Project(p);
        if (uv.has_value() && camera.InImage(*uv)) return true;
      }
    }
  }
  return false;
}

// Capsules of the neighbours' canes and head spheres, appended to `scene` (arm base frame).
void AddNeighbours(const std::vector<VineModel>& neighbours,
                   const Eigen::Isometry3d& base_from_platform, CollisionScene* scene) {
  int64_t owner = 1000000;
  for (const VineModel& n : neighbours) {
    for (const Cane& cane : n.canes) {
      ++owner;
      const Polyline3 line = cane.polyline.Resampled(0.03);
      for (size_t i = 1; i < line.points.size(); ++i) {
        Obstacle o;
        o.kind = ObstacleKind::kCane;
        o.owner_id = owner;
        o.capsule = {base_from_platform * line.points[i - 1], base_from_platform * line.points[i],
                     std::max(line.radii[i - 1], line.radii[i])};
        scene->obstacles.push_back(o);
      }
    }
    for (const Sphere& s : n.head.spheres) {
      Obstacle o;
      o.kind = ObstacleKind::kHead;
      o.capsule = {base_from_platform * s.center, base_from_platform * s.center, s.radius};
      scene->obstacles.push_back(o);
    }
  }
}

nlohmann::json Study(const Mount& mount, const std::vector<Stop>& stops, const ToolGeometry& tool,
                     const CutMotionOptions& options, bool ik_only, bool verbose,
                     const RigCalibration& rig) {
  RobotModel robot = DefaultUr5(tool);
  robot.platform_from_arm_base = mount.platform_from_arm_base;
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Isometry3d tcp_from_flange = tool.flange_from_tcp.inverse();
  int cuts = 0, reachable = 0, planned = 0, slid = 0, errors = 0;
  std::vector<double> clearances;
  std::map<std::string, int> outcomes;
  const auto start = std::chrono::steady_clock::now();
  for (const Stop& stop : stops) {
    cuts += static_cast<int>(stop.cuts.size());
    for (const Cut& cut : stop.cuts) {
      for (const Eigen::Isometry3d& pose :
           SampleCutPoses(base_from_platform * cut.point,
                          base_from_platform.linear() * cut.direction, options)) {
        if (InverseKinematics(pose * tcp_from_flange, robot.limits).count > 0) {
          ++reachable;
          break;
        }
      }
    }
    if (ik_only) continue;
    auto scene = CollisionScene::Build(stop.model, DefaultPlatform(), robot);
    if (!scene.ok()) {
      ++errors;
      continue;
    }
    AddNeighbours(stop.neighbours, base_from_platform, &*scene);
    for (const CutMotion& m :
         PlanCutMotions(robot, stop.model, *scene, stop.cuts, options, Deadline::In(60.0))) {
      ++outcomes[std::string(CutMotionOutcomeName(m.outcome))];
      if (verbose && m.outcome != CutMotionOutcome::kPlanned) {
        std::fprintf(stderr, "%s\n", m.message.c_str());
      }
      if (m.outcome != CutMotionOutcome::kPlanned) continue;
      ++planned;
      slid += m.slid_m > 0;
      clearances.push_back(m.clearance_m);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::sort(clearances.begin(), clearances.end());
  const Eigen::Quaterniond q(mount.platform_from_arm_base.linear());
  const Eigen::Vector3d t = mount.platform_from_arm_base.translation();
  nlohmann::json out = {{"mount", mount.name},
                        {"translation", {t.x(), t.y(), t.z()}},
                        {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
                        {"base_in_camera_view", BaseInView(mount.platform_from_arm_base, rig)},
                        {"cuts", cuts},
                        {"reachable_fraction", cuts ? static_cast<double>(reachable) / cuts : 0.0}};
  if (!ik_only) {
    out["planned_fraction"] = cuts ? static_cast<double>(planned) / cuts : 0.0;
    out["slid_fraction_of_planned"] = planned ? static_cast<double>(slid) / planned : 0.0;
    out["median_clearance_m"] = clearances.empty() ? 0.0 : clearances[clearances.size() / 2];
    out["scene_errors"] = errors;
    out["outcomes"] = outcomes;
    out["ms_per_cut"] = cuts ? 1000.0 * seconds / cuts : 0.0;
  }
  return out;
}

}  // namespace
}  // namespace vb::plan

int main(int argc, char** argv) {
  int vines = 100;
  bool ik_only = false, grid = false, verbose = false;
  vb::plan::CutMotionOptions options;
  std::vector<vb::plan::Mount> custom;
  std::string tool_name = "mill_end", only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--vines") && i + 1 < argc) {
      vines = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--ik_only")) {
      ik_only = true;
    } else if (!std::strcmp(argv[i], "--verbose")) {
      verbose = true;
    } else if (!std::strcmp(argv[i], "--max_tilt_deg") && i + 1 < argc) {
      options.max_tilt_rad = std::atof(argv[++i]) * M_PI / 180;
    } else if (!std::strcmp(argv[i], "--tilt_steps") && i + 1 < argc) {
      options.tilt_steps = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--sweep_m") && i + 1 < argc) {
      options.sweep_m = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--max_slide_m") && i + 1 < argc) {
      options.max_slide_m = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--mount") && i + 1 < argc) {
      only = argv[++i];
    } else if (!std::strcmp(argv[i], "--floor") && i + 3 < argc) {
      // A floor mount at (0, y, z) tilted toward the vine by tilt_deg about x.
      const double y = std::atof(argv[i + 1]), z = std::atof(argv[i + 2]),
                   tilt = std::atof(argv[i + 3]);
      custom.push_back(vb::plan::MakeMount(
          std::string("floor_y") + argv[i + 1] + "_z" + argv[i + 2] + "_tilt" + argv[i + 3],
          {0, y, z}, vb::plan::Rx(-tilt)));
      i += 3;
    } else if (!std::strcmp(argv[i], "--grid")) {
      grid = true;
    } else if (!std::strcmp(argv[i], "--tool") && i + 1 < argc) {
      tool_name = argv[++i];
    } else {
      std::fprintf(
          stderr,
          "usage: %s [--vines N] [--ik_only] [--grid] [--mount NAME] [--tool mill_end|secateur] "
          "[--floor Y Z TILT_DEG]... [--max_tilt_deg D --tilt_steps N] [--sweep_m S] "
          "[--max_slide_m M] [--verbose]\n",
          argv[0]);
      return 2;
    }
  }
  const vb::ToolGeometry tool =
      tool_name == "secateur" ? vb::plan::SecateurTool() : vb::plan::MillEndTool();
  auto rig = vb::sim::MakeRig();
  if (!rig.ok()) return 1;
  const auto stops = vb::plan::LoadStops(vines);
  const auto mounts =
      !custom.empty() ? custom : (grid ? vb::plan::GridMounts() : vb::plan::NamedMounts());
  if (auto status = options.Validate(); !status.ok()) {
    std::fprintf(stderr, "%s\n", std::string(status.message()).c_str());
    return 2;
  }
  for (const auto& mount : mounts) {
    if (!only.empty() && mount.name != only) continue;
    std::printf(
        "%s\n",
        vb::plan::Study(mount, stops, tool, options, ik_only, verbose, *rig).dump().c_str());
    std::fflush(stdout);
  }
  return 0;
}
