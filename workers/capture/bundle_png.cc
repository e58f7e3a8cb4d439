// SPDX-License-Identifier: Apache-2.0
// PNG I/O and demosaicing of the capture bundle's images, on OpenCV (imgcodecs, imgproc).
// Files are read into memory and decoded with cv::imdecode so that a missing file, a truncated
// stream and a wrong PNG type each get their own message; cv::imread would return an empty
// matrix for all of them.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "opencv2/core.hpp"
#include "opencv2/imgcodecs.hpp"
#include "opencv2/imgproc.hpp"
#include "workers/capture/bundle.h"
#include "workers/capture/bundle_internal.h"

namespace vb::capture {
namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

absl::Status CheckImage(const Image& image, const std::string& what) {
  if (image.width <= 0 || image.height <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": size must be positive, is ", image.width, "x", image.height));
  }
  const size_t expected =
      static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * image.channels();
  if (image.data.size() != expected) {
    return absl::InvalidArgumentError(absl::StrCat(
        what, ": holds ", image.data.size(), " bytes, but a ", image.width, "x", image.height, " ",
        std::string(PixelFormatName(image.format)), " image needs ", expected));
  }
  return absl::OkStatus();
}

// A header over the image's bytes (no copy). The Mat must not be written through.
cv::Mat WrapImage(const Image& image) {
  return cv::Mat(image.height, image.width, CV_8UC(image.channels()),
                 const_cast<uint8_t*>(image.data.data()));
}

std::string DescribeMat(const cv::Mat& m) {
  const int bits = m.depth() == CV_8U || m.depth() == CV_8S     ? 8
                   : m.depth() == CV_16U || m.depth() == CV_16S ? 16
                                                                : 32;
  return absl::StrCat(bits, "-bit, ", m.channels(), " channel", m.channels() == 1 ? "" : "s");
}

// Far beyond any camera; stops a corrupt header from requesting gigabytes.
constexpr uint64_t kMaxPixels = uint64_t{1} << 27;

struct PngHeader {
  uint32_t width = 0;
  uint32_t height = 0;
  int bit_depth = 0;
};

uint32_t BigEndian32(const std::string& bytes, size_t at) {
  return (uint32_t{static_cast<uint8_t>(bytes[at])} << 24) |
         (uint32_t{static_cast<uint8_t>(bytes[at + 1])} << 16) |
         (uint32_t{static_cast<uint8_t>(bytes[at + 2])} << 8) |
         uint32_t{static_cast<uint8_t>(bytes[at + 3])};
}

// The signature and IHDR chunk (PNG spec, section 11.2.2), which must come first.
absl::StatusOr<PngHeader> ParsePngHeader(const std::string& path, const std::string& bytes) {
  if (bytes.size() < sizeof(kPngSignature) ||
      std::memcmp(bytes.data(), kPngSignature, sizeof(kPngSignature)) != 0) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not a PNG file (bad signature)"));
  }
  constexpr size_t kIhdrEnd = 8 + 4 + 4 + 13;
  if (bytes.size() < kIhdrEnd || BigEndian32(bytes, 8) != 13 ||
      bytes.compare(12, 4, "IHDR") != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": cannot decode PNG (truncated or corrupt header)"));
  }
  PngHeader header;
  header.width = BigEndian32(bytes, 16);
  header.height = BigEndian32(bytes, 20);
  header.bit_depth = static_cast<uint8_t>(bytes[24]);
  if (header.width == 0 || header.height == 0 ||
      uint64_t{header.width} * header.height > kMaxPixels) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": PNG header claims an image of ",
                                                   header.width, "x", header.height));
  }
  return header;
}

