// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/mask_ops.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vb::reconstruct {

int FlipSmallComponents(uint8_t value, int max_area, bool eight_connected, bool border_is_large,
                        BinaryImage* image) {
  if (max_area <= 0 || image->data.empty()) return 0;
  const int w = image->width;
  const int h = image->height;
  uint8_t* data = image->data.data();
  // 0 unknown, 1 in a large component, 2 in the current fill, 3 flipped.
  enum : uint8_t { kUnknown = 0, kLarge = 1, kFilling = 2, kFlipped = 3 };
  std::vector<uint8_t> state(image->data.size(), kUnknown);
  static constexpr int kSteps[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1},
                                       {1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
  const int steps = eight_connected ? 8 : 4;
  std::vector<int> fill;
  int flipped = 0;
  const int n = w * h;
  for (int p = 0; p < n; ++p) {
    if (data[p] != value || state[p] != kUnknown) continue;
    fill.clear();
    fill.push_back(p);
    state[p] = kFilling;
    bool large = false;
    for (size_t i = 0; i < fill.size() && !large; ++i) {
      const int x = fill[i] % w;
      const int y = fill[i] / w;
      if (border_is_large && (x == 0 || y == 0 || x == w - 1 || y == h - 1)) {
        large = true;
        break;
      }
      for (int k = 0; k < steps; ++k) {
        const int u = x + kSteps[k][0];
        const int v = y + kSteps[k][1];
        if (u < 0 || v < 0 || u >= w || v >= h) continue;
        const int q = v * w + u;
        if (data[q] != value) continue;
        if (state[q] == kLarge) {
          large = true;
          break;
        }
        if (state[q] == kUnknown) {
          state[q] = kFilling;
          fill.push_back(q);
          if (static_cast<int>(fill.size()) > max_area) {
            large = true;
            break;
          }
        }
      }
    }
    for (int q : fill) {
      state[q] = large ? kLarge : kFlipped;
      if (!large) data[q] = value ? 0 : 1;
    }
    flipped += !large;
  }
  return flipped;
}

std::vector<float> CappedDistanceTransform(const BinaryImage& sites, int cap) {
  cap = std::clamp(cap, 1, 250);
  const int w = sites.width;
  const int h = sites.height;
  std::vector<float> out(static_cast<size_t>(w) * h, static_cast<float>(cap));
  if (w <= 0 || h <= 0) return out;
  // Column pass: vertical distance to the nearest site, saturating at `far` (beyond the cap).
  const uint8_t far = static_cast<uint8_t>(cap + 1);
  std::vector<uint8_t> g(out.size());
  for (int x = 0; x < w; ++x) g[x] = sites.data[x] ? 0 : far;
  for (int y = 1; y < h; ++y) {
    const uint8_t* s = &sites.data[static_cast<size_t>(y) * w];
    const uint8_t* above = &g[static_cast<size_t>(y - 1) * w];
    uint8_t* row = &g[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      row[x] = s[x] ? 0 : static_cast<uint8_t>(std::min<int>(above[x] + 1, far));
    }
  }
  for (int y = h - 2; y >= 0; --y) {
    const uint8_t* below = &g[static_cast<size_t>(y + 1) * w];
    uint8_t* row = &g[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) row[x] = std::min<uint8_t>(row[x], below[x] + 1);
  }
  // Row pass: lower envelope of the parabolas (x - q)^2 + g(q)^2 of the near columns q.
  const int cap2 = cap * cap;
  std::vector<float> root(cap2);
  for (int i = 0; i < cap2; ++i) root[i] = std::sqrt(static_cast<float>(i));
  std::vector<int> v(w);
  std::vector<float> z(w + 1);
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = &g[static_cast<size_t>(y) * w];
    int k = -1;
    for (int q = 0; q < w; ++q) {
      if (row[q] >= far) continue;
      const int fq = row[q] * row[q] + q * q;
      float s = -std::numeric_limits<float>::infinity();
      while (k >= 0) {
        const int r = v[k];
        s = static_cast<float>(fq - (row[r] * row[r] + r * r)) / static_cast<float>(2 * (q - r));
        if (s > z[k]) break;
        --k;
      }
      if (k < 0) s = -std::numeric_limits<float>::infinity();
      ++k;
      v[k] = q;
      z[k] = s;
      z[k + 1] = std::numeric_limits<float>::infinity();
    }
    if (k < 0) continue;  // no site within the cap of this row
    float* dst = &out[static_cast<size_t>(y) * w];
    int j = 0;
    for (int x = 0; x < w; ++x) {
      while (z[j + 1] < static_cast<float>(x)) ++j;
      const int dx = x - v[j];
      const int d2 = dx * dx + row[v[j]] * row[v[j]];
      if (d2 < cap2) dst[x] = root[d2];
    }
  }
  return out;
}

}  // namespace vb::reconstruct
