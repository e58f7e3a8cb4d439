// SPDX-License-Identifier: Apache-2.0
// The collision-checker interface the planner is written against (after OMPL's
// StateValidityChecker / MotionValidator), with its implementations: our primitive checker
// (spheres of the arm against capsules, spheres and planes, sorted by distance from the base and
// culled per link by reach, after Botterill et al. 2017 section 3.4 and VAMP, Thomason et al.
// ICRA 2024) and the FCL baselines (triangle meshes or FCL primitives of the same geometry).
// A checker is built for one robot and one scene and never changes. Not thread-safe (it counts
// checks); use one per thread.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "absl/status/statusor.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

class CollisionChecker {
 public:
  virtual ~CollisionChecker() = default;

  // True if at q no arm body (tool included) touches an obstacle inflated by its margin, and no
  // self-collision pair touches. Joint limits are not checked here. Counts one check.
  virtual bool IsFree(const Joints& q) = 0;
  // out[i] = IsFree(qs[i]); implementations may check configurations together. Counts qs.size().
  virtual void AreFree(std::span<const Joints> qs, std::span<bool> out);
  // True if every configuration on the straight joint-space segment from a to b, interpolated so
  // that no point of the arm moves more than `max_step_m` between checks (a conservative bound
  // from joint steps and lever arms, see MotionSteps), is free. Both ends included.
  virtual bool IsMotionFree(const Joints& a, const Joints& b, double max_step_m);
  // Smallest distance between the surface of any arm body and any obstacle (inflated by its
  // margin), or between self-collision pairs; negative when they overlap. Counts one check.
  virtual double Clearance(const Joints& q) = 0;

  int64_t checks() const { return checks_; }
  void ResetChecks() { checks_ = 0; }

 protected:
  int64_t checks_ = 0;
};

// Number of intervals to split the joint segment a -> b into so that no point of the arm within
// `reach_m` of any joint axis moves more than max_step_m per interval (>= 1).
int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m = 1.2);

enum class FclMode { kMesh, kPrimitives };

std::unique_ptr<CollisionChecker> MakePrimitiveChecker(const RobotModel& robot,
                                                      const CollisionScene& scene);
// FCL baselines. kMesh tessellates every capsule, sphere and plane patch (~1-5k triangles per arm
// link at the default density); kPrimitives uses FCL's capsules, spheres and half-spaces.
std::unique_ptr<CollisionChecker> MakeFclChecker(const RobotModel& robot,
                                                const CollisionScene& scene, FclMode mode);

}  // namespace vb::plan
