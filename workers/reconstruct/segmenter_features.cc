// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/segmenter_features.h"

#include <algorithm>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/segmenter.h"
#include "opencv2/core.hpp"
#include "opencv2/imgproc.hpp"

namespace vb::reconstruct::segmenter_internal {
namespace {

constexpr int kScales[] = {1, 3, 7, 15, 63};
constexpr int kScaleCount = 5;
constexpr float kDarkOffsetDn = 24.0f;

// Plane indices: 3 * scale index + {0 lum, 1 cb, 2 cr}.
constexpr int kLum1 = 0, kCb1 = 1, kLum3 = 3, kCb3 = 4, kCb15 = 10;

// Writes lum, cb, cr of interleaved float RGB (values in DN) into three planes.
void ChromaOf(const float* rgb, size_t n, float* lum, float* cb, float* cr) {
  for (size_t i = 0; i < n; ++i) {
    const float r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
    const float s = r + g + b;
    const float inv = 1.0f / (s + kDarkOffsetDn);
    lum[i] = s * (1.0f / 765.0f);
    cb[i] = (b - 0.5f * (r + g)) * inv;
    cr[i] = (r - g) * inv;
  }
}

// dst[x] = row clamp(y + dy) of `plane`, at column clamp(x + dx): the plane shifted, with the
// border pixels repeated (close enough to the reflection of the box filters for a few pixels).
void ShiftedRow(const float* plane, int w, int h, int y, int dx, int dy, float* dst) {
  const int yy = std::clamp(y + dy, 0, h - 1);
  const float* row = plane + static_cast<size_t>(yy) * w;
  if (dx >= w || -dx >= w) {
    std::fill(dst, dst + w, row[dx > 0 ? w - 1 : 0]);
    return;
  }
  if (dx >= 0) {
    std::memcpy(dst, row + dx, sizeof(float) * (w - dx));
    std::fill(dst + (w - dx), dst + w, row[w - 1]);
  } else {
    std::fill(dst, dst - dx, row[0]);
    std::memcpy(dst - dx, row, sizeof(float) * (w + dx));
  }
}

constexpr int kDirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};

}  // namespace

const std::vector<std::string>& FeatureNames() {
  static const std::vector<std::string>* names = [] {
    auto* n = new std::vector<std::string>;
    for (int s : kScales) {
      n->push_back(absl::StrCat("lum", s));
      n->push_back(absl::StrCat("cb", s));
      n->push_back(absl::StrCat("cr", s));
    }
    for (const char* f : {"ridge_cb2", "ridge_cb4", "ridge_cb7", "ridge_lum2", "valley_lum3",
                          "grad_cb", "side_cb40", "row"}) {
      n->push_back(f);
    }
    return n;
  }();
  return *names;
}

absl::StatusOr<FeatureExtractor> FeatureExtractor::Create(const Image& rgb) {
  if (rgb.format != PixelFormat::kRgb8) {
    return absl::InvalidArgumentError(
        absl::StrCat("image: format must be rgb8, got ", std::string(PixelFormatName(rgb.format))));
  }
  if (rgb.width <= 0 || rgb.height <= 0 || rgb.width > 65536 || rgb.height > 65536) {
    return absl::InvalidArgumentError(
        absl::StrCat("image: size ", rgb.width, "x", rgb.height, " is not positive"));
  }
  const size_t n = static_cast<size_t>(rgb.width) * rgb.height;
  if (rgb.data.size() != n * 3) {
    return absl::InvalidArgumentError(absl::StrCat("image: ", rgb.data.size(), " bytes for ",
                                                   rgb.width, "x", rgb.height, " rgb8"));
  }
  FeatureExtractor fx;
  fx.width_ = rgb.width;
  fx.height_ = rgb.height;
  fx.planes_.resize(n * 3 * kScaleCount);
  try {
    // cv::Mat over the caller's bytes; never written.
    const cv::Mat src(rgb.height, rgb.width, CV_8UC3, const_cast<uint8_t*>(rgb.data.data()));
    cv::Mat mean;
    for (int si = 0; si < kScaleCount; ++si) {
      const int s = kScales[si];
      if (s == 1) {
        src.convertTo(mean, CV_32F);
      } else {
        cv::boxFilter(src, mean, CV_32F, cv::Size(s, s), cv::Point(-1, -1), true,
                      cv::BORDER_REFLECT_101);
      }
      float* base = fx.planes_.data() + n * 3 * si;
      ChromaOf(mean.ptr<float>(0), n, base, base + n, base + 2 * n);
    }
  } catch (const cv::Exception& e) {
    return absl::InternalError(absl::StrCat("segmenter features: OpenCV: ", e.what()));
  }
  return fx;
}

