// SPDX-License-Identifier: Apache-2.0
// Binary-mask operations of the 2D structure stage (structure2d.h), written for speed on
// 1280x1024 masks where the general OpenCV routines do more than is needed: removal of small
// connected components by bounded flood fill, and a Euclidean distance transform capped at a
// small distance. Plain C++; thread-safe (pure functions on caller-owned data).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vb::reconstruct {

// A binary image, 0 or 1 per pixel, row-major.
struct BinaryImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> data;

  BinaryImage() = default;
  BinaryImage(int w, int h) : width(w), height(h), data(static_cast<size_t>(w) * h, 0) {}
  uint8_t at(int x, int y) const { return data[static_cast<size_t>(y) * width + x]; }
  void set(int x, int y, uint8_t v) { data[static_cast<size_t>(y) * width + x] = v; }
};

// Flips (value -> 1 - value) every connected component of pixels equal to `value` (0 or 1) with
// at most `max_area` pixels: 8-connected if `eight_connected`, else 4-connected. If
// `border_is_large`, components touching the image border are never flipped (holes must be
// enclosed). Each flood fill stops as soon as it exceeds max_area pixels or meets a pixel already
// known to be in a large component, so the cost is ~ image size, whatever the components.
// Returns the number of components flipped.
int FlipSmallComponents(uint8_t value, int max_area, bool eight_connected, bool border_is_large,
                        BinaryImage* image);

// Euclidean distance from every pixel to the nearest pixel with value 1 in `sites`, capped at
// `cap` (1 <= cap <= 250; every pixel is `cap` if there are no sites). Exact: column distances,
// then the lower envelope of parabolas along each row (Felzenszwalb & Huttenlocher, "Distance
// Transforms of Sampled Functions", Theory of Computing 2012), with only the columns within `cap`
// of a site entering each envelope. Row-major, sites.width * sites.height.
std::vector<float> CappedDistanceTransform(const BinaryImage& sites, int cap);

}  // namespace vb::reconstruct
