// SPDX-License-Identifier: Apache-2.0
#include "core/capture_metadata.h"

#include <cmath>
#include <ctime>
#include <unordered_set>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb {

absl::Status CaptureMetadata::Validate() const {
  if (!std::isfinite(vine_position_m)) {
    return absl::InvalidArgumentError("vine_position_m: not finite");
  }
  if (cameras.empty()) return absl::InvalidArgumentError("cameras: empty");
  std::unordered_set<std::string> names;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const CapturedCamera& c = cameras[i];
    const std::string what = absl::StrCat("cameras[", i, "]");
    if (c.name.empty()) return absl::InvalidArgumentError(what + ".name: empty");
    if (!names.insert(c.name).second) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".name: duplicate '", c.name, "'"));
    }
    if (c.image.empty() || c.image.front() == '/' || c.image.find("..") != std::string::npos) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ".image: '", c.image, "' must be a file name inside the bundle"));
    }
  }
  return absl::OkStatus();
}

nlohmann::json CaptureMetadataToJson(const CaptureMetadata& meta) {
  nlohmann::json cameras = nlohmann::json::array();
  for (const CapturedCamera& c : meta.cameras) {
    cameras.push_back({{"name", c.name},
                       {"image", c.image},
                       {"pixel_format", std::string(PixelFormatName(c.pixel_format))}});
  }
  return {{"format", kCaptureFormat},
          {"row", meta.row},
          {"vine_position_m", meta.vine_position_m},
          {"captured_at", meta.captured_at},
          {"cameras", cameras}};
}

absl::StatusOr<CaptureMetadata> CaptureMetadataFromJson(const nlohmann::json& j) {
  VB_RETURN_IF_ERROR(CheckFormat(j, kCaptureFormat));
  CaptureMetadata meta;
  VB_ASSIGN_OR_RETURN(meta.row, StringField(j, "row"));
  VB_ASSIGN_OR_RETURN(meta.vine_position_m, NumberField(j, "vine_position_m"));
  VB_ASSIGN_OR_RETURN(meta.captured_at, StringField(j, "captured_at"));
  VB_ASSIGN_OR_RETURN(const nlohmann::json* cameras, Field(j, "cameras"));
  if (!cameras->is_array()) return absl::InvalidArgumentError("cameras: not an array");
  for (size_t i = 0; i < cameras->size(); ++i) {
    const nlohmann::json& c = (*cameras)[i];
    const std::string what = absl::StrCat("cameras[", i, "].");
    CapturedCamera cam;
    auto name = StringField(c, "name");
    if (!name.ok()) return absl::InvalidArgumentError(what + std::string(name.status().message()));
    cam.name = *name;
    auto image = StringField(c, "image");
    if (!image.ok()) return absl::InvalidArgumentError(what + std::string(image.status().message()));
    cam.image = *image;
    auto format_name = StringField(c, "pixel_format");
    if (!format_name.ok()) {
      return absl::InvalidArgumentError(what + std::string(format_name.status().message()));
    }
    auto format = ParsePixelFormat(*format_name);
    if (!format.ok()) return absl::InvalidArgumentError(what + std::string(format.status().message()));
    cam.pixel_format = *format;
    meta.cameras.push_back(std::move(cam));
  }
  VB_RETURN_IF_ERROR(meta.Validate());
  return meta;
}

std::string UtcNowIso8601() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

}  // namespace vb
