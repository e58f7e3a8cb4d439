// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/segmenter_features.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct::segmenter_internal {
namespace {

constexpr int kBoxSizes[] = {3, 7, 15, 63};
constexpr float kDarkOffsetDn = 24.0f;
constexpr int kRingRows = 16;  // >= 2 * 7 + 1: rows y - 7 .. y + 7 for the ridges
constexpr int kPad = 8;        // padding of ring rows: ridge offsets up to 7, gradient 1
constexpr int kSidePad = 40;   // padding of the cb15 row for side_cb40
constexpr int kLeadPlanes = 6; // lum1 cb1 cr1 lum3 cb3 cr3
constexpr int kLead = 7;       // rows computed ahead of the current one
constexpr int kOwnRows = kFeatureCount - kLeadPlanes;  // features computed per row in Next()

// Feature indices (FeatureNames order).
enum : int {
  kLum1, kCb1, kCr1, kLum3, kCb3, kCr3, kLum7, kCb7, kCr7, kLum15, kCb15, kCr15, kLum63, kCb63,
  kCr63, kRidgeCb2, kRidgeCb4, kRidgeCb7, kRidgeLum2, kValleyLum3, kGradCb, kSideCb40, kRow
};
static_assert(kRow + 1 == kFeatureCount);


// BORDER_REFLECT_101 index for any i (repeated reflection for tiny n).
inline int Reflect(int i, int n) {
  if (n == 1) return 0;
  while (i < 0 || i >= n) i = i < 0 ? -i : 2 * n - 2 - i;
  return i;
}

// lum, cb, cr of mean colours (DN) r, g, b.
inline void Chroma(float r, float g, float b, float* lum, float* cb, float* cr) {
  const float s = r + g + b;
  const float inv = 1.0f / (s + kDarkOffsetDn);
  *lum = s * (1.0f / 765.0f);
  *cb = (b - 0.5f * (r + g)) * inv;
  *cr = (r - g) * inv;
}

// Repeats the first and last of the w values at row[0..w) into `pad` cells either side.
inline void PadRow(float* row, int w, int pad) {
  std::fill(row - pad, row, row[0]);
  std::fill(row + w, row + w + pad, row[w - 1]);
}

constexpr int kDirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};

}  // namespace

