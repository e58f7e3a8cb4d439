// SPDX-License-Identifier: Apache-2.0
// The JSON summary of one reconstruction that `vinebot reconstruct` and `vinebot bench
// reconstruct` print: counts, per-step timings, and why a model is empty.
#pragma once

#include "nlohmann/json.hpp"
#include "workers/reconstruct/reconstruct.h"

namespace vb::app {

nlohmann::json TimingsToJson(const reconstruct::StageTimings& t);
nlohmann::json ReconstructReport(const reconstruct::ReconstructResult& result);

}  // namespace vb::app
