// SPDX-License-Identifier: Apache-2.0
// Why cut motions fail (issue 5, docs/plan.md "Cut motions"): plans simulated vines as
// `vinebot bench plan` does (ground truth, default policy, default PlanOptions, secateur), and for
// every cut left "no_collision_free_cut_motion" re-walks the cut-motion search (every slide,
// sampled pose, IK branch and stroke, as PlanCutMotions samples them) on the vine as the plan
// leaves it (the wood of every planned cut fallen) and names, with exact distances in double,
// what each candidate touches: which obstacle class and which arm body.
//
// Obstacle classes: the cut cane beyond the free radius (distal: toward its tip, falls with the
// cut; proximal: toward its base), another cane that the plan removes anyway ("goes": it or that
// part of it falls with one of the plan's cuts, planned or not) or that stays, the trunk, the
// head spheres, wires, posts, the platform (planes by name, camera capsules) and self-collision;
// for the secateur also the cut cane near the cut, which must lie between the open jaws.
// A candidate's blockers are the classes touched at its cut configuration or along its stroke.
// Per cut it prints the IK solutions over all slides and poses, those free at the cut, the strokes
// followed (a cut configuration already touching two classes, when a candidate with fewer is
// known, is not followed), and the candidate with the fewest blocker classes; over all cuts, the
// number of cuts that at least one candidate would free if one class (or one class on one body)
// were not an obstacle. The stroke is sampled at its Cartesian steps (not interpolated). Run:
//   build/bench/vb_cut_motion_diagnosis [--seed-base 1110] [--vines 20] [--verbose]
// --recheck instead re-checks each vine's trajectory (FCL meshes, 1 mm, as the bench) and prints
// the colliding segments, and any slid cut that passed the base of a child of its cane (the child
// would then stay on the vine: decide gives it no cut of its own).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/fallen_wood.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"
#include "workers/plan/trajectory_check.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {
namespace {

constexpr double kContactM = 1e-5;  // overlap deeper than this is a contact (as the flange test)

struct Body {
  std::string name;  // link name; the tool's capsules are "tool_body", "tool_jaw", "tool_bit"...
  int frame;
  Capsule capsule;
  int body_index;  // into BodiesWithTool (self pairs)
};

std::vector<Body> Bodies(const RobotModel& robot) {
  std::vector<Body> out;
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  for (size_t b = 0; b < bodies.size(); ++b) {
    for (size_t c = 0; c < bodies[b].capsules.size(); ++c) {
      std::string name = bodies[b].name;
      if (b + 1 == bodies.size()) name = c == 0 ? "tool_body" : "tool_jaw";
      out.push_back({name, bodies[b].frame, bodies[b].capsules[c], static_cast<int>(b)});
    }
  }
  return out;
}

// What one configuration touches: (class, body) pairs.
using Contacts = std::set<std::pair<std::string, std::string>>;

class Classifier {
 public:
  Classifier(const RobotModel& robot, const CollisionScene& scene,
             std::vector<std::string> obstacle_class)
      : robot_(robot), scene_(scene), class_(std::move(obstacle_class)), bodies_(Bodies(robot)),
        self_pairs_(robot.SelfCollisionPairs()) {}

