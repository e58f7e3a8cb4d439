// SPDX-License-Identifier: Apache-2.0
#include "sim/vine_generator.h"

#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "sim/trellis.h"
#include "sim/vine_plant.h"

namespace vb::sim {
namespace {

absl::Status Invalid(const char* field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("VineGeneratorOptions.", field, ": ", why));
}

absl::Status CheckPositive(const char* field, double value) {
  if (!std::isfinite(value) || value <= 0.0) {
    return Invalid(field, absl::StrCat("must be finite and > 0, is ", value));
  }
  return absl::OkStatus();
}

absl::Status CheckRange(const char* min_field, double min, const char* max_field, double max) {
  if (absl::Status s = CheckPositive(min_field, min); !s.ok()) return s;
  if (absl::Status s = CheckPositive(max_field, max); !s.ok()) return s;
  if (min > max) {
    return Invalid(min_field, absl::StrCat("is ", min, ", greater than ", max_field, " ", max));
  }
  return absl::OkStatus();
}

absl::Status CheckCountRange(const char* min_field, int min, int min_allowed,
                             const char* max_field, int max, int max_allowed) {
  if (min < min_allowed) return Invalid(min_field, absl::StrCat("must be >= ", min_allowed, ", is ", min));
  if (max > max_allowed) return Invalid(max_field, absl::StrCat("must be <= ", max_allowed, ", is ", max));
  if (min > max) {
    return Invalid(min_field, absl::StrCat("is ", min, ", greater than ", max_field, " ", max));
  }
  return absl::OkStatus();
}

// Scene lights: the rig's four LED flashes, left/right of the cameras, low and high. Each is
// half the reference intensity, so the pair facing a point gives about the reference exposure.
std::vector<Light> RigLights() {
  std::vector<Light> lights;
  for (double z : {0.7, 1.4}) {
    for (double x : {-0.3, 0.3}) lights.push_back({Eigen::Vector3d(x, 0.05, z), 0.5});
  }
  return lights;
}

}  // namespace

absl::Status VineGeneratorOptions::Validate() const {
#define VB_CHECK_OK(expr)                    \
  if (absl::Status s = (expr); !s.ok()) return s
  VB_CHECK_OK(CheckPositive("vine_spacing_m", vine_spacing_m));
  VB_CHECK_OK(CheckPositive("vine_plane_y_m", vine_plane_y_m));
  VB_CHECK_OK(CheckRange("trunk_height_min_m", trunk_height_min_m, "trunk_height_max_m",
                         trunk_height_max_m));
  VB_CHECK_OK(CheckRange("trunk_diameter_min_m", trunk_diameter_min_m, "trunk_diameter_max_m",
                         trunk_diameter_max_m));
  VB_CHECK_OK(CheckCountRange("canes_min", canes_min, 1, "canes_max", canes_max, 200));
  if (!(fork_probability >= 0.0 && fork_probability <= 1.0)) {
    return Invalid("fork_probability", absl::StrCat("must be in [0, 1], is ", fork_probability));
  }
  VB_CHECK_OK(CheckRange("cane_length_min_m", cane_length_min_m, "cane_length_max_m",
                         cane_length_max_m));
  if (cane_length_max_m > 10.0) {
    return Invalid("cane_length_max_m", absl::StrCat("must be <= 10, is ", cane_length_max_m));
  }
  VB_CHECK_OK(CheckRange("cane_diameter_min_m", cane_diameter_min_m, "cane_diameter_max_m",
                         cane_diameter_max_m));
  VB_CHECK_OK(CheckCountRange("old_spurs_min", old_spurs_min, 0, "old_spurs_max", old_spurs_max, 50));
  VB_CHECK_OK(CheckPositive("head_radius_m", head_radius_m));
  VB_CHECK_OK(CheckRange("fruiting_wire_min_m", fruiting_wire_min_m, "fruiting_wire_max_m",
                         fruiting_wire_max_m));
  VB_CHECK_OK(CheckCountRange("foliage_wires_min", foliage_wires_min, 0, "foliage_wires_max",
                              foliage_wires_max, 10));
  VB_CHECK_OK(CheckPositive("wire_radius_m", wire_radius_m));
  VB_CHECK_OK(CheckPositive("post_spacing_m", post_spacing_m));
  VB_CHECK_OK(CheckPositive("post_radius_m", post_radius_m));
  VB_CHECK_OK(CheckPositive("post_height_m", post_height_m));
  if (post_height_m <= fruiting_wire_max_m) {
    return Invalid("post_height_m", absl::StrCat("must exceed fruiting_wire_max_m ",
                                                 fruiting_wire_max_m, ", is ", post_height_m));
  }
  VB_CHECK_OK(CheckPositive("backdrop_y_m", backdrop_y_m));
  if (backdrop_y_m <= vine_plane_y_m) {
    return Invalid("backdrop_y_m", absl::StrCat("must be behind vine_plane_y_m ", vine_plane_y_m,
                                                ", is ", backdrop_y_m));
  }
#undef VB_CHECK_OK
  return absl::OkStatus();
}

absl::StatusOr<Scene> GenerateScene(uint64_t seed, int vine_index,
                                    const VineGeneratorOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  const TrellisRow row = MakeTrellisRow(seed, options);
  // The platform stops with its origin at the vine's nominal row position; the vine's own jitter
  // is what the rig sees as an offset from x = 0.
  const double origin_x_row = vine_index * options.vine_spacing_m;

  Scene scene;
  scene.seed = seed;
  scene.vine_index = vine_index;
  VinePlant plant = GrowVine(seed, vine_index, options, row);
  scene.vine_position_m = plant.position_m;
  scene.vine = std::move(plant.model);
  ShiftModelX(-origin_x_row, &scene.vine);
  AddTrellisToModel(row, origin_x_row, options, &scene.vine);
  if (options.neighbours) {
    for (int k : {vine_index - 1, vine_index + 1}) {
      VinePlant neighbour = GrowVine(seed, k, options, row);
      ShiftModelX(-origin_x_row, &neighbour.model);
      scene.neighbours.push_back(std::move(neighbour.model));
    }
  }
  scene.backdrop_y_m = options.backdrop_y_m;
  scene.ground_z_m = 0.0;
  scene.lights = RigLights();
  // A generator bug must not reach the pipeline as ground truth.
  if (absl::Status s = scene.vine.Validate(); !s.ok()) {
    return absl::InternalError(absl::StrCat("generated vine is malformed: ",
                                            std::string(s.message())));
  }
  return scene;
}

}  // namespace vb::sim
