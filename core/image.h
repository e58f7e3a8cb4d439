// SPDX-License-Identifier: Apache-2.0
// In-memory images as plain byte buffers, so core and sim need no OpenCV.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace vb {

// Pixel formats of the capture bundle (ARCHITECTURE.md). Bayer formats are raw single-channel
// mosaics named by the colours of the top-left 2x2 block's first row (GenICam naming).
enum class PixelFormat { kRgb8, kMono8, kBayerRg8, kBayerGb8, kBayerGr8, kBayerBg8 };

std::string_view PixelFormatName(PixelFormat format);  // "rgb8", "mono8", "bayer_rg8", ...
// INVALID_ARGUMENT naming the value for anything not listed above.
absl::StatusOr<PixelFormat> ParsePixelFormat(std::string_view name);
int ChannelCount(PixelFormat format);  // 3 for rgb8, else 1
bool IsBayer(PixelFormat format);

// An 8-bit image, row-major, channels interleaved (RGB order for rgb8).
struct Image {
  int width = 0;
  int height = 0;
  PixelFormat format = PixelFormat::kRgb8;
  std::vector<uint8_t> data;  // width * height * ChannelCount(format) bytes

  Image() = default;
  Image(int w, int h, PixelFormat f)
      : width(w), height(h), format(f), data(static_cast<size_t>(w) * h * ChannelCount(f), 0) {}
  int channels() const { return ChannelCount(format); }
  uint8_t* at(int x, int y) { return &data[(static_cast<size_t>(y) * width + x) * channels()]; }
  const uint8_t* at(int x, int y) const {
    return &data[(static_cast<size_t>(y) * width + x) * channels()];
  }
};

// A 16-bit single-channel image (the simulator's ground-truth labels).
struct LabelImage {
  int width = 0;
  int height = 0;
  std::vector<uint16_t> data;

  LabelImage() = default;
  LabelImage(int w, int h) : width(w), height(h), data(static_cast<size_t>(w) * h, 0) {}
  uint16_t& at(int x, int y) { return data[static_cast<size_t>(y) * width + x]; }
  uint16_t at(int x, int y) const { return data[static_cast<size_t>(y) * width + x]; }
};

}  // namespace vb
