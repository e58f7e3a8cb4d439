// SPDX-License-Identifier: Apache-2.0
// Capture bundles, format "vinebot.capture.v1" (ARCHITECTURE.md): a directory with capture.json,
// calibration.yaml (OpenCV FileStorage) and one 8-bit PNG per camera. Import validates everything
// and names the problem; it never crashes on bad files. Thread-safe (no shared state).
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/capture_metadata.h"
#include "core/image.h"

namespace vb::capture {

struct CaptureBundle {
  CaptureMetadata metadata;
  RigCalibration calibration;
  // One image per metadata.cameras entry, same order, in the stored pixel format (Bayer images
  // stay raw mosaics; use ToRgb to demosaic).
  std::vector<Image> images;

  // The calibration of metadata.cameras[i] (by name).
  const CameraCalibration& CalibrationOf(size_t i) const;
};

// Writes `dir`/capture.json, calibration.yaml and the images (creating `dir`). Validates first.
// INVALID_ARGUMENT for an inconsistent bundle; INTERNAL on I/O failure.
absl::Status WriteBundle(const std::string& dir, const CaptureBundle& bundle);

// Reads and validates a bundle directory. INVALID_ARGUMENT naming the file and field for: missing
// or truncated file, malformed JSON/YAML, unknown pixel format, a camera without calibration,
// image size or channel count that disagrees with the calibration/pixel format, non-finite or
// singular camera matrix, non-orthonormal rotation. NOT_FOUND if `dir` does not exist.
absl::StatusOr<CaptureBundle> ReadBundle(const std::string& dir);

// Reads / writes calibration.yaml alone (same validation, errors prefixed with the path).
absl::StatusOr<RigCalibration> ReadCalibrationYaml(const std::string& path);
absl::Status WriteCalibrationYaml(const std::string& path, const RigCalibration& rig);

// Converts any supported image to rgb8, demosaicing Bayer mosaics (edge-aware, OpenCV).
absl::StatusOr<Image> ToRgb(const Image& image);

// 8-bit PNG (1 or 3 channels) and 16-bit label PNG I/O.
absl::Status WritePng(const std::string& path, const Image& image);
absl::StatusOr<Image> ReadPng(const std::string& path, PixelFormat format);
absl::Status WriteLabelPng(const std::string& path, const LabelImage& labels);
absl::StatusOr<LabelImage> ReadLabelPng(const std::string& path);

}  // namespace vb::capture
