// SPDX-License-Identifier: Apache-2.0
#include "sim/rig.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

absl::Status Invalid(const std::string& field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("rig options: ", field, " ", why));
}

// Radial distortion factor of OpenCV's model at undistorted normalised radius r.
double RadialFactor(const RigOptions& o, double r) {
  const double r2 = r * r;
  return 1.0 + r2 * (o.k1 + r2 * (o.k2 + r2 * o.k3));
}

// Where the radial model folds back (d r_d / d r <= 0): the edge of the region where pixels have
// a unique ray. Scans up to r = 4 (~76 deg). Returns {undistorted r, distorted r_d} there.
std::pair<double, double> Fold(const RigOptions& o) {
  double best = 0.0;
  double r_best = 0.0;
  for (double r = 1e-3; r <= 4.0; r += 1e-3) {
    const double rd = r * RadialFactor(o, r);
    if (rd <= best) break;
    best = rd;
    r_best = r;
  }
  return {r_best, best};
}

// Portable random numbers: only the raw output of mt19937_64 is specified by the standard, so
// uniforms and normals are derived here rather than with std distributions.
class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  // Irwin-Hall approximation of a standard normal (sum of 12 uniforms); plenty for perturbations.
  double Normal() {
    double sum = 0.0;
    for (int i = 0; i < 12; ++i) sum += Uniform();
    return sum - 6.0;
  }

 private:
  std::mt19937_64 engine_;
};

struct Perturbation {
  double focal_rel = 0.0;          // relative focal-length change
  Eigen::Vector2d principal = Eigen::Vector2d::Zero();  // px
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();   // rad, rotation vector in camera frame
};

CameraCalibration Apply(const CameraCalibration& camera, const Perturbation& p, double scale) {
  CameraCalibration out = camera;
  out.camera_matrix(0, 0) *= 1.0 + scale * p.focal_rel;
  out.camera_matrix(1, 1) *= 1.0 + scale * p.focal_rel;
  out.camera_matrix(0, 2) += scale * p.principal.x();
  out.camera_matrix(1, 2) += scale * p.principal.y();
  const Eigen::Vector3d w = scale * p.rotation;
  Eigen::Matrix3d delta = Eigen::Matrix3d::Identity();
  if (w.norm() > 0.0) delta = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  // Rotate about the camera centre so only the orientation is wrong, as a bumped mount would be.
  const Eigen::Vector3d centre = camera.CentreInPlatform();
  out.rotation_camera_from_platform = delta * camera.rotation_camera_from_platform;
  out.translation_camera_from_platform = -out.rotation_camera_from_platform * centre;
  return out;
}

}  // namespace

