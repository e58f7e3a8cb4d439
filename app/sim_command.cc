// SPDX-License-Identifier: Apache-2.0
#include <iostream>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "app/sim_flags.h"
#include "core/status_macros.h"
#include "sim/vine_generator.h"
#include "workers/capture/sim_capture.h"

namespace vb::app {

absl::Status RunSimRender(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const SimStopFlags stop, ReadSimStopFlags(flags));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  VB_RETURN_IF_ERROR(flags.Finish());

  VB_ASSIGN_OR_RETURN(const sim::Scene scene,
                      sim::GenerateScene(stop.seed, stop.vine, stop.generator));
  VB_ASSIGN_OR_RETURN(const capture::SimCapture capture,
                      capture::RenderSimCapture(scene, stop.capture, stop.noise_seed));
  VB_RETURN_IF_ERROR(capture::WriteSimCapture(out, capture));
  std::cout << absl::StrCat("wrote simulated stop (seed ", stop.seed, ", vine ", stop.vine, ", ",
                            capture.bundle.images.size(), " cameras, ", scene.vine.canes.size(),
                            " canes) to ", out, "\n");
  return absl::OkStatus();
}

}  // namespace vb::app