static_assert(FeatureExtractor::kScratchRows == kFeatureCount - 3 * kScaleCount + 2);

void FeatureExtractor::Row(int y, float* scratch, const float* rows[kFeatureCount]) const {
  const int w = width_, h = height_;
  const size_t row_off = static_cast<size_t>(y) * w;
  for (int k = 0; k < 3 * kScaleCount; ++k) rows[k] = Plane(k) + row_off;
  for (int k = 3 * kScaleCount; k < kFeatureCount; ++k) {
    rows[k] = scratch + static_cast<size_t>(k - 3 * kScaleCount) * w;
  }
  const float* lum1 = Plane(kLum1) + row_off;
  const float* cb1 = Plane(kCb1) + row_off;
  float* a = scratch + static_cast<size_t>(kScratchRows - 2) * w;
  float* b = scratch + static_cast<size_t>(kScratchRows - 1) * w;
  float* f = scratch;

  // ridge_cb{k}
  for (int k : {2, 4, 7}) {
    float* dst = f;
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      ShiftedRow(Plane(kCb3), w, h, y, k * d[0], k * d[1], a);
      ShiftedRow(Plane(kCb3), w, h, y, -k * d[0], -k * d[1], b);
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], std::min(a[x], b[x]) - cb1[x]);
    }
    f += w;
  }
  // ridge_lum2
  {
    float* dst = f;
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      ShiftedRow(Plane(kLum3), w, h, y, 2 * d[0], 2 * d[1], a);
      ShiftedRow(Plane(kLum3), w, h, y, -2 * d[0], -2 * d[1], b);
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], lum1[x] - std::max(a[x], b[x]));
    }
    f += w;
  }
  // valley_lum3
  {
    float* dst = f;
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      ShiftedRow(Plane(kLum3), w, h, y, 3 * d[0], 3 * d[1], a);
      ShiftedRow(Plane(kLum3), w, h, y, -3 * d[0], -3 * d[1], b);
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], std::min(a[x], b[x]) - lum1[x]);
    }
    f += w;
  }
  // grad_cb
  {
    float* dst = f;
    ShiftedRow(Plane(kCb3), w, h, y, 1, 0, a);
    ShiftedRow(Plane(kCb3), w, h, y, -1, 0, b);
    for (int x = 0; x < w; ++x) dst[x] = std::abs(a[x] - b[x]);
    ShiftedRow(Plane(kCb3), w, h, y, 0, 1, a);
    ShiftedRow(Plane(kCb3), w, h, y, 0, -1, b);
    for (int x = 0; x < w; ++x) dst[x] += std::abs(a[x] - b[x]);
    f += w;
  }
  // side_cb40
  {
    float* dst = f;
    ShiftedRow(Plane(kCb15), w, h, y, 40, 0, a);
    ShiftedRow(Plane(kCb15), w, h, y, -40, 0, b);
    for (int x = 0; x < w; ++x) dst[x] = std::max(a[x], b[x]);
    f += w;
  }
  // row
  std::fill(f, f + w, (static_cast<float>(y) + 0.5f) / static_cast<float>(h));
}

}  // namespace vb::reconstruct::segmenter_internal
