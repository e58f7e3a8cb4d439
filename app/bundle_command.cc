// SPDX-License-Identifier: Apache-2.0
#include <iostream>

#include "app/commands.h"
#include "core/status_macros.h"
#include "nlohmann/json.hpp"
#include "workers/capture/bundle.h"

namespace vb::app {

absl::Status RunBundleInfo(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string dir, flags.RequiredString("bundle"));
  VB_RETURN_IF_ERROR(flags.Finish());
  VB_ASSIGN_OR_RETURN(const capture::CaptureBundle bundle, capture::ReadBundle(dir));
  nlohmann::json cameras = nlohmann::json::array();
  for (size_t i = 0; i < bundle.images.size(); ++i) {
    const CameraCalibration& cal = bundle.CalibrationOf(i);
    const Eigen::Vector3d centre = cal.CentreInPlatform();
    cameras.push_back({{"name", cal.name},
                       {"image", bundle.metadata.cameras[i].image},
                       {"pixel_format", std::string(PixelFormatName(bundle.images[i].format))},
                       {"width", bundle.images[i].width},
                       {"height", bundle.images[i].height},
                       {"fx", cal.camera_matrix(0, 0)},
                       {"centre_in_platform", {centre.x(), centre.y(), centre.z()}}});
  }
  const nlohmann::json out = {{"bundle", dir},
                              {"valid", true},
                              {"row", bundle.metadata.row},
                              {"vine_position_m", bundle.metadata.vine_position_m},
                              {"captured_at", bundle.metadata.captured_at},
                              {"cameras", cameras}};
  std::cout << out.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