// Reads and decodes a PNG file without converting its type. NOT_FOUND if the file is missing,
// INVALID_ARGUMENT if it is not a complete, decodable PNG or if `check_header` rejects it.
template <typename CheckHeader>
absl::StatusOr<cv::Mat> DecodePngFile(const std::string& path, CheckHeader check_header) {
  VB_ASSIGN_OR_RETURN(const std::string bytes, internal::ReadFileBytes(path));
  VB_ASSIGN_OR_RETURN(const PngHeader header, ParsePngHeader(path, bytes));
  VB_RETURN_IF_ERROR(check_header(header));
  cv::Mat decoded;
  try {
    const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8UC1,
                         const_cast<char*>(bytes.data()));
    decoded = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot decode PNG: ", e.err));
  }
  if (decoded.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": cannot decode PNG (truncated or corrupt, ", bytes.size(), " bytes)"));
  }
  return decoded;
}

absl::Status EncodeAndWrite(const std::string& path, const cv::Mat& mat) {
  std::vector<uchar> encoded;
  try {
    // Level 1 favours speed over size: capture happens while the platform waits.
    if (!cv::imencode(".png", mat, encoded, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
      return absl::InternalError(absl::StrCat(path, ": PNG encoding failed"));
    }
  } catch (const cv::Exception& e) {
    return absl::InternalError(absl::StrCat(path, ": PNG encoding failed: ", e.err));
  }
  return internal::WriteFileAtomically(
      path, std::string_view(reinterpret_cast<const char*>(encoded.data()), encoded.size()));
}

// OpenCV names a Bayer pattern by the second row's 2nd and 3rd pixels, which is the GenICam/PFNC
// name (first row's 1st and 2nd pixels) shifted by one pixel diagonally: PFNC BayerRG
// (R G / G B) is OpenCV's BayerBG. Checked by DemosaicTest against hand-made mosaics.
int DemosaicCode(PixelFormat format) {
  switch (format) {
    case PixelFormat::kBayerRg8:
      return cv::COLOR_BayerBG2RGB_EA;
    case PixelFormat::kBayerGb8:
      return cv::COLOR_BayerGR2RGB_EA;
    case PixelFormat::kBayerGr8:
      return cv::COLOR_BayerGB2RGB_EA;
    case PixelFormat::kBayerBg8:
      return cv::COLOR_BayerRG2RGB_EA;
    case PixelFormat::kRgb8:
    case PixelFormat::kMono8:
      break;
  }
  return -1;
}

}  // namespace

absl::Status WritePng(const std::string& path, const Image& image) {
  VB_RETURN_IF_ERROR(CheckImage(image, path));
  if (image.format != PixelFormat::kRgb8) return EncodeAndWrite(path, WrapImage(image));
  cv::Mat bgr;
  try {
    cv::cvtColor(WrapImage(image), bgr, cv::COLOR_RGB2BGR);
  } catch (const cv::Exception& e) {
    return absl::InternalError(absl::StrCat(path, ": colour conversion failed: ", e.err));
  }
  return EncodeAndWrite(path, bgr);
}

namespace {

std::string BitDepthMismatch(const std::string& path, const std::string& what,
                             PixelFormat format) {
  return absl::StrCat(path, ": PNG is ", what, ", but pixel_format ",
                      std::string(PixelFormatName(format)), " needs an 8-bit PNG");
}

absl::StatusOr<Image> ReadPngChecked(const std::string& path, PixelFormat format, int width,
                                     int height) {
  const auto check_header = [&](const PngHeader& header) -> absl::Status {
    if (width > 0 && (header.width != static_cast<uint32_t>(width) ||
                      header.height != static_cast<uint32_t>(height))) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": image is ", header.width, "x",
                                                     header.height, " but the calibration says ",
                                                     width, "x", height));
    }
    if (header.bit_depth > 8) {
      return absl::InvalidArgumentError(
          BitDepthMismatch(path, absl::StrCat(header.bit_depth, "-bit"), format));
    }
    return absl::OkStatus();
  };
  VB_ASSIGN_OR_RETURN(const cv::Mat decoded, DecodePngFile(path, check_header));
  const std::string format_name(PixelFormatName(format));
  if (decoded.depth() != CV_8U) {
    return absl::InvalidArgumentError(BitDepthMismatch(path, DescribeMat(decoded), format));
  }
  if (decoded.channels() != ChannelCount(format)) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": PNG has ", decoded.channels(), " channel(s), but pixel_format ", format_name,
        " needs ", ChannelCount(format)));
  }
  if (width > 0 && (decoded.cols != width || decoded.rows != height)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": decoded image is ", decoded.cols, "x",
                                                   decoded.rows, ", expected ", width, "x", height));
  }
  Image image(decoded.cols, decoded.rows, format);
  cv::Mat out(image.height, image.width, CV_8UC(image.channels()), image.data.data());
  try {
    if (format == PixelFormat::kRgb8) {
      cv::cvtColor(decoded, out, cv::COLOR_BGR2RGB);
    } else {
      decoded.copyTo(out);
    }
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot convert PNG: ", e.err));
  }
  // cvtColor/copyTo reallocate instead of failing if the destination does not fit; make sure
  // they wrote into the image.
  if (out.data != image.data.data()) {
    return absl::InternalError(absl::StrCat(path, ": internal error: conversion reallocated"));
  }
  return image;
}

}  // namespace