absl::Status RigOptions::Validate() const {
  if (camera_count < 1 || camera_count > 4) {
    return Invalid("camera_count", absl::StrCat("must be 1, 2, 3 or 4, is ", camera_count));
  }
  if (image_width < 16 || image_width > 16384) {
    return Invalid("image_width", absl::StrCat("must be in [16, 16384], is ", image_width));
  }
  if (image_height < 16 || image_height > 16384) {
    return Invalid("image_height", absl::StrCat("must be in [16, 16384], is ", image_height));
  }
  if (!(horizontal_fov_deg > 10.0 && horizontal_fov_deg < 170.0)) {
    return Invalid("horizontal_fov_deg", absl::StrCat("must be in (10, 170), is ", horizontal_fov_deg));
  }
  if (!(baseline_m > 0.0 && baseline_m <= 2.0)) {
    return Invalid("baseline_m", absl::StrCat("must be in (0, 2], is ", baseline_m));
  }
  if (!(std::isfinite(rig_height_m) && rig_height_m > 0.05)) {
    return Invalid("rig_height_m", absl::StrCat("must be finite and > 0.05, is ", rig_height_m));
  }
  if (!(std::isfinite(distance_to_vine_plane_m) && distance_to_vine_plane_m > 0.05)) {
    return Invalid("distance_to_vine_plane_m",
                   absl::StrCat("must be finite and > 0.05, is ", distance_to_vine_plane_m));
  }
  if (!(std::isfinite(rig_y_m) && std::abs(rig_y_m) <= 1.0)) {
    return Invalid("rig_y_m", absl::StrCat("must be finite and within [-1, 1], is ", rig_y_m));
  }
  if (!(std::isfinite(aim_below_rig_m) && std::abs(aim_below_rig_m) <= rig_height_m)) {
    return Invalid("aim_below_rig_m",
                   absl::StrCat("must be finite and within +-rig_height_m, is ", aim_below_rig_m));
  }
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"apex_aim_up_m", apex_aim_up_m},
        std::pair<const char*, double>{"pair_aim_up_m", pair_aim_up_m}}) {
    if (!(std::isfinite(value) && std::abs(value) <= rig_height_m)) {
      return Invalid(name, absl::StrCat("must be finite and within +-rig_height_m, is ", value));
    }
  }
  if (!(std::isfinite(apex_raise_m) && apex_raise_m >= 0.0 && apex_raise_m <= 1.0)) {
    return Invalid("apex_raise_m",
                   absl::StrCat("must be finite and within [0, 1], is ", apex_raise_m));
  }
  if (!(upper_pair_side_m > 0.0 && upper_pair_side_m <= 2.0)) {
    return Invalid("upper_pair_side_m",
                   absl::StrCat("must be in (0, 2], is ", upper_pair_side_m));
  }
  const std::pair<const char*, double> coefficients[] = {
      {"k1", k1}, {"k2", k2}, {"p1", p1}, {"p2", p2}, {"k3", k3}};
  for (const auto& [name, value] : coefficients) {
    if (!std::isfinite(value)) return Invalid(name, "is not finite");
  }
  return absl::OkStatus();
}

