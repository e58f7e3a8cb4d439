// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/robot_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>
#include <random>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"

namespace vb::plan {
namespace {

// UR5 dimensions beyond the DH table (Universal Robots' published drawings): the upper arm runs
// 0.13585 m out along the joint 2 axis from the plane of the base axis, the forearm 0.1197 m back
// (0.01615 m out), and the wrist 1 axis sits at d4 = 0.10915 m.
constexpr double kShoulderOffsetM = 0.13585;
constexpr double kElbowOffsetM = -0.1197;
constexpr double kForearmOffsetM = kShoulderOffsetM + kElbowOffsetM;  // 0.01615
constexpr double kArmRadiusM = 0.06;        // upper arm, forearm, shoulder and elbow housings
constexpr double kBaseRadiusM = 0.065;      // joint 1 housing above the mounting flange
constexpr double kWristRadiusM = 0.045;     // wrist 1 and wrist 2 housings
constexpr double kWrist3RadiusM = 0.0375;   // wrist 3 up to the flange

bool FiniteVec(const Eigen::Vector3d& v) { return v.allFinite(); }

absl::Status ValidateCapsule(const Capsule& c, const std::string& what) {
  if (!FiniteVec(c.a) || !FiniteVec(c.b) || !std::isfinite(c.radius)) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": non-finite geometry"));
  }
  if (c.radius < 0) return absl::InvalidArgumentError(absl::StrCat(what, ": negative radius"));
  return absl::OkStatus();
}

absl::Status ValidatePose(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().allFinite()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": non-finite"));
  }
  const Eigen::Matrix3d r = pose.linear();
  if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() < 0) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": rotation is not orthonormal"));
  }
  return absl::OkStatus();
}

}  // namespace

Eigen::Isometry3d DefaultPlatformFromArmBase() {
  // The mount study's best (docs/plan.md "Mount study"): on the floor, 0.45 m in front of the
  // cameras and below their view, tilted 50 degrees toward the vine about the platform x axis.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.0, 0.45, 0.45);
  pose.linear() = Eigen::AngleAxisd(-50.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return pose;
}

namespace {

// Everything SelfCollisionPairs depends on: the bodies (frames and capsules) and the joint limits
// (the sampling range). Compared exactly.
std::vector<double> SelfPairsKey(const std::vector<LinkBody>& bodies, const JointLimits& limits) {
  std::vector<double> key(limits.lower.data(), limits.lower.data() + 6);
  key.insert(key.end(), limits.upper.data(), limits.upper.data() + 6);
  for (const LinkBody& body : bodies) {
    key.push_back(body.frame);
    key.push_back(static_cast<double>(body.capsules.size()));
    for (const Capsule& c : body.capsules) {
      key.insert(key.end(), {c.a.x(), c.a.y(), c.a.z(), c.b.x(), c.b.y(), c.b.z(), c.radius});
    }
  }
  return key;
}

}  // namespace

std::vector<std::pair<int, int>> RobotModel::SelfCollisionPairs() const {
  const std::vector<LinkBody> bodies = BodiesWithTool();
  // Every checker build asks (the cut motions build one per cut and slide): the pairs of the
  // last few robots are kept, keyed by their inputs (thread-safe).
  struct Entry {
    std::vector<double> key;
    std::vector<std::pair<int, int>> pairs;
  };
  static std::mutex cache_mutex;
  static std::deque<Entry> cache;  // most recent first, at most kCached
  constexpr size_t kCached = 8;
  std::vector<double> key = SelfPairsKey(bodies, limits);
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    for (const Entry& e : cache) {
      if (e.key == key) return e.pairs;
    }
  }
  // Sample configurations (fixed seed, portable generator) to find pairs whose distance never
  // changes, e.g. wrist 2 and a straight tool: their closest points are the joint 6 axis points
  // whatever q is. Such a pair can neither come into nor leave contact, and checking it would only
  // pin Clearance() to a constant.
  constexpr int kSamples = 48;
  std::mt19937_64 rng(20170401);
  std::vector<std::array<Eigen::Isometry3d, 7>> frames;
  for (int k = 0; k < kSamples; ++k) {
    Joints q;
    for (int i = 0; i < 6; ++i) {
      const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
      q[i] = limits.lower[i] + u * (limits.upper[i] - limits.lower[i]);
    }
    frames.push_back(LinkFrames(q));
  }
  auto distance = [&](const LinkBody& x, const LinkBody& y, const std::array<Eigen::Isometry3d, 7>& f) {
    double best = std::numeric_limits<double>::infinity();
    for (const Capsule& c : x.capsules) {
      for (const Capsule& d : y.capsules) {
        best = std::min(best, SegmentSegmentDistance(f[x.frame] * c.a, f[x.frame] * c.b,
                                                     f[y.frame] * d.a, f[y.frame] * d.b) -
                                  c.radius - d.radius);
      }
    }
    return best;
  };
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
    for (int j = i + 1; j < static_cast<int>(bodies.size()); ++j) {
      if (std::abs(bodies[i].frame - bodies[j].frame) < 2) continue;
      if (bodies[i].capsules.empty() || bodies[j].capsules.empty()) continue;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const auto& f : frames) {
        const double d = distance(bodies[i], bodies[j], f);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      if (hi - lo > 1e-9) pairs.emplace_back(i, j);
    }
  }
  std::lock_guard<std::mutex> lock(cache_mutex);
  cache.push_front({std::move(key), pairs});
  if (cache.size() > kCached) cache.pop_back();
  return pairs;
}