  Contacts At(const Joints& q) const {
    Contacts out;
    const auto frames = LinkFrames(q);
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> placed(bodies_.size());
    for (size_t i = 0; i < bodies_.size(); ++i) {
      const Body& b = bodies_[i];
      placed[i] = {frames[b.frame] * b.capsule.a, frames[b.frame] * b.capsule.b};
    }
    static const char* kPlaneNames[] = {"ground", "roof", "camera_wall", "backdrop"};
    for (size_t i = 0; i < bodies_.size(); ++i) {
      const auto& [a, b] = placed[i];
      const double r = bodies_[i].capsule.radius;
      for (size_t p = 0; p < scene_.planes.size(); ++p) {
        const HalfSpace& h = scene_.planes[p];
        if (std::max(h.normal.dot(a), h.normal.dot(b)) + r + h.margin_m > h.offset + kContactM)
          out.insert({p < 4 ? kPlaneNames[p] : "plane", bodies_[i].name});
      }
      const Eigen::Vector3d centre = 0.5 * (a + b);
      const double bound = 0.5 * (b - a).norm() + r;
      for (size_t o = 0; o < scene_.obstacles.size(); ++o) {
        const Obstacle& ob = scene_.obstacles[o];
        const double orad = ob.capsule.radius + ob.margin_m;
        const double apart =
            bound + 0.5 * (ob.capsule.b - ob.capsule.a).norm() + orad;
        if ((centre - 0.5 * (ob.capsule.a + ob.capsule.b)).squaredNorm() > apart * apart) continue;
        if (SegmentSegmentDistance(a, b, ob.capsule.a, ob.capsule.b) < r + orad - kContactM)
          out.insert({class_[o], bodies_[i].name});
      }
    }
    // Self pairs by body (all capsules of both bodies).
    for (const auto& [bi, bj] : self_pairs_) {
      bool touch = false;
      for (size_t i = 0; i < bodies_.size() && !touch; ++i) {
        if (bodies_[i].body_index != bi) continue;
        for (size_t j = 0; j < bodies_.size() && !touch; ++j) {
          if (bodies_[j].body_index != bj) continue;
          touch = SegmentSegmentDistance(placed[i].first, placed[i].second, placed[j].first,
                                         placed[j].second) <
                  bodies_[i].capsule.radius + bodies_[j].capsule.radius - kContactM;
          if (touch) out.insert({"self", bodies_[i].name + "/" + bodies_[j].name});
        }
      }
    }
    return out;
  }

