// SPDX-License-Identifier: Apache-2.0
// File helpers shared by the capture bundle sources (bundle*.cc). Internal to vb_capture: not
// part of the bundle API. OpenCV-free.
#pragma once

#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/image.h"

namespace vb::capture::internal {

// Reads a whole file into memory. NOT_FOUND naming the path if it does not exist;
// INVALID_ARGUMENT if it is not a regular file or cannot be read.
absl::StatusOr<std::string> ReadFileBytes(const std::string& path);

// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so a
// reader never sees a half-written file. INTERNAL naming the path on I/O failure.
absl::Status WriteFileAtomically(const std::string& path, std::string_view bytes);

// ReadPng that also requires the image to be width x height, checked from the PNG header before
// decoding (so a corrupt header cannot make us allocate gigabytes). INVALID_ARGUMENT naming both
// sizes otherwise.
absl::StatusOr<Image> ReadPngOfSize(const std::string& path, PixelFormat format, int width,
                                    int height);

// The same status with code INVALID_ARGUMENT (OK stays OK): ReadBundle reports every problem of
// the bundle's content (including missing files) as bad input.
absl::Status AsInvalidArgument(const absl::Status& status);

}  // namespace vb::capture::internal