std::vector<LinkBody> RobotModel::BodiesWithTool() const {
  std::vector<LinkBody> bodies = links;
  if (!tool.capsules.empty()) {
    bodies.push_back(LinkBody{tool.name.empty() ? std::string("tool") : tool.name, 6,
                              tool.capsules});
  }
  return bodies;
}

absl::Status RobotModel::Validate() const {
  if (auto s = ValidatePose(platform_from_arm_base, "platform_from_arm_base"); !s.ok()) return s;
  if (auto s = limits.Validate(); !s.ok()) return s;
  if (auto s = ValidatePose(tool.flange_from_tcp, "tool.flange_from_tcp"); !s.ok()) return s;
  for (size_t i = 0; i < tool.capsules.size(); ++i) {
    if (auto s = ValidateCapsule(tool.capsules[i], absl::StrCat("tool.capsules[", i, "]"));
        !s.ok()) {
      return s;
    }
  }
  if (links.empty()) return absl::InvalidArgumentError("links: empty");
  for (size_t i = 0; i < links.size(); ++i) {
    const std::string what = absl::StrCat("links[", i, "] (", links[i].name, ")");
    if (links[i].frame < 0 || links[i].frame > 6) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": frame outside [0, 6]"));
    }
    for (size_t k = 0; k < links[i].capsules.size(); ++k) {
      if (auto s = ValidateCapsule(links[i].capsules[k], absl::StrCat(what, ".capsules[", k, "]"));
          !s.ok()) {
        return s;
      }
    }
  }
  return absl::OkStatus();
}

