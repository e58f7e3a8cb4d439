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

  // The calibration of metadata.cameras[i] (by name). Precondition: the bundle is consistent
  // (as every bundle ReadBundle returns and WriteBundle accepts); aborts otherwise.
  const CameraCalibration& CalibrationOf(size_t i) const;
};

// Writes `dir`/capture.json, calibration.yaml and the images (creating `dir` and any
// subdirectories named by image paths). Validates first and writes nothing if the bundle is
// inconsistent: metadata or calibration invalid, image count, pixel format or size (and byte
// count) disagreeing with metadata/calibration, a camera without calibration, two cameras sharing
// an image file. Each file is written to a temporary and renamed into place; capture.json comes
// last, so a directory holding capture.json holds a complete bundle (but a failed write may leave
// a partial bundle without capture.json, and overwriting an existing bundle is not atomic).
// INVALID_ARGUMENT for an inconsistent bundle; INTERNAL on I/O failure.
absl::Status WriteBundle(const std::string& dir, const CaptureBundle& bundle);

// Reads and validates a bundle directory. INVALID_ARGUMENT naming the file and field for: missing
// or truncated file, malformed JSON/YAML, unknown pixel format, a camera without calibration,
// image size or channel count that disagrees with the calibration/pixel format, non-finite or
// singular camera matrix, non-orthonormal rotation. NOT_FOUND if `dir` does not exist.
// Calibration entries may come in any order and may include cameras not in capture.json.
absl::StatusOr<CaptureBundle> ReadBundle(const std::string& dir);

// Reads / writes calibration.yaml alone (same validation, errors prefixed with the path).
// Reading: NOT_FOUND if the file does not exist; INVALID_ARGUMENT naming the camera and field for
// malformed YAML (with the line), a missing node, a node of the wrong type, a matrix of the wrong
// shape or with non-numeric data, and anything RigCalibration::Validate rejects. Matrices are
// !!opencv-matrix nodes of any numeric dt; distortion may be 1x5 or 5x1, translation 3x1 or 1x3.
// A missing "%YAML:1.0" directive is tolerated. Writing validates first (INVALID_ARGUMENT) and
// writes doubles with 17 significant digits, so a round trip is exact.
absl::StatusOr<RigCalibration> ReadCalibrationYaml(const std::string& path);
absl::Status WriteCalibrationYaml(const std::string& path, const RigCalibration& rig);

// Converts any supported image to rgb8: rgb8 is copied, mono8 becomes grey, Bayer mosaics are
// demosaiced with OpenCV's edge-aware (EA) method, honouring the GenICam pattern naming of
// PixelFormat. INVALID_ARGUMENT if the image's size and byte count disagree, or for a Bayer
// mosaic smaller than 2x2.
absl::StatusOr<Image> ToRgb(const Image& image);

// 8-bit PNG (1 or 3 channels) and 16-bit label PNG I/O. rgb8 is stored as an RGB PNG; mono8 and
// Bayer mosaics as greyscale PNGs. Writes go through a temporary file and a rename; INVALID_ARGUMENT
// for an image whose byte count disagrees with its size, INTERNAL on I/O failure.
// Reads: NOT_FOUND if the file does not exist; INVALID_ARGUMENT naming the file for a non-PNG,
// truncated or corrupt file, a bit depth other than 8 (16 for labels), or a channel count that
// disagrees with `format` (1 for labels).
absl::Status WritePng(const std::string& path, const Image& image);
absl::StatusOr<Image> ReadPng(const std::string& path, PixelFormat format);
absl::Status WriteLabelPng(const std::string& path, const LabelImage& labels);
absl::StatusOr<LabelImage> ReadLabelPng(const std::string& path);

}  // namespace vb::capture