Eigen::Matrix3d LookAlong(const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

RigOptions NarrowRigOptions() {
  RigOptions o;
  o.baseline_m = 0.29;
  o.apex_aim_up_m = 0.0;
  return o;
}

absl::StatusOr<RigCalibration> MakeRig(const RigOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  const double half_w = 0.5 * options.image_width;
  const double half_h = 0.5 * options.image_height;

  const double edge_r = std::tan(0.5 * options.horizontal_fov_deg * kPi / 180.0);
  const auto [fold_r, fold_rd] = Fold(options);
  const double edge_rd = edge_r * RadialFactor(options, edge_r);
  // The few-pixel principal point offsets below move a corner at most this far out.
  const double corner_px = std::hypot(half_w + 6.0, half_h + 6.0);
  double fx = edge_rd > 0.0 ? half_w / edge_rd : 0.0;
  const double corner_limit = 0.97 * fold_rd;
  if (edge_r >= fold_r || corner_px / fx > corner_limit) {
    fx = corner_px / corner_limit;
  }
  if (!(fx > 0.0) || !std::isfinite(fx) || fold_rd < 1e-3) {
    return Invalid("k1", "distortion (k1, k2, k3) leaves no invertible region for the image");
  }

  const double s = options.baseline_m;
  std::vector<Eigen::Vector3d> centres;
  switch (options.camera_count) {
    case 1:
      centres = {{0.0, 0.0, 0.0}};
      break;
    case 2:
      centres = {{-0.5 * s, 0.0, 0.0}, {0.5 * s, 0.0, 0.0}};
      break;
    default: {
      // Centroid to the side of the pair; the third camera is twice as far on the other side.
      const double inradius = s / (2.0 * std::sqrt(3.0));
      const double pair = options.apex_up ? -inradius : inradius;
      const double apex = -2.0 * pair + (options.apex_up ? 1.0 : -1.0) * options.apex_raise_m;
      centres = {{-0.5 * s, 0.0, pair}, {0.5 * s, 0.0, pair}, {0.0, 0.0, apex}};
      if (options.camera_count == 4) {
        const double u = 0.5 * options.upper_pair_side_m;
        centres[2] = {-u, 0.0, apex};
        centres.push_back({u, 0.0, apex});
      }
    }
  }
  const Eigen::Vector3d rig_centre(0.0, options.rig_y_m, options.rig_height_m);
  const Eigen::Vector3d target(0.0, options.rig_y_m + options.distance_to_vine_plane_m,
                               options.rig_height_m - options.aim_below_rig_m);

  RigCalibration rig;
  for (int i = 0; i < options.camera_count; ++i) {
    CameraCalibration c;
    c.name = absl::StrCat("cam", i);
    c.image_width = options.image_width;
    c.image_height = options.image_height;
    // Real lenses are never centred exactly; a fixed per-camera offset keeps code honest about cx.
    const double offset_x[] = {3.2, -2.7, 1.4, -1.8};
    const double offset_y[] = {-2.4, 1.9, 2.8, -3.1};
    c.camera_matrix << fx, 0.0, 0.5 * (options.image_width - 1) + offset_x[i], 0.0, fx,
        0.5 * (options.image_height - 1) + offset_y[i], 0.0, 0.0, 1.0;
    c.distortion = {options.k1, options.k2, options.p1, options.p2, options.k3};
    const Eigen::Vector3d centre = rig_centre + centres[i];
    const bool apex = options.camera_count >= 3 && i >= 2;
    const Eigen::Vector3d aim =
        target + Eigen::Vector3d::UnitZ() * (apex ? options.apex_aim_up_m : options.pair_aim_up_m);
    c.rotation_camera_from_platform =
        options.toe_in ? LookAlong(aim - centre) : LookAlong(Eigen::Vector3d::UnitY());
    c.translation_camera_from_platform = -c.rotation_camera_from_platform * centre;
    rig.cameras.push_back(std::move(c));
  }
  if (absl::Status st = rig.Validate(); !st.ok()) return st;
  return rig;
}

double ReprojectionRmsPx(const CameraCalibration& a, const CameraCalibration& b, double depth_m) {
  const Eigen::Vector3d centre = a.CentreInPlatform();
  const Eigen::Vector3d axis = a.rotation_camera_from_platform.row(2).transpose();
  double sum = 0.0;
  int count = 0;
  constexpr int kGrid = 9;
  for (int iy = 0; iy < kGrid; ++iy) {
    for (int ix = 0; ix < kGrid; ++ix) {
      // Stay inside the central 90% of the image, where the lens model is well conditioned.
      const Eigen::Vector2d uv((0.05 + 0.9 * ix / (kGrid - 1)) * (a.image_width - 1),
                               (0.05 + 0.9 * iy / (kGrid - 1)) * (a.image_height - 1));
      const Eigen::Vector3d ray = a.RayInPlatform(uv);
      const Eigen::Vector3d p = centre + ray * (depth_m / ray.dot(axis));
      const auto pa = a.Project(p);
      const auto pb = b.Project(p);
      if (!pa || !pb) continue;
      sum += (*pa - *pb).squaredNorm();
      ++count;
    }
  }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

RigCalibration PerturbCalibration(const RigCalibration& rig, double error_px, uint64_t seed) {
  if (!(error_px > 0.0) || !std::isfinite(error_px)) return rig;
  RigCalibration out = rig;
  Rng rng(seed);
  for (CameraCalibration& camera : out.cameras) {
    const double fx = camera.camera_matrix(0, 0);
    // Draw a direction in parameter space with each effect contributing comparably at unit
    // scale (~1 px each), then scale the whole perturbation to the requested RMS.
    Perturbation p;
    p.focal_rel = rng.Normal() / (0.5 * camera.image_width);
    p.principal = Eigen::Vector2d(rng.Normal(), rng.Normal());
    p.rotation = Eigen::Vector3d(rng.Normal(), rng.Normal(), 0.5 * rng.Normal()) / fx;
    double scale = 1.0;
    // The displacement is nearly linear in the scale; two secant-style corrections suffice.
    for (int it = 0; it < 3; ++it) {
      const double rms = ReprojectionRmsPx(camera, Apply(camera, p, scale));
      if (rms <= 1e-12) break;
      scale *= error_px / rms;
    }
    camera = Apply(camera, p, scale);
  }
  return out;
}

}  // namespace vb::sim
