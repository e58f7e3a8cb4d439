// SPDX-License-Identifier: Apache-2.0
#include "sim/fiducials.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace vb::sim {

absl::Status FiducialLayoutOptions::Validate() const {
  if (!std::isfinite(backdrop_y_m)) return absl::InvalidArgumentError("fiducials.backdrop_y_m: not finite");
  if (!(std::isfinite(radius_m) && radius_m > 0.0 && radius_m <= 0.2)) {
    return absl::InvalidArgumentError(
        absl::StrCat("fiducials.radius_m: must be in (0, 0.2], is ", radius_m));
  }
  auto finite = [](const std::vector<double>& v) {
    for (double x : v) if (!std::isfinite(x)) return false;
    return true;
  };
  if (!finite(top_bottom_x_m)) return absl::InvalidArgumentError("fiducials.top_bottom_x_m: not finite");
  if (!finite(top_bottom_z_m)) return absl::InvalidArgumentError("fiducials.top_bottom_z_m: not finite");
  if (!finite(side_x_m)) return absl::InvalidArgumentError("fiducials.side_x_m: not finite");
  if (!finite(side_z_m)) return absl::InvalidArgumentError("fiducials.side_z_m: not finite");
  return absl::OkStatus();
}

absl::StatusOr<std::vector<Fiducial>> PlatformFiducials(const FiducialLayoutOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  std::vector<Fiducial> out;
  auto add = [&](double x, double z) {
    Fiducial f;
    f.name = absl::StrCat("fid", out.size());
    f.position_in_platform = Eigen::Vector3d(x, options.backdrop_y_m, z);
    f.radius_m = options.radius_m;
    out.push_back(std::move(f));
  };
  for (double z : options.top_bottom_z_m)
    for (double x : options.top_bottom_x_m) add(x, z);
  for (double x : options.side_x_m)
    for (double z : options.side_z_m) add(x, z);
  return out;
}

}  // namespace vb::sim
