// SPDX-License-Identifier: Apache-2.0
// The per-pixel features of the segmenter (segmenter.h), shared by training and inference so the
// two can never disagree. For an rgb8 image, each pixel gets:
//   lum{s}, cb{s}, cr{s} for s in {1, 3, 7, 15, 63}: brightness (R+G+B)/765 and two chromaticities of
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
//   side_cb40: max(cb15(x - 40), cb15(x + 40)): is there backdrop within 40 px to the side (true
//     beside trunks and posts, false inside the ground).
//   row: (y + 0.5) / height. The rig is fixed, so the ground is always low in the image.
// Box means extend the image by reflection (OpenCV's BORDER_REFLECT_101); the shifted samples of
// the ridge, gradient and side features repeat the border pixels. Internal to
// workers/reconstruct. Thread-compatible.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/image.h"
#include "workers/reconstruct/segmenter.h"

namespace vb::reconstruct::segmenter_internal {

inline constexpr int kFeatureCount = 23;

// Names of the features, in the order Next() returns them.
const std::vector<std::string>& FeatureNames();

// Computes the features row by row in one downward pass, keeping only a few rows of state (box
// sums by running column sums; the rows within 7 of the current one for the ridge features),
// so an image costs no full-size intermediate planes.
class FeatureExtractor {
 public:
  // INVALID_ARGUMENT unless `rgb` is rgb8 with a positive size and a matching byte count.
  // `rgb` must outlive the extractor.
  static absl::StatusOr<FeatureExtractor> Create(const Image& rgb);

  int width() const { return width_; }
  int height() const { return height_; }

  // The features of the next row (y = 0, 1, ... in turn; at most height() calls): rows[f][x] is
  // feature f at column x. The pointers stay valid until the next call. Returns the row index.
  int Next(const float* rows[kFeatureCount]);

 private:
  FeatureExtractor() = default;
  struct BoxScale {         // running column sums of one box size
    int size = 0;           // box side, odd
    int row = -1;           // the row the sums are centred on
    std::vector<int32_t> column;  // width x 3 channels: sums over rows row +- size / 2
  };
  void AdvanceBox(BoxScale& box, int row);
  void ComputeLead(int row);  // lum/cb/cr at scales 1 and 3 of `row`, into the ring
  float* Ring(int plane, int row);  // plane 0..5: lum1 cb1 cr1 lum3 cb3 cr3, row clamped

  const Image* rgb_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  int next_ = 0;       // the row Next() returns
  int lead_done_ = -1; // last row in the ring
  std::vector<BoxScale> boxes_;   // 3, 7, 15, 63
  std::vector<float> ring_;       // kRingRows rows x 6 planes, padded by kPad each side
  std::vector<float> own_;        // this row's computed features, one padded row each
  std::vector<int32_t> prefix_;   // horizontal prefix sums, scratch (< 2^31: 63 * 63 * 255 * w)
  std::vector<float> mean_;       // box mean colour of one row, scratch
};

// Stage-2 inputs of one pixel (see SegmenterModel::quadratic) from its kFeatureCount raw
// features; `out` holds kFeatureCount + q (q + 1) / 2 floats. The model must be valid.
void Stage2Input(const SegmenterModel& model, const float* features, float* out);

// OK if `view` is usable for training or scoring: an rgb8 image whose bytes match its size,
// labels of the same size; else INVALID_ARGUMENT naming `what` and the field (".rgb", ".labels").
absl::Status CheckLabelledView(const LabelledView& view, const std::string& what);

// Segment() that also counts the pixels decided by stage 2 (may be null).
absl::StatusOr<ClassImage> SegmentCounting(const Image& rgb, const SegmenterModel& model,
                                           int64_t* stage2_pixels);

}  // namespace vb::reconstruct::segmenter_internal
