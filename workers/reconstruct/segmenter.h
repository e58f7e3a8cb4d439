// SPDX-License-Identifier: Apache-2.0
// Segmentation, the first stage of reconstruction: labels every pixel of a camera image as
// background, foreground (wood: canes, trunk, head, of this vine or a neighbour), wire or post
// (PixelClass, view2d.h), from its colour and neighbourhood.
//
// Method, after Botterill et al. 2017 ("A Robot System for Pruning Grape Vines", sec. 3.2.1),
// who classified 5x5 Bayer patches with linear SVMs and an RBF SVM for the hard remainder. Here a
// pixel's feature vector (segmenter_features.h) holds brightness and two chromaticities of the
// mean colour at four scales (1x1 .. 15x15) plus thin-ridge responses that pick out wires and thin
// canes against the blue backdrop. Stage 1 is one linear SVM per class (one against the rest;
// background split into backdrop and ground, SegmenterClass); the class with the largest score
// wins. Pixels whose two best scores are within
// `cascade_margin` go to stage 2, linear SVMs on the quadratic expansion of the features (a cheap
// stand-in for the paper's RBF SVM). The SVMs are trained by dual coordinate descent
// (TrainSegmenter); inference is a plain loop over the stored weights.
//
// Models are JSON files of format "vinebot.segmenter.v1"; the committed model
// (workers/reconstruct/models/segmenter.json, trained by `vinebot train segmenter`) is embedded in
// the library at build time (BuiltinSegmenterModel).
//
// Thread safety: all functions are thread-safe; models are immutable values.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/image.h"
#include "nlohmann/json.hpp"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

inline constexpr char kSegmenterModelFormat[] = "vinebot.segmenter.v1";

// The classes the SVMs separate: PixelClass with background split by its two looks, the blue
// backdrop and the brown ground (no single linear function separates both from bark).
enum class SegmenterClass : uint8_t { kBackdrop = 0, kGround, kForeground, kWire, kPost };
inline constexpr int kSegmenterClassCount = 5;
PixelClass PixelClassOf(SegmenterClass c);

// One linear SVM per SegmenterClass over an input vector x (features, or their quadratic expansion):
// score_c = bias[c] + sum_i weights[c][i] * (x_i - mean[i]) / scale[i].
struct SegmenterLinearStage {
  std::vector<float> mean;   // per input, the normalisation applied before the weights
  std::vector<float> scale;  // per input, > 0
  std::array<std::vector<float>, kSegmenterClassCount> weights;  // per class, one per input
  std::array<float, kSegmenterClassCount> bias{};                // per class
};

struct SegmenterModel {
  // The feature names the model was trained on; must equal SegmenterFeatureNames() of this build.
  std::vector<std::string> features;
  SegmenterLinearStage stage1;  // inputs: the features
  // Cascade: pixels whose best two stage-1 scores differ by less than cascade_margin are
  // re-classified by stage2, whose inputs are the features followed by the products
  // z_i * z_j (i <= j, both in `quadratic`) of the stage-1-normalised features
  // z = (f - stage1.mean) / stage1.scale. cascade_margin <= 0 disables stage 2.
  float cascade_margin = 0.0f;
  std::vector<int> quadratic;  // feature indices, strictly increasing
  SegmenterLinearStage stage2;
  std::string notes;  // provenance: how and on what the model was trained
};

// The names of the per-pixel features this build computes (segmenter_features.h), in order.
const std::vector<std::string>& SegmenterFeatureNames();

// Checks sizes (features match this build, one weight per input and class, stage 2 present when
// cascade_margin > 0, quadratic indices in range and increasing) and finiteness.
// INVALID_ARGUMENT naming the offending field.
absl::Status ValidateSegmenterModel(const SegmenterModel& model);

// JSON I/O. Read: NOT_FOUND if the file cannot be opened; INVALID_ARGUMENT naming the file and the
// field for malformed content (wrong format string, missing field, wrong sizes, non-finite
// numbers, features that differ from this build's). Write: validates first (INVALID_ARGUMENT),
// INTERNAL on I/O failure; atomic (temp file + rename).
absl::StatusOr<SegmenterModel> ParseSegmenterModel(const nlohmann::json& json);
nlohmann::json SegmenterModelToJson(const SegmenterModel& model);
absl::StatusOr<SegmenterModel> ReadSegmenterModel(const std::string& path);
absl::Status WriteSegmenterModel(const std::string& path, const SegmenterModel& model);

