// SPDX-License-Identifier: Apache-2.0
// The per-pixel features of the segmenter (segmenter.h), shared by training and inference so the
// two can never disagree. For an rgb8 image, each pixel gets:
//   lum{s}, cb{s}, cr{s} for s in {1, 3, 7, 15}: brightness (R+G+B)/765 and two chromaticities of
//     the mean colour over an s x s box, cb = (B - (R+G)/2) / (R+G+B + 24) ("blueness", high on
//     the backdrop, negative on bark) and cr = (R - G) / (R+G+B + 24) ("redness": bark > post >
//     wire > backdrop). The +24 DN keeps dark pixels from producing noisy chromaticities.
//   ridge_cb{k} for k in {2, 4, 7}: max over 4 directions u of min(cb3(p+ku), cb3(p-ku)) - cb1(p):
//     positive on a structure narrower than 2k with backdrop on both sides (thin canes, wires),
//     ~0 inside wide wood or on open backdrop, negative just beside a structure.
//   ridge_lum2: max over u of lum1(p) - max(lum3(p+2u), lum3(p-2u)): bright thin lines (wires).
//   valley_lum3: max over u of min(lum3(p+3u), lum3(p-3u)) - lum1(p): dark thin lines (shadows of
//     canes on the backdrop, which must stay background).
//   grad_cb: |cb3(x+1) - cb3(x-1)| + |cb3(y+1) - cb3(y-1)|: the pixel is on an edge.
// Images are extended at their borders by reflection. Internal to workers/reconstruct.
// Thread-compatible: a FeatureExtractor is immutable after Create.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/image.h"
#include "workers/reconstruct/segmenter.h"

namespace vb::reconstruct::segmenter_internal {

inline constexpr int kFeatureCount = 23;

// Names of the features, in the order Row() writes them.
const std::vector<std::string>& FeatureNames();

class FeatureExtractor {
 public:
  // Precomputes the box-filtered planes of `rgb`. INVALID_ARGUMENT unless `rgb` is rgb8 with a
  // positive size and a matching byte count; INTERNAL if OpenCV throws.
  static absl::StatusOr<FeatureExtractor> Create(const Image& rgb);

  int width() const { return width_; }
  int height() const { return height_; }

  // The features of row y (0 <= y < height): rows[f][x] is feature f at x. The pointers stay
  // valid until the next call with the same `scratch`, which must hold kScratchRows * width
  // floats, or until the extractor is destroyed.
  static constexpr int kScratchRows = 10;  // 8 computed features + 2 temporaries
  void Row(int y, float* scratch, const float* rows[kFeatureCount]) const;

 private:
  FeatureExtractor() = default;
  const float* Plane(int k) const { return planes_.data() + static_cast<size_t>(k) * width_ * height_; }

  int width_ = 0;
  int height_ = 0;
  std::vector<float> planes_;  // 15 planes: lum, cb, cr at scales 1, 3, 7, 15, 63
};

// Stage-2 inputs of one pixel (see SegmenterModel::quadratic) from its kFeatureCount raw
// features; `out` holds kFeatureCount + q (q + 1) / 2 floats. The model must be valid.
void Stage2Input(const SegmenterModel& model, const float* features, float* out);

// Segment() that also counts the pixels decided by stage 2 (may be null).
absl::StatusOr<ClassImage> SegmentCounting(const Image& rgb, const SegmenterModel& model,
                                           int64_t* stage2_pixels);

}  // namespace vb::reconstruct::segmenter_internal