RobotModel DefaultUr5(const ToolGeometry& tool) {
  const DhParameters& dh = Ur5Dh();
  const double a2 = -dh.a[1], a3 = -dh.a[2], d1 = dh.d[0], d4 = dh.d[3], d5 = dh.d[4],
               d6 = dh.d[5];
  RobotModel robot;
  robot.platform_from_arm_base = DefaultPlatformFromArmBase();
  robot.limits.lower[2] = -M_PI;  // the elbow cannot pass through the upper arm
  robot.limits.upper[2] = M_PI;
  robot.tool = tool;
  auto cap = [](Eigen::Vector3d a, Eigen::Vector3d b, double r) { return Capsule{a, b, r}; };
  using V = Eigen::Vector3d;
  // Frame 0: the joint 1 housing, from the mounting flange up to the shoulder axis.
  robot.links.push_back({"base", 0, {cap(V(0, 0, 0), V(0, 0, d1), kBaseRadiusM)}});
  // Frame 1 (z = joint 2 axis through the shoulder): the shoulder housing out to the upper arm.
  robot.links.push_back({"shoulder", 1, {cap(V(0, 0, 0), V(0, 0, kShoulderOffsetM), kArmRadiusM)}});
  // Frame 2 (origin on the elbow axis; the shoulder axis at x = -a2 = 0.425): upper arm tube and
  // the elbow housing back to the forearm's plane.
  robot.links.push_back(
      {"upper_arm", 2,
       {cap(V(a2, 0, kShoulderOffsetM), V(0, 0, kShoulderOffsetM), kArmRadiusM),
        cap(V(0, 0, kShoulderOffsetM), V(0, 0, kForearmOffsetM), kArmRadiusM)}});
  // Frame 3 (origin on the wrist 1 axis; the elbow axis at x = -a3 = 0.39225): forearm tube and
  // the wrist 1 housing along the joint 4 axis out to d4.
  robot.links.push_back({"forearm", 3,
                         {cap(V(a3, 0, kForearmOffsetM), V(0, 0, kForearmOffsetM), kArmRadiusM),
                          cap(V(0, 0, kForearmOffsetM), V(0, 0, d4), kWristRadiusM)}});
  // Frame 4 (origin where the joint 4 and joint 5 axes meet; z = joint 5 axis): wrist 2 housing.
  robot.links.push_back({"wrist_2", 4, {cap(V(0, 0, 0), V(0, 0, d5), kWristRadiusM)}});
  // Frame 5 (origin on the joint 6 axis; z = joint 6 axis, flange at d6): wrist 3 to the flange.
  robot.links.push_back(
      {"wrist_3", 5, {cap(V(0, 0, 0), V(0, 0, d6 - kWrist3RadiusM), kWrist3RadiusM)}});
  return robot;
}

