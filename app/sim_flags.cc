// SPDX-License-Identifier: Apache-2.0
#include "app/sim_flags.h"

#include "absl/strings/str_cat.h"
#include "core/image.h"
#include "core/status_macros.h"

namespace vb::app {

absl::StatusOr<SimStopFlags> ReadSimStopFlags(Flags& flags) {
  SimStopFlags out;
  VB_ASSIGN_OR_RETURN(const int64_t seed, flags.Int("seed", 1));
  VB_ASSIGN_OR_RETURN(const int64_t vine, flags.Int("vine", 0));
  if (seed < 0) return absl::InvalidArgumentError("--seed: must be >= 0");
  if (vine < -1000000 || vine > 1000000) {
    return absl::InvalidArgumentError("--vine: must be within +-1000000");
  }
  out.seed = static_cast<uint64_t>(seed);
  out.vine = static_cast<int>(vine);
  VB_ASSIGN_OR_RETURN(const int64_t noise_seed,
                      flags.Int("noise-seed", static_cast<int64_t>(out.seed * 1000003 + out.vine)));
  out.noise_seed = static_cast<uint64_t>(noise_seed);
  VB_ASSIGN_OR_RETURN(out.capture.render.pixel_format,
                      flags.Format("pixel-format", PixelFormat::kRgb8));
  VB_ASSIGN_OR_RETURN(out.capture.calibration_error_px, flags.Double("calibration-error-px", 0.0));
  VB_ASSIGN_OR_RETURN(const int64_t cameras, flags.Int("cameras", 3));
  out.capture.rig.camera_count = static_cast<int>(cameras);
  VB_ASSIGN_OR_RETURN(const bool no_neighbours, flags.Bool("no-neighbours", false));
  out.generator.neighbours = !no_neighbours;
  VB_ASSIGN_OR_RETURN(const bool no_noise, flags.Bool("no-noise", false));
  if (no_noise) {
    out.capture.render.read_noise_dn = 0.0;
    out.capture.render.shot_noise = 0.0;
  }
  VB_ASSIGN_OR_RETURN(out.capture.fiducials, flags.Bool("fiducials", out.capture.fiducials));
  VB_ASSIGN_OR_RETURN(out.capture.row, flags.String("row", absl::StrCat("sim-", out.seed)));
  VB_RETURN_IF_ERROR(out.generator.Validate());
  VB_RETURN_IF_ERROR(out.capture.Validate());
  return out;
}

}  // namespace vb::app
