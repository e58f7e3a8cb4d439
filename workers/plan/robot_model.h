// SPDX-License-Identifier: Apache-2.0
// The arm as the planner sees it: a UR5 mounted on the platform, its joint limits, the cutter on
// its flange, and the collision geometry of its links (capsules in each DH link frame), plus the
// platform's own fixed geometry (walls, ground, roof, camera rig) that the arm must not touch.
// Plain value types; thread-compatible.
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/geometry.h"
#include "core/trajectory.h"
#include "Eigen/Geometry"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// Collision geometry of one link, in DH frame `frame` (0 = base .. 6 = flange; see LinkFrames).
struct LinkBody {
  std::string name;            // "base", "shoulder", "upper_arm", ..., "tool"
  int frame = 0;               // 0..6
  std::vector<Capsule> capsules;
};

struct RobotModel {
  Eigen::Isometry3d platform_from_arm_base = Eigen::Isometry3d::Identity();
  JointLimits limits;
  ToolGeometry tool;           // its capsules become the last LinkBody ("tool", frame 6)
  std::vector<LinkBody> links; // arm links (without the tool), base first

  // Pairs of indices into BodiesWithTool() that may never touch (self-collision pairs): every
  // pair of bodies at least two links apart along the chain, except pairs whose distance is the
  // same in every configuration (found by sampling within the limits; e.g. wrist 2 and a straight
  // tool on the joint 6 axis), which can neither come into contact nor leave it (MoveIt's
  // "never/always in collision" pairs). Costs ~0.1 ms the first time; the pairs of the last 8
  // robots (bodies and limits compared exactly) are cached, process-wide and thread-safe.
  std::vector<std::pair<int, int>> SelfCollisionPairs() const;
  // links plus the tool as a last body in frame 6.
  std::vector<LinkBody> BodiesWithTool() const;
  // INVALID_ARGUMENT naming the field: non-orthonormal mount rotation, bad limits, negative radii,
  // non-finite geometry, frame outside [0, 6].
  absl::Status Validate() const;
};

// A UR5 with the capsule model of ARCHITECTURE.md (upper arm and forearm 0.06 m, wrists
// 0.0375-0.06 m), the given tool, and the default mount on the platform (documented in
// docs/plan.md with the reachability study that chose it).
RobotModel DefaultUr5(const ToolGeometry& tool);

// The default mount, chosen by the mount study (docs/plan.md): arm base at (0, 0.45, 0.45) m in the
// platform frame, its z axis tilted 50 degrees from vertical toward the vine (rotation -50 degrees
// about platform x). The one place the default mount is defined.
Eigen::Isometry3d DefaultPlatformFromArmBase();

// The platform's fixed geometry in the platform frame: the arm may touch none of it.
struct PlatformGeometry {
  double ground_z_m = 0.0;            // ground plane
  double roof_z_m = 2.2;              // platform roof
  double camera_side_wall_y_m = -0.25;// wall behind the camera rig (free side: y greater)
  double backdrop_y_m = 1.25;         // backdrop panel across the row (free side: y smaller)
  std::vector<Sphere> fixed_spheres;  // fixed parts of the platform, as enclosing spheres
  std::vector<Capsule> fixed_capsules;// e.g. the cameras of the rig, each along its optical axis

  absl::Status Validate() const;
};

// The default platform around the simulator's default rig (sim/rig.h): walls and ground as
// above and, for each of the three cameras, a capsule of radius 0.045 m along its optical axis
// from 0.13 m behind its centre of projection (at the camera-side wall) to 0.05 m in front of it,
// enclosing a 0.03 x 0.03 x 0.06 m camera body and a 0.03 x 0.05 m lens (docs/plan.md).
// For tools without a calibration (benchmarks, tests); a stop's plan uses PlatformAroundRig.
PlatformGeometry DefaultPlatform();

// The capsule DefaultPlatform puts around a camera whose centre of projection is
// `centre_in_platform` and whose optical axis points along `axis_in_platform` (normalised here):
// radius 0.045 m, from 0.13 m behind the centre to 0.05 m in front of it.
Capsule CameraBody(const Eigen::Vector3d& centre_in_platform,
                   const Eigen::Vector3d& axis_in_platform);

// The platform around a calibrated rig: DefaultPlatform's walls, ground and roof, and for each
// camera of `rig`, in its order, CameraBody at its calibrated centre along its optical axis (the
// camera's z axis), so that a rig mounted off nominal moves its capsules with it. For the
// simulator's default rig (sim::MakeRig) the capsules are DefaultPlatform's.
// INVALID_ARGUMENT naming the camera and field for an invalid calibration
// (RigCalibration::Validate), and naming the camera when its centre lies farther than
// kMaxCameraOffNominalM from every camera of DefaultPlatform's design, or its optical axis turned
// more than kMaxCameraTurnFromNominalDeg from that camera's (another rig's calibration, or a frame
// or sign error, would leave the real cameras unprotected).
inline constexpr double kMaxCameraOffNominalM = 0.15;
inline constexpr double kMaxCameraTurnFromNominalDeg = 30.0;
absl::StatusOr<PlatformGeometry> PlatformAroundRig(const RigCalibration& rig);

}  // namespace vb::plan