absl::Status PlatformGeometry::Validate() const {
  for (const auto& [value, name] :
       {std::pair{ground_z_m, "ground_z_m"}, std::pair{roof_z_m, "roof_z_m"},
        std::pair{camera_side_wall_y_m, "camera_side_wall_y_m"},
        std::pair{backdrop_y_m, "backdrop_y_m"}}) {
    if (!std::isfinite(value)) {
      return absl::InvalidArgumentError(absl::StrCat("platform: ", name, " is not finite"));
    }
  }
  if (!(roof_z_m > ground_z_m)) {
    return absl::InvalidArgumentError("platform: roof_z_m must be above ground_z_m");
  }
  if (!(backdrop_y_m > camera_side_wall_y_m)) {
    return absl::InvalidArgumentError(
        "platform: backdrop_y_m must be greater than camera_side_wall_y_m");
  }
  for (size_t i = 0; i < fixed_spheres.size(); ++i) {
    const Sphere& s = fixed_spheres[i];
    if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius < 0) {
      return absl::InvalidArgumentError(absl::StrCat(
          "platform: fixed_spheres[", i, "]: need finite centre and radius >= 0"));
    }
  }
  for (size_t i = 0; i < fixed_capsules.size(); ++i) {
    if (auto s = ValidateCapsule(fixed_capsules[i],
                                 absl::StrCat("platform: fixed_capsules[", i, "]"));
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

Capsule CameraBody(const Eigen::Vector3d& centre_in_platform,
                   const Eigen::Vector3d& axis_in_platform) {
  // Each camera's body (docs/plan.md "Collision checking"): a machine-vision camera of 0.03 x
  // 0.03 x 0.06 m with a lens of 0.03 m diameter and 0.05 m length in front of it, its centre of
  // projection anywhere in the lens, so body and lens lie between 0.11 m behind the centre and
  // 0.05 m in front of it, within 0.0212 m of the optical axis (the body's half diagonal). The
  // capsule reaches back 0.13 m to the camera-side wall (the bracket and cable) and pads the
  // body's edges by 0.024 m (the lens by 0.03 m).
  constexpr double kBehindM = 0.13, kAheadM = 0.05, kRadiusM = 0.045;
  const Eigen::Vector3d axis = axis_in_platform.normalized();
  return {centre_in_platform - kBehindM * axis, centre_in_platform + kAheadM * axis, kRadiusM};
}

namespace {

// sim/rig.h's default trinocular rig, hard-coded because workers do not depend on sim: an
// equilateral triangle of side 0.40 m centred at (0, -0.12, 1.05), cam0 lower left, cam1 lower
// right, cam2 above the middle, the lower pair aimed at kRigAim on the vine plane and cam2 at
// kApexAimUpM above it.
constexpr double kRigSide = 0.40, kRigY = -0.12, kRigHeight = 1.05, kApexAimUpM = 0.03;
const Eigen::Vector3d kRigAim(0.0, 0.80, 1.15);

struct NominalCamera {
  Eigen::Vector3d centre;
  Eigen::Vector3d aim;  // the point on the vine plane it looks at
};

std::vector<NominalCamera> NominalCameras() {
  const double circum = kRigSide / std::sqrt(3.0);  // centroid to vertex
  const Eigen::Vector3d apex_aim = kRigAim + Eigen::Vector3d(0, 0, kApexAimUpM);
  return {{Eigen::Vector3d(-kRigSide / 2, kRigY, kRigHeight - circum / 2), kRigAim},
          {Eigen::Vector3d(kRigSide / 2, kRigY, kRigHeight - circum / 2), kRigAim},
          {Eigen::Vector3d(0, kRigY, kRigHeight + circum), apex_aim}};
}

}  // namespace

PlatformGeometry DefaultPlatform() {
  PlatformGeometry platform;
  for (const NominalCamera& camera : NominalCameras()) {
    platform.fixed_capsules.push_back(CameraBody(camera.centre, camera.aim - camera.centre));
  }
  return platform;
}

absl::StatusOr<PlatformGeometry> PlatformAroundRig(const RigCalibration& rig) {
  if (absl::Status s = rig.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("calibration: ", s.message()));
  }
  // A calibration of another rig, or one with a frame or sign error, would move the capsules
  // away from the real cameras: each calibrated camera must lie near a camera of the platform's
  // design (a real rig is mounted within a few cm of it).
  for (const CameraCalibration& camera : rig.cameras) {
    double nearest = std::numeric_limits<double>::infinity();
    Eigen::Vector3d nominal_axis = Eigen::Vector3d::UnitY();
    for (const NominalCamera& nominal : NominalCameras()) {
      const double d = (camera.CentreInPlatform() - nominal.centre).norm();
      if (d < nearest) {
        nearest = d;
        nominal_axis = (nominal.aim - nominal.centre).normalized();
      }
    }
    if (nearest > kMaxCameraOffNominalM) {
      return absl::InvalidArgumentError(absl::StrCat(
          "calibration: camera '", camera.name, "' lies ", nearest,
          " m from every camera position of the platform's design (at most ",
          kMaxCameraOffNominalM, " m): a calibration of another rig, or a frame error?"));
    }
    // x_cam = R x_platform + t: the camera's z axis is R's last row in the platform frame.
    const Eigen::Vector3d axis = camera.rotation_camera_from_platform.row(2).transpose();
    const double angle_deg = std::acos(std::clamp(axis.dot(nominal_axis), -1.0, 1.0)) * 180 / M_PI;
    if (angle_deg > kMaxCameraTurnFromNominalDeg) {
      return absl::InvalidArgumentError(absl::StrCat(
          "calibration: camera '", camera.name, "' looks ", angle_deg,
          " degrees away from its direction in the platform's design (at most ",
          kMaxCameraTurnFromNominalDeg, "): a calibration of another rig, or a frame error?"));
    }
  }
  PlatformGeometry platform = DefaultPlatform();
  platform.fixed_capsules.clear();
  for (const CameraCalibration& camera : rig.cameras) {
    // x_cam = R x_platform + t: the camera's z axis is R's last row in the platform frame.
    platform.fixed_capsules.push_back(
        CameraBody(camera.CentreInPlatform(),
                   camera.rotation_camera_from_platform.row(2).transpose()));
  }
  return platform;
}

}  // namespace vb::plan