namespace internal {

absl::StatusOr<Image> ReadPngOfSize(const std::string& path, PixelFormat format, int width,
                                    int height) {
  return ReadPngChecked(path, format, std::max(width, 1), std::max(height, 1));
}

}  // namespace internal

absl::StatusOr<Image> ReadPng(const std::string& path, PixelFormat format) {
  return ReadPngChecked(path, format, 0, 0);
}

absl::Status WriteLabelPng(const std::string& path, const LabelImage& labels) {
  if (labels.width <= 0 || labels.height <= 0 ||
      labels.data.size() != static_cast<size_t>(labels.width) * labels.height) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": label image of ", labels.width, "x",
                                                   labels.height, " holds ", labels.data.size(),
                                                   " values"));
  }
  const cv::Mat mat(labels.height, labels.width, CV_16UC1,
                    const_cast<uint16_t*>(labels.data.data()));
  return EncodeAndWrite(path, mat);
}

absl::StatusOr<LabelImage> ReadLabelPng(const std::string& path) {
  VB_ASSIGN_OR_RETURN(const cv::Mat decoded,
                      DecodePngFile(path, [](const PngHeader&) { return absl::OkStatus(); }));
  if (decoded.depth() != CV_16U || decoded.channels() != 1) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": label PNG is ", DescribeMat(decoded), ", expected 16-bit, 1 channel"));
  }
  LabelImage labels(decoded.cols, decoded.rows);
  for (int y = 0; y < decoded.rows; ++y) {
    std::memcpy(&labels.at(0, y), decoded.ptr<uint16_t>(y), sizeof(uint16_t) * decoded.cols);
  }
  return labels;
}

absl::StatusOr<Image> ToRgb(const Image& image) {
  VB_RETURN_IF_ERROR(CheckImage(image, "ToRgb: image"));
  if (image.format == PixelFormat::kRgb8) return image;
  if (IsBayer(image.format) && (image.width < 2 || image.height < 2)) {
    return absl::InvalidArgumentError(absl::StrCat("ToRgb: a Bayer mosaic needs at least 2x2 pixels, got ",
                                                   image.width, "x", image.height));
  }
  Image rgb(image.width, image.height, PixelFormat::kRgb8);
  cv::Mat out(rgb.height, rgb.width, CV_8UC3, rgb.data.data());
  const int code = image.format == PixelFormat::kMono8 ? cv::COLOR_GRAY2RGB : DemosaicCode(image.format);
  try {
    cv::cvtColor(WrapImage(image), out, code);
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(absl::StrCat("ToRgb: cannot convert ",
                                                   std::string(PixelFormatName(image.format)),
                                                   " image: ", e.err));
  }
  if (out.data != rgb.data.data()) {
    return absl::InternalError("ToRgb: internal error: conversion reallocated");
  }
  return rgb;
}

}  // namespace vb::capture
