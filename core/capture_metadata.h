// SPDX-License-Identifier: Apache-2.0
// The capture bundle's metadata, capture.json, format "vinebot.capture.v1" (ARCHITECTURE.md).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/image.h"
#include "nlohmann/json.hpp"

namespace vb {

inline constexpr char kCaptureFormat[] = "vinebot.capture.v1";

struct CapturedCamera {
  std::string name;       // matches a camera of calibration.yaml
  std::string image;      // file name inside the bundle directory, e.g. "cam0.png"
  PixelFormat pixel_format = PixelFormat::kRgb8;
};

struct CaptureMetadata {
  std::string row;               // vineyard row name
  double vine_position_m = 0.0;  // platform position along the row
  std::string captured_at;       // ISO 8601 UTC, e.g. "2026-07-14T09:12:03Z"
  std::vector<CapturedCamera> cameras;

  // INVALID_ARGUMENT naming the field: no cameras, empty or duplicate names, image names that
  // are empty, absolute or contain "..", non-finite position.
  absl::Status Validate() const;
};

nlohmann::json CaptureMetadataToJson(const CaptureMetadata& meta);
absl::StatusOr<CaptureMetadata> CaptureMetadataFromJson(const nlohmann::json& json);

// Current UTC time as ISO 8601 with seconds ("2026-07-14T09:12:03Z").
std::string UtcNowIso8601();

}  // namespace vb