 private:
  const RobotModel& robot_;
  const CollisionScene& scene_;
  std::vector<std::string> class_;
  std::vector<Body> bodies_;
  std::vector<std::pair<int, int>> self_pairs_;
};

// The class of each obstacle of `scene` (built from `now`) for a cut on `cut_cane` at arc length
// `cut_s`; `after_all` is the vine once every cut of the plan is made.
std::vector<std::string> ObstacleClasses(const CollisionScene& scene, const VineModel& now,
                                         const VineModel& after_all, const RobotModel& robot,
                                         CaneId cut_cane, double cut_s) {
  std::vector<std::string> out;
  for (const Obstacle& o : scene.obstacles) {
    const Eigen::Vector3d mid = robot.platform_from_arm_base * (0.5 * (o.capsule.a + o.capsule.b));
    switch (o.kind) {
      case ObstacleKind::kHead:
        out.push_back("head");
        continue;
      case ObstacleKind::kWire:
        out.push_back("wire");
        continue;
      case ObstacleKind::kPost:
        out.push_back("post");
        continue;
      case ObstacleKind::kPlatform:
        out.push_back("camera");
        continue;
      case ObstacleKind::kLeftOutWood:
        out.push_back("left_out_wood");
        continue;
      case ObstacleKind::kCane:
        break;
    }
    const Cane& cane = now.canes[*now.IndexOf(CaneId{o.owner_id})];
    const double s = cane.polyline.Project(mid);
    if (o.owner_id == cut_cane.value) {
      out.push_back(s > cut_s ? "cut_cane_distal" : "cut_cane_proximal");
      continue;
    }
    if (cane.kind == CaneKind::kTrunk) {
      out.push_back("trunk");
      continue;
    }
    const std::optional<size_t> kept = after_all.IndexOf(cane.id);
    const bool goes = !kept || s > after_all.canes[*kept].polyline.Length() + 1e-3;
    out.push_back(goes ? "other_cane_goes" : "other_cane_stays");
  }
  return out;
}

// Along a trajectory segment's points in `scene`: the least primitive clearance (capped at 1 m)
// and how many points the FCL mesh checker finds in collision.
struct SegmentClearance {
  double worst_m = 1;
  int mesh_colliding = 0;
};
SegmentClearance ClearanceAlong(const RobotModel& robot, const CollisionScene& scene,
                                const std::vector<TrajectoryPoint>& points) {
  auto primitive = MakeChecker(CheckerKind::kPrimitives, robot, scene);
  auto mesh = MakeChecker(CheckerKind::kFclMesh, robot, scene);
  SegmentClearance out;
  for (const TrajectoryPoint& p : points) {
    const Joints q = Eigen::Map<const Joints>(p.q.data());
    out.worst_m = std::min(out.worst_m, primitive->Clearance(q));
    out.mesh_colliding += mesh->IsFree(q) ? 0 : 1;
  }
  return out;
}

// Every (obstacle, arm body) contact at any of the points.
Contacts ContactsAlong(const Classifier& who, const std::vector<TrajectoryPoint>& points) {
  Contacts all;
  for (const TrajectoryPoint& p : points) {
    const Contacts c = who.At(Eigen::Map<const Joints>(p.q.data()));
    all.insert(c.begin(), c.end());
  }
  return all;
}

std::string Join(const std::set<std::string>& s) {
  std::string out;
  for (const std::string& x : s) out += (out.empty() ? "" : "+") + x;
  return out.empty() ? "none" : out;
}

struct Totals {
  int cuts = 0;
  std::map<std::string, int> best_classes;          // best candidate's blocker set -> cuts
  std::map<std::string, int> freed_by_class;        // class -> cuts a single-class candidate has
  std::map<std::string, int> freed_by_class_body;   // class@body -> cuts
  std::map<std::string, int> where;                 // best candidate: at cut / stroke only
  int no_free_cut_config = 0, free_cut_config_stroke_collides = 0, stroke_ik_fails_only = 0;
};

void Diagnose(const RobotModel& robot, const PlatformGeometry& platform,
              const CutMotionOptions& options, const VineModel& now, const VineModel& after_all,
              const Cut& cut, bool verbose, Totals& totals) {
  const std::optional<size_t> ci = now.IndexOf(cut.cane_id);
  if (!ci) return;
  const auto scene = CollisionScene::Build(now, platform, robot);
  if (!scene.ok()) return;
  const Polyline3& cane = now.canes[*ci].polyline;
  const double s0 = cane.Project(cut.point);
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Isometry3d tcp_from_flange = robot.tool.flange_from_tcp.inverse();
  int cut_index = 0;
  const std::vector<Eigen::Vector3d> waypoints =
      StrokeWaypoints(StrokeOf(robot.tool), options, &cut_index);
  const int slides = static_cast<int>(options.max_slide_m / options.slide_step_m + 1e-9);

  struct Best {
    size_t classes = 1000;
    std::set<std::string> blockers;
    Contacts contacts;
    std::string where;
    int slide = 0;
  } best;
  std::map<std::string, bool> freed_by_class, freed_by_class_body;
  int ik_solutions = 0, free_cut = 0, strokes_ik = 0;
  for (int k = 0; k <= slides; ++k) {
    const double s = s0 + k * options.slide_step_m;
    if (k > 0 && s > cane.Length()) break;
    const Eigen::Vector3d point = base_from_platform * (k == 0 ? cut.point : cane.PointAt(s));
    const Eigen::Vector3d dir =
        base_from_platform.linear() * (k == 0 ? cut.direction : cane.TangentAt(s));
    CollisionScene local = scene->WithoutCaneNear(cut.cane_id, point,
                                                  options.cut_cane_free_radius_m);
    std::vector<std::string> classes =
        ObstacleClasses(local, now, after_all, robot, cut.cane_id, s);
    // A secateur may not touch the cut cane near the cut either (it lies between the jaws).
    if (StrokeOf(robot.tool) == CutStroke::kApproachCloseRetract) {
      for (const Obstacle& o : scene->obstacles) {
        if (o.kind == ObstacleKind::kCane && o.owner_id == cut.cane_id.value &&
            PointSegmentDistance(point, o.capsule.a, o.capsule.b) - o.capsule.radius <=
                options.cut_cane_free_radius_m) {
          local.obstacles.push_back(o);
          classes.push_back("cut_cane_near");
        }
      }
    }
    const Classifier classify(robot, local, classes);
    for (const Eigen::Isometry3d& pose : SampleCutPoses(point, dir, options)) {
      const IkSolutions ik = InverseKinematics(pose * tcp_from_flange, robot.limits);
      for (int b = 0; b < ik.count; ++b) {
        ++ik_solutions;
        Contacts at_cut = classify.At(ik.q[b]);
        if (at_cut.empty()) ++free_cut;
        std::set<std::string> cut_classes;
        for (const auto& [cls, body] : at_cut) cut_classes.insert(cls);
        // Two classes at the cut already: neither single-class nor better than a best with one.
        if (cut_classes.size() >= 2 && best.classes <= cut_classes.size()) continue;
        // The stroke toward its start (secateur: the approach; its retract retraces it).
        Contacts along;
        bool end_collides = false, ik_ok = true;
        Joints previous = ik.q[b];
        // Follows the stroke to waypoint i from `previous` (the IK branch nearest it, within
        // max_joint_jump_rad); false where the arm would jump.
        auto step_to = [&](size_t i) {
          Eigen::Isometry3d tcp = pose;
          tcp.translation() += pose.linear() * waypoints[i];
          const IkSolutions step = InverseKinematics(tcp * tcp_from_flange, robot.limits, &previous);
          int nearest = -1;
          double change = options.max_joint_jump_rad;
          for (int j = 0; j < step.count; ++j) {
            const double c = (step.q[j] - previous).cwiseAbs().maxCoeff();
            if (c <= change) change = c, nearest = j;
          }
          if (nearest < 0) return false;
          previous = step.q[nearest];
          return true;
        };
        for (int i = cut_index - 1; i >= 0 && ik_ok; --i) {
          ik_ok = step_to(static_cast<size_t>(i));
          if (!ik_ok) break;
          const Contacts c = classify.At(previous);
          if (i == 0 && !c.empty()) end_collides = true;
          along.insert(c.begin(), c.end());
        }
        if (StrokeOf(robot.tool) == CutStroke::kSweep) {
          previous = ik.q[b];
          for (size_t i = cut_index + 1; i < waypoints.size() && ik_ok; ++i) {
            ik_ok = step_to(i);
            if (!ik_ok) break;
            const Contacts c = classify.At(previous);
            along.insert(c.begin(), c.end());
          }
        }
        if (!ik_ok) continue;
        ++strokes_ik;
        Contacts all = at_cut;
        all.insert(along.begin(), along.end());
        std::set<std::string> classes;
        for (const auto& [cls, body] : all) classes.insert(cls);
        if (classes.size() == 1) {
          freed_by_class[*classes.begin()] = true;
          std::set<std::string> bodies;
          for (const auto& [cls, body] : all) bodies.insert(body);
          if (bodies.size() == 1) freed_by_class_body[*classes.begin() + "@" + *bodies.begin()] = true;
        }
        if (classes.size() < best.classes) {
          best.classes = classes.size();
          best.blockers = classes;
          best.contacts = all;
          best.where = !at_cut.empty() ? "cut_configuration"
                                       : (end_collides ? "stroke_incl_end" : "stroke_interior_only");
          best.slide = k;
        }
      }
    }
  }
  ++totals.cuts;
  const std::string key = best.classes == 1000 ? "no_stroke_within_ik" : Join(best.blockers);
  ++totals.best_classes[key];
  ++totals.where[best.where.empty() ? "none" : best.where];
  if (free_cut == 0) ++totals.no_free_cut_config;
  else ++totals.free_cut_config_stroke_collides;
  for (const auto& [c, v] : freed_by_class) ++totals.freed_by_class[c];
  for (const auto& [c, v] : freed_by_class_body) ++totals.freed_by_class_body[c];
  std::printf("  cut %lld cane %lld %s d=%.1fmm: ik %d, free at cut %d, strokes %d; best: %s (%s, "
              "slide %d cm)",
              static_cast<long long>(cut.id.value), static_cast<long long>(cut.cane_id.value),
              std::string(CutReasonName(cut.reason)).c_str(), 1000 * cut.diameter_m, ik_solutions,
              free_cut, strokes_ik, key.c_str(), best.where.c_str(), best.slide);
  if (verbose) {
    std::printf(" [");
    for (const auto& [cls, body] : best.contacts) std::printf(" %s@%s", cls.c_str(), body.c_str());
    std::printf(" ]");
  }
  std::printf("\n");
}

int Main(int argc, char** argv) {
  int seed_base = 1110, vines = 20;
  bool verbose = false, recheck = false;
  int alternatives = -1;  // -1: PlanOptions' default
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seed-base") && i + 1 < argc) seed_base = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--vines") && i + 1 < argc) vines = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--verbose")) verbose = true;
    else if (!std::strcmp(argv[i], "--recheck")) recheck = true;
    else if (!std::strcmp(argv[i], "--cut-alternatives") && i + 1 < argc)
      alternatives = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: %s [--seed-base N] [--vines N] [--verbose] [--recheck]"
                   " [--cut-alternatives N]\n",
                   argv[0]);
      return 2;
    }
  }
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions options;
  options.home = DefaultHome();
  if (alternatives >= 0) options.cut_motion.alternatives = alternatives;
  Totals totals;
  int cuts = 0, reachable = 0, planned = 0;
  int unproven_paths = 0, unproven_blends = 0, stub_notes = 0;  // PlanStats, over the vines
  for (int v = 0; v < vines; ++v) {
    const uint64_t seed = seed_base + v;
    const auto scene = sim::GenerateScene(seed, 1);
    if (!scene.ok()) continue;
    const auto decision = decide::Decide(scene->vine, PruningPolicy{});
    if (!decision.ok()) continue;
    const auto result = PlanVine(scene->vine, decision->plan, robot, platform, options);
    if (!result.ok()) {
      std::printf("seed %llu: %s\n", static_cast<unsigned long long>(seed),
                  std::string(result.status().message()).c_str());
      continue;
    }
    cuts += result->stats.cuts;
    reachable += result->stats.cuts - result->stats.unreachable;
    planned += result->stats.planned;
    unproven_paths += result->stats.unproven_paths;
    unproven_blends += result->stats.unproven_blends;
    for (const std::string& note : result->stats.notes)
      stub_notes += note.find("touch the stub") != std::string::npos;
    if (recheck) {
      // A slid cut must not pass the base of a child of its cane (that child would stay).
      for (const Cut& made : result->cuts) {
        const Cut* given = nullptr;
        for (const Cut& c : decision->plan.cuts)
          if (c.id.value == made.id.value) given = &c;
        const Cane& cane = scene->vine.canes[*scene->vine.IndexOf(made.cane_id)];
        const double s_given = cane.polyline.Project(given->point);
        const double s_made = cane.polyline.Project(made.point);
        if (s_made <= s_given + 1e-9) continue;
        for (CaneId child : scene->vine.ChildrenOf(made.cane_id)) {
          const Cane& c = scene->vine.canes[*scene->vine.IndexOf(child)];
          const double at = cane.polyline.Project(c.polyline.points.front());
          if (at > s_given && at <= s_made)
            std::printf("  cut %lld slid %.3f m past the base of cane %lld (at %.3f m)\n",
                        static_cast<long long>(made.id.value), s_made - s_given,
                        static_cast<long long>(child.value), at);
        }
      }
      std::vector<int> bad;
      const int64_t n = CountTrajectoryCollisions(
          result->trajectory, result->cuts, scene->vine, platform, robot, CheckerKind::kFclMesh,
          0.001, options.cut_motion.cut_cane_free_radius_m, &bad);
      std::printf("seed %llu: %lld colliding configurations\n",
                  static_cast<unsigned long long>(seed), static_cast<long long>(n));
      for (size_t i = 0; i < bad.size(); ++i) {
        if (bad[i] == 0) continue;
        const TrajectorySegment& segment = result->trajectory.segments[i];
        std::printf("  segment %zu (%s, cut %lld, %zu points): %d\n", i,
                    segment.kind == SegmentKind::kCut ? "cut" : "transit",
                    static_cast<long long>(segment.cut_id.value), segment.points.size(), bad[i]);
        if (segment.kind == SegmentKind::kTransit) {
          // The wood at the time of a transit is at least the wood after every cut before it;
          // the way home (cut 0) runs after all of them.
          std::vector<Cut> before;
          for (size_t k = 0; k < i; ++k)
            for (const Cut& c : result->cuts)
              if (result->trajectory.segments[k].kind == SegmentKind::kCut &&
                  c.id.value == result->trajectory.segments[k].cut_id.value)
                before.push_back(c);
          const auto s = CollisionScene::Build(WithoutFallenWood(scene->vine, before), platform, robot);
          const SegmentClearance along = ClearanceAlong(robot, *s, segment.points);
          std::printf("    transit after %zu cuts: primitive clearance at its samples %.6f m; "
                      "mesh-colliding samples %d\n", before.size(), along.worst_m,
                      along.mesh_colliding);
          // What its samples touch: obstacle kind:owner#chord (a cane's chords from its base).
          std::vector<std::string> names;
          std::map<int64_t, int> chords;
          for (const Obstacle& o : s->obstacles)
            names.push_back(std::to_string(static_cast<int>(o.kind)) + ":" +
                            std::to_string(o.owner_id) + "#" +
                            std::to_string(o.kind == ObstacleKind::kCane ? chords[o.owner_id]++ : 0));
          const Contacts all = ContactsAlong(Classifier(robot, *s, names), segment.points);
          for (const auto& [o, body] : all) std::printf("    touches %s with %s\n", o.c_str(), body.c_str());
        }
        for (const Cut& c : result->cuts) {
          if (c.id.value != segment.cut_id.value) continue;
          std::vector<Cut> before;
          for (const Cut& b : result->cuts) {
            if (b.id.value == c.id.value) break;
            before.push_back(b);
          }
          const auto s = CollisionScene::Build(WithoutFallenWood(scene->vine, before), platform, robot);
          const CollisionScene allowed = s->WithoutCaneNear(
              c.cane_id, robot.platform_from_arm_base.inverse() * c.point,
              options.cut_motion.cut_cane_free_radius_m);
          const SegmentClearance along = ClearanceAlong(robot, allowed, segment.points);
          std::printf("    primitive clearance along it %.6f m; mesh-colliding points %d\n",
                      along.worst_m, along.mesh_colliding);
          std::vector<std::string> names;
          for (const Obstacle& o : allowed.obstacles)
            names.push_back(std::to_string(static_cast<int>(o.kind)) + ":" +
                            std::to_string(o.owner_id));
          const Contacts all = ContactsAlong(Classifier(robot, allowed, names), segment.points);
          for (const auto& [o, body] : all) std::printf("    touches %s with %s\n", o.c_str(), body.c_str());
          std::printf("    cut cane %lld, cuts before:", static_cast<long long>(c.cane_id.value));
          for (const Cut& b : before) std::printf(" %lld(cane %lld)", static_cast<long long>(b.id.value), static_cast<long long>(b.cane_id.value));
          std::printf("\n");
        }
      }
      continue;
    }
    const VineModel now = WithoutFallenWood(scene->vine, result->cuts);
    const VineModel after_all = WithoutFallenWood(scene->vine, decision->plan.cuts);
    std::printf("seed %llu: %d cuts, %d planned\n", static_cast<unsigned long long>(seed),
                result->stats.cuts, result->stats.planned);
    for (const UnplannedCut& u : result->trajectory.unplanned) {
      if (u.reason != "no_collision_free_cut_motion") {
        std::printf("  cut %lld: %s\n", static_cast<long long>(u.cut_id.value), u.reason.c_str());
        continue;
      }
      for (const Cut& cut : decision->plan.cuts) {
        if (cut.id.value == u.cut_id.value)
          Diagnose(robot, platform, options.cut_motion, now, after_all, cut, verbose, totals);
      }
    }
  }
  std::printf("\n%d cuts, %d reachable, %d planned; %d without a collision-free cut motion\n",
              cuts, reachable, planned, totals.cuts);
  std::printf("  paths not proven free %d, blends not proven free %d, cuts with motions touching "
              "another cut's stub %d\n", unproven_paths, unproven_blends, stub_notes);
  std::printf("  no collision-free cut configuration at any slide: %d; free cut configurations "
              "but every stroke collides: %d\n",
              totals.no_free_cut_config, totals.free_cut_config_stroke_collides);
  std::printf("best candidate's blocker classes (cuts):\n");
  for (const auto& [k, n] : totals.best_classes) std::printf("  %-50s %d\n", k.c_str(), n);
  std::printf("where the best candidate collides (cuts):\n");
  for (const auto& [k, n] : totals.where) std::printf("  %-50s %d\n", k.c_str(), n);
  std::printf("cuts freed if one class were not an obstacle:\n");
  for (const auto& [k, n] : totals.freed_by_class) std::printf("  %-50s %d\n", k.c_str(), n);
  std::printf("cuts freed if one class on one body were not an obstacle:\n");
  for (const auto& [k, n] : totals.freed_by_class_body) std::printf("  %-50s %d\n", k.c_str(), n);
  return 0;
}

}  // namespace
}  // namespace vb::plan

int main(int argc, char** argv) { return vb::plan::Main(argc, argv); }
