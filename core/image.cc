// SPDX-License-Identifier: Apache-2.0
#include "core/image.h"

#include "absl/strings/str_cat.h"

namespace vb {

std::string_view PixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kRgb8:
      return "rgb8";
    case PixelFormat::kMono8:
      return "mono8";
    case PixelFormat::kBayerRg8:
      return "bayer_rg8";
    case PixelFormat::kBayerGb8:
      return "bayer_gb8";
    case PixelFormat::kBayerGr8:
      return "bayer_gr8";
    case PixelFormat::kBayerBg8:
      return "bayer_bg8";
  }
  return "rgb8";
}

absl::StatusOr<PixelFormat> ParsePixelFormat(std::string_view name) {
  for (PixelFormat f : {PixelFormat::kRgb8, PixelFormat::kMono8, PixelFormat::kBayerRg8,
                        PixelFormat::kBayerGb8, PixelFormat::kBayerGr8, PixelFormat::kBayerBg8}) {
    if (PixelFormatName(f) == name) return f;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "pixel_format: unknown '", std::string(name),
      "' (expected rgb8, mono8, bayer_rg8, bayer_gb8, bayer_gr8 or bayer_bg8)"));
}

int ChannelCount(PixelFormat format) { return format == PixelFormat::kRgb8 ? 3 : 1; }

bool IsBayer(PixelFormat format) {
  return format != PixelFormat::kRgb8 && format != PixelFormat::kMono8;
}

}  // namespace vb
