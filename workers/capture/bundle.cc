// SPDX-License-Identifier: Apache-2.0
// Capture bundle directories: capture.json + calibration.yaml + one PNG per camera. The PNG and
// YAML halves live in bundle_png.cc and bundle_calibration.cc.
#include "workers/capture/bundle.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <unordered_set>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"
#include "workers/capture/bundle_internal.h"

namespace vb::capture {
namespace {

constexpr char kMetadataFile[] = "capture.json";
constexpr char kCalibrationFile[] = "calibration.yaml";

std::string SizeString(int width, int height) { return absl::StrCat(width, "x", height); }

// Cross-checks metadata, calibration and images before anything is written.
absl::Status CheckConsistent(const CaptureBundle& bundle) {
  VB_RETURN_IF_ERROR(bundle.metadata.Validate());
  VB_RETURN_IF_ERROR(bundle.calibration.Validate());
  const std::vector<CapturedCamera>& cameras = bundle.metadata.cameras;
  if (bundle.images.size() != cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("images: ", bundle.images.size(),
                                                   " images for ", cameras.size(), " cameras"));
  }
  std::unordered_set<std::string> files;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const CapturedCamera& cam = cameras[i];
    if (cam.image == kMetadataFile || cam.image == kCalibrationFile ||
        !files.insert(cam.image).second) {
      return absl::InvalidArgumentError(absl::StrCat(
          "cameras[", i, "] (", cam.name, ").image: '", cam.image,
          "' clashes with another file of the bundle"));
    }
    const std::optional<size_t> k = bundle.calibration.IndexOf(cam.name);
    if (!k) {
      return absl::InvalidArgumentError(absl::StrCat("cameras[", i, "]: camera '", cam.name,
                                                     "' has no calibration"));
    }
    const CameraCalibration& calib = bundle.calibration.cameras[*k];
    const Image& image = bundle.images[i];
    if (image.format != cam.pixel_format) {
      return absl::InvalidArgumentError(absl::StrCat(
          "images[", i, "] (", cam.name, "): pixel format ",
          std::string(PixelFormatName(image.format)), " but metadata says ",
          std::string(PixelFormatName(cam.pixel_format))));
    }
    const size_t bytes = static_cast<size_t>(std::max(image.width, 0)) *
                         static_cast<size_t>(std::max(image.height, 0)) * image.channels();
    if (image.width != calib.image_width || image.height != calib.image_height ||
        image.data.size() != bytes) {
      return absl::InvalidArgumentError(absl::StrCat(
          "images[", i, "] (", cam.name, "): image is ", SizeString(image.width, image.height),
          " with ", image.data.size(), " bytes, calibration says ",
          SizeString(calib.image_width, calib.image_height)));
    }
  }
  return absl::OkStatus();
}

absl::Status EnsureDirectory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir, ec)) {
    return absl::InternalError(
        absl::StrCat(dir.string(), ": cannot create directory: ", ec.message()));
  }
  return absl::OkStatus();
}

}  // namespace

const CameraCalibration& CaptureBundle::CalibrationOf(size_t i) const {
  const std::optional<size_t> k =
      i < metadata.cameras.size() ? calibration.IndexOf(metadata.cameras[i].name) : std::nullopt;
  if (!k) {
    // A programmer error: bundles from ReadBundle, and those WriteBundle accepts, always match.
    std::fprintf(stderr, "CaptureBundle::CalibrationOf(%zu): no calibration for that camera\n", i);
    std::abort();
  }
  return calibration.cameras[*k];
}

absl::Status WriteBundle(const std::string& dir, const CaptureBundle& bundle) {
  if (absl::Status s = CheckConsistent(bundle); !s.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat(dir, ": inconsistent bundle: ", std::string(s.message())));
  }
  const std::filesystem::path root(dir);
  VB_RETURN_IF_ERROR(EnsureDirectory(root));
  for (size_t i = 0; i < bundle.images.size(); ++i) {
    const std::filesystem::path file = root / bundle.metadata.cameras[i].image;
    VB_RETURN_IF_ERROR(EnsureDirectory(file.parent_path()));
    VB_RETURN_IF_ERROR(WritePng(file.string(), bundle.images[i]));
  }
  VB_RETURN_IF_ERROR(WriteCalibrationYaml((root / kCalibrationFile).string(), bundle.calibration));
  // capture.json last: a reader that finds it finds the rest of the bundle complete.
  return WriteJsonFile((root / kMetadataFile).string(), CaptureMetadataToJson(bundle.metadata));
}

absl::StatusOr<CaptureBundle> ReadBundle(const std::string& dir) {
  const std::filesystem::path root(dir);
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(root, ec);
  if (st.type() == std::filesystem::file_type::not_found) {
    return absl::NotFoundError(absl::StrCat(dir, ": no such capture bundle directory"));
  }
  if (st.type() != std::filesystem::file_type::directory) {
    return absl::InvalidArgumentError(absl::StrCat(dir, ": not a directory"));
  }

  CaptureBundle bundle;
  const std::string metadata_path = (root / kMetadataFile).string();
  absl::StatusOr<nlohmann::json> json = ReadJsonFile(metadata_path);
  if (!json.ok()) return internal::AsInvalidArgument(json.status());
  absl::StatusOr<CaptureMetadata> metadata = CaptureMetadataFromJson(*json);
  if (!metadata.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat(metadata_path, ": ", std::string(metadata.status().message())));
  }
  bundle.metadata = *std::move(metadata);

  absl::StatusOr<RigCalibration> calibration =
      ReadCalibrationYaml((root / kCalibrationFile).string());
  if (!calibration.ok()) return internal::AsInvalidArgument(calibration.status());
  bundle.calibration = *std::move(calibration);

  for (size_t i = 0; i < bundle.metadata.cameras.size(); ++i) {
    const CapturedCamera& cam = bundle.metadata.cameras[i];
    const std::optional<size_t> k = bundle.calibration.IndexOf(cam.name);
    if (!k) {
      return absl::InvalidArgumentError(
          absl::StrCat(metadata_path, ": cameras[", i, "]: camera '", cam.name,
                       "' has no entry in ", kCalibrationFile));
    }
    const CameraCalibration& calib = bundle.calibration.cameras[*k];
    absl::StatusOr<Image> image = internal::ReadPngOfSize(
        (root / cam.image).string(), cam.pixel_format, calib.image_width, calib.image_height);
    if (!image.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("camera '", cam.name, "': ",
                                                     std::string(image.status().message())));
    }
    bundle.images.push_back(*std::move(image));
  }
  return bundle;
}

}  // namespace vb::capture
