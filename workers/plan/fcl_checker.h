// SPDX-License-Identifier: Apache-2.0
// The FCL baselines of the primitive checker (what an FCL user would write): every arm body and
// obstacle an fcl::CollisionObject, the scene in a DynamicAABBTreeCollisionManager, each arm body
// collided against it through the broadphase, self-collision pairs collided directly.
//  - kPrimitives: fcl::Capsule / fcl::Sphere / fcl::Halfspace of exactly the same geometry.
//  - kMesh: every capsule and sphere tessellated (vertices on the true surface, so the mesh lies
//    inside it by at most MeshToleranceM()), fcl::BVHModel<OBBRSS>; each arm body one mesh of
//    ~1-5k triangles; each plane a large box mesh behind it.
// FCL exceptions are caught: a configuration whose check throws counts as in collision (and
// Clearance returns -inf). Thread-compatible: one checker per thread.
#pragma once

#include <memory>

#include "workers/plan/collision_checker.h"

namespace vb::plan {

// Largest distance between a tessellated surface and the true one, for a body of radius
// `radius_m` at the density kMesh uses. Disagreements between kMesh and the exact checkers are
// expected only where |Clearance| is below this.
double MeshToleranceM(double radius_m);
// The largest MeshToleranceM over the arm and the scene.
double MeshToleranceM(const RobotModel& robot, const CollisionScene& scene);

// Triangles of the kMesh tessellation of arm body `body` (an index into BodiesWithTool()).
int MeshTriangles(const RobotModel& robot, int body);

}  // namespace vb::plan