// The committed model, embedded at build time. Parsed on first use; aborts if the embedded file
// is malformed (a build defect, caught by segmenter_test.cc).
const SegmenterModel& BuiltinSegmenterModel();

// Labels every pixel of `rgb`. INVALID_ARGUMENT for a format other than rgb8, a size that is not
// positive, a byte count that disagrees with the size, or an invalid model. Any image content is
// accepted (black, saturated, 1x1).
absl::StatusOr<ClassImage> Segment(const Image& rgb, const SegmenterModel& model);

// The class of a simulator label value. Restates sim/scene.h (reconstruct may not link sim):
// 0 background, 1 wire, 2 post, 3 head, 4 a neighbouring vine, >= 1000 a cane or the trunk; head,
// neighbours, canes and trunk are all foreground. Unknown values (5..999) count as background.
PixelClass ClassOfSimLabel(uint16_t label);
ClassImage ClassesOfSimLabels(const LabelImage& labels);

// ---- Training -----------------------------------------------------------------------------

// A training image: an rgb8 image (demosaiced if it was Bayer) and the simulator's labels.
struct LabelledView {
  Image rgb;
  LabelImage labels;
};

struct SegmenterTrainOptions {
  int samples_per_class_per_view = 1500;  // pixels drawn per class from each training view
  double hard_fraction = 0.6;     // of those, the fraction drawn from near a class boundary or
                                  // from thin structures (where errors happen)
  int boundary_radius_px = 2;     // "near a boundary": another class within this Chebyshev radius
  double svm_c = 0.5;             // SVM soft-margin constant, features normalised to unit variance
  int svm_max_iterations = 200;   // cap on the solver's passes over the samples, per SVM
  bool cascade = true;            // train stage 2
  float cascade_margin = 1.0f;    // stage-1 score margin below which stage 2 decides
  int stage2_max_samples = 24000; // cap on hard pixels used to train stage 2
  int uniform_samples_per_view = 20000;  // uniform pixel sample per view for tuning the biases
  uint64_t seed = 1;              // sampling seed
  // INVALID_ARGUMENT naming the field for non-positive counts, hard_fraction outside [0, 1],
  // non-finite or non-positive svm_c, negative radius or margin.
  absl::Status Validate() const;
};

// Pixel-level accuracy of a segmenter on a set of labelled views.
struct SegmenterClassScore {
  int64_t true_px = 0;       // pixels of this class in the labels
  int64_t predicted_px = 0;  // pixels the segmenter put in this class
  int64_t correct_px = 0;    // both
  double precision = 0.0;    // correct / predicted (1 when nothing was predicted)
  double recall = 0.0;       // correct / true (1 when there is nothing to find)
};

struct SegmenterReport {
  int views = 0;
  int64_t pixels = 0;
  double accuracy = 0.0;  // fraction of pixels labelled correctly
  std::array<SegmenterClassScore, kPixelClassCount> classes;  // indexed by PixelClass
  // Foreground pixels inside a fully foreground 2x2 block (structures at least ~2 px wide), and
  // the fraction of them labelled foreground.
  int64_t wide_foreground_px = 0;
  double wide_foreground_recall = 0.0;
  // Pixels that reached stage 2 (fraction of all pixels).
  double stage2_fraction = 0.0;
  double mean_segment_ms = 0.0;  // wall time of Segment per view
};

// Segments every view with `model` and scores it against the labels. INVALID_ARGUMENT for a view
// whose image and labels disagree in size, or any error of Segment.
absl::StatusOr<SegmenterReport> EvaluateSegmenter(const std::vector<LabelledView>& views,
                                                  const SegmenterModel& model);
nlohmann::json SegmenterReportToJson(const SegmenterReport& report);

struct SegmenterTrainResult {
  SegmenterModel model;
  SegmenterReport held_out;  // on `held_out` (empty report if none were given)
  int64_t stage1_samples = 0;
  int64_t stage2_samples = 0;
  double train_seconds = 0.0;
};

// Trains a model on `train` and reports it on `held_out`. INVALID_ARGUMENT for invalid options,
// no training views, a view whose image is not rgb8 or disagrees in size with its labels, or a
// class with no pixels in any training view; INTERNAL if OpenCV fails.
absl::StatusOr<SegmenterTrainResult> TrainSegmenter(const std::vector<LabelledView>& train,
                                                    const std::vector<LabelledView>& held_out,
                                                    const SegmenterTrainOptions& options);

}  // namespace vb::reconstruct
