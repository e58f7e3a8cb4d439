// SPDX-License-Identifier: Apache-2.0
// Flags shared by the commands that simulate a stop (sim render, capture --source sim).
#pragma once

#include <cstdint>

#include "absl/status/statusor.h"
#include "app/flags.h"
#include "sim/vine_generator.h"
#include "workers/capture/sim_capture.h"

namespace vb::app {

struct SimStopFlags {
  uint64_t seed = 0;         // --seed: the vineyard
  int vine = 0;              // --vine: the vine index along the row
  uint64_t noise_seed = 0;   // --noise-seed (default derived from seed and vine)
  sim::VineGeneratorOptions generator;
  capture::SimCaptureOptions capture;
};

// Reads --seed, --vine, --noise-seed, --pixel-format, --calibration-error-px, --cameras,
// --no-neighbours, --no-noise, --fiducials (true/false), --row.
absl::StatusOr<SimStopFlags> ReadSimStopFlags(Flags& flags);

}  // namespace vb::app