const std::vector<std::string>& FeatureNames() {
  static const std::vector<std::string>* names = [] {
    auto* n = new std::vector<std::string>;
    for (int s : {1, 3, 7, 15, 63}) {
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
  fx.rgb_ = &rgb;
  fx.width_ = rgb.width;
  fx.height_ = rgb.height;
  const size_t w = rgb.width;
  for (int s : kBoxSizes) fx.boxes_.push_back({s, -1, std::vector<int32_t>(3 * w)});
  fx.ring_.assign(static_cast<size_t>(kRingRows) * kLeadPlanes * (w + 2 * kPad), 0.0f);
  fx.own_.assign(static_cast<size_t>(kOwnRows) * (w + 2 * kSidePad), 0.0f);
  fx.prefix_.assign(3 * (w + 2 * 32 + 1), 0);  // box sizes up to 65
  fx.mean_.assign(3 * w, 0.0f);
  return fx;
}

float* FeatureExtractor::Ring(int plane, int row) {
  row = std::clamp(row, 0, height_ - 1);
  const size_t stride = static_cast<size_t>(width_) + 2 * kPad;
  return ring_.data() + (static_cast<size_t>(row % kRingRows) * kLeadPlanes + plane) * stride +
         kPad;
}

// Moves the column sums of `box` to be centred on `row`, then leaves the row's box mean colour in
// mean_ (interleaved RGB, DN).
void FeatureExtractor::AdvanceBox(BoxScale& box, int row) {
  const int w = width_, h = height_, r = box.size / 2;
  auto add_row = [&](int y, int sign) {
    const uint8_t* src = rgb_->data.data() + static_cast<size_t>(Reflect(y, h)) * w * 3;
    int32_t* col = box.column.data();
    for (int i = 0; i < 3 * w; ++i) col[i] += sign * src[i];
  };
  if (box.row < 0 || row != box.row + 1) {
    std::fill(box.column.begin(), box.column.end(), 0);
    for (int y = row - r; y <= row + r; ++y) add_row(y, 1);
  } else {
    add_row(row + r, 1);
    add_row(row - r - 1, -1);
  }
  box.row = row;
  // Horizontal box over the column sums: prefix sums over the row extended by reflection.
  const int n = w + 2 * r;
  int32_t* p = prefix_.data();
  p[0] = p[1] = p[2] = 0;
  const int32_t* col = box.column.data();
  for (int i = 0; i < n; ++i) {
    const int x = i - r;
    const int32_t* c = col + 3 * static_cast<size_t>(x >= 0 && x < w ? x : Reflect(x, w));
    p[3 * i + 3] = p[3 * i] + c[0];
    p[3 * i + 4] = p[3 * i + 1] + c[1];
    p[3 * i + 5] = p[3 * i + 2] + c[2];
  }
  const float inv = 1.0f / static_cast<float>(box.size * box.size);
  const int32_t* hi = p + 3 * box.size;
  float* mean = mean_.data();
  for (int i = 0; i < 3 * w; ++i) mean[i] = static_cast<float>(hi[i] - p[i]) * inv;
}

void FeatureExtractor::ComputeLead(int row) {
  const int w = width_;
  const uint8_t* src = rgb_->data.data() + static_cast<size_t>(row) * w * 3;
  float* lum1 = Ring(0, row);
  float* cb1 = Ring(1, row);
  float* cr1 = Ring(2, row);
  for (int x = 0; x < w; ++x) {
    Chroma(src[3 * x], src[3 * x + 1], src[3 * x + 2], &lum1[x], &cb1[x], &cr1[x]);
  }
  AdvanceBox(boxes_[0], row);
  float* lum3 = Ring(3, row);
  float* cb3 = Ring(4, row);
  float* cr3 = Ring(5, row);
  for (int x = 0; x < w; ++x) {
    Chroma(mean_[3 * x], mean_[3 * x + 1], mean_[3 * x + 2], &lum3[x], &cb3[x], &cr3[x]);
  }
  for (int plane = 0; plane < kLeadPlanes; ++plane) PadRow(Ring(plane, row), w, kPad);
}

int FeatureExtractor::Next(const float* rows[kFeatureCount]) {
  const int w = width_, y = next_++;
  while (lead_done_ < std::min(height_ - 1, y + kLead)) ComputeLead(++lead_done_);
  for (int plane = 0; plane < kLeadPlanes; ++plane) rows[plane] = Ring(plane, y);

  const size_t stride = static_cast<size_t>(w) + 2 * kSidePad;
  auto own = [&](int feature) { return own_.data() + (feature - kLeadPlanes) * stride + kSidePad; };
  for (int b = 1; b < 4; ++b) {
    AdvanceBox(boxes_[b], y);
    const int base = 3 * (b + 1);
    float* lum = own(base);
    float* cb = own(base + 1);
    float* cr = own(base + 2);
    for (int x = 0; x < w; ++x) {
      Chroma(mean_[3 * x], mean_[3 * x + 1], mean_[3 * x + 2], &lum[x], &cb[x], &cr[x]);
    }
  }
  const float* lum1 = Ring(0, y);
  const float* cb1 = Ring(1, y);

  // ridge_cb{k}
  const int ks[3] = {2, 4, 7};
  for (int i = 0; i < 3; ++i) {
    const int k = ks[i];
    float* dst = own(kRidgeCb2 + i);
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      const float* a = Ring(4, y + k * d[1]) + k * d[0];
      const float* b = Ring(4, y - k * d[1]) - k * d[0];
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], std::min(a[x], b[x]) - cb1[x]);
    }
  }
  {
    float* dst = own(kRidgeLum2);
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      const float* a = Ring(3, y + 2 * d[1]) + 2 * d[0];
      const float* b = Ring(3, y - 2 * d[1]) - 2 * d[0];
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], lum1[x] - std::max(a[x], b[x]));
    }
  }
  {
    float* dst = own(kValleyLum3);
    std::fill(dst, dst + w, -1e9f);
    for (const auto& d : kDirs) {
      const float* a = Ring(3, y + 3 * d[1]) + 3 * d[0];
      const float* b = Ring(3, y - 3 * d[1]) - 3 * d[0];
      for (int x = 0; x < w; ++x) dst[x] = std::max(dst[x], std::min(a[x], b[x]) - lum1[x]);
    }
  }
  {
    float* dst = own(kGradCb);
    const float* c = Ring(4, y);
    const float* up = Ring(4, y - 1);
    const float* down = Ring(4, y + 1);
    for (int x = 0; x < w; ++x) dst[x] = std::abs(c[x + 1] - c[x - 1]) + std::abs(down[x] - up[x]);
  }
  {
    float* cb15 = own(kCb15);
    PadRow(cb15, w, kSidePad);
    float* dst = own(kSideCb40);
    for (int x = 0; x < w; ++x) dst[x] = std::max(cb15[x - 40], cb15[x + 40]);
  }
  {
    float* dst = own(kRow);
    std::fill(dst, dst + w, (static_cast<float>(y) + 0.5f) / static_cast<float>(height_));
  }
  for (int f = kLeadPlanes; f < kFeatureCount; ++f) rows[f] = own(f);
  return y;
}

}  // namespace vb::reconstruct::segmenter_internal
