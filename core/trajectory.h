// SPDX-License-Identifier: Apache-2.0
// A vine's planned arm motion: timed joint trajectories through every cut (format
// "vinebot.trajectory.v1", ARCHITECTURE.md "Trajectory"), plus the tool geometry it was planned
// with. Joint angles follow the ur_kinematics DH convention. Plain value types; thread-compatible.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "core/ids.h"
#include "Eigen/Core"
#include "Eigen/Geometry"
#include "nlohmann/json.hpp"

namespace vb {

inline constexpr char kTrajectoryFormat[] = "vinebot.trajectory.v1";

// The cutter on the arm's flange: its tool-centre point and its collision geometry.
struct ToolGeometry {
  std::string name;                                          // e.g. "mill_end", "secateur"
  Eigen::Isometry3d flange_from_tcp = Eigen::Isometry3d::Identity();
  std::vector<Capsule> capsules;                             // in the flange frame
};

struct TrajectoryPoint {
  double t = 0.0;                                            // s from the trajectory start
  std::array<double, 6> q{};                                 // rad
};

enum class SegmentKind { kTransit, kCut };
std::string_view SegmentKindName(SegmentKind kind);          // "transit", "cut"

struct TrajectorySegment {
  SegmentKind kind = SegmentKind::kTransit;
  CutId cut_id;                                              // meaningful on cut segments only
  // t strictly increasing; the first point may repeat the previous segment's last time (each
  // segment holds its own start, so a cut segment can be executed and logged on its own).
  std::vector<TrajectoryPoint> points;
};

// Why a cut has no motion (ARCHITECTURE.md: `unplanned[].reason`).
struct UnplannedCut {
  CutId cut_id;
  std::string reason;  // "unreachable", "no_collision_free_cut_motion", "no_path_within_deadline", ...
};

struct Trajectory {
  std::string robot = "ur5";
  Eigen::Isometry3d platform_from_arm_base = Eigen::Isometry3d::Identity();
  ToolGeometry tool;
  std::vector<TrajectorySegment> segments;
  double duration_s = 0.0;
  std::vector<UnplannedCut> unplanned;

  // INVALID_ARGUMENT naming the element: non-finite numbers, a rotation that is not orthonormal,
  // times not strictly increasing within a segment or decreasing from one segment to the next, a cut segment without a positive
  // cut id, duration_s less than the last time, negative capsule radius.
  absl::Status Validate() const;
};

nlohmann::json TrajectoryToJson(const Trajectory& trajectory);
// Parses and validates; INVALID_ARGUMENT naming the field on any problem.
absl::StatusOr<Trajectory> TrajectoryFromJson(const nlohmann::json& json);
absl::Status WriteTrajectory(const std::string& path, const Trajectory& trajectory);
// Errors are prefixed with the path.
absl::StatusOr<Trajectory> ReadTrajectory(const std::string& path);

// {"translation":[x,y,z], "rotation_xyzw":[qx,qy,qz,qw]} <-> Isometry3d (the pose form of the
// trajectory format). Parsing normalises the quaternion and rejects one of norm < 0.5 or > 2.
nlohmann::json PoseToJson(const Eigen::Isometry3d& pose);
absl::StatusOr<Eigen::Isometry3d> PoseFromJson(const nlohmann::json& json, const std::string& what);

}  // namespace vb
