// SPDX-License-Identifier: Apache-2.0
// Scoring of the segmenter against label images (EvaluateSegmenter, SegmenterReportToJson;
// segmenter.h). Split from segmenter_train.cc, whose held-out report it makes.
#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/segmenter_features.h"

namespace vb::reconstruct {
namespace {

constexpr int kC = kPixelClassCount;

}  // namespace

absl::StatusOr<SegmenterReport> EvaluateSegmenter(const std::vector<LabelledView>& views,
                                                  const SegmenterModel& model) {
  SegmenterReport r;
  std::array<std::array<int64_t, kC>, kC> m{};
  int64_t stage2 = 0, wide_hit = 0;
  double ms = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    VB_RETURN_IF_ERROR(
        segmenter_internal::CheckLabelledView(views[v], absl::StrCat("views[", v, "]")));
    const auto t0 = std::chrono::steady_clock::now();
    int64_t hard = 0;
    VB_ASSIGN_OR_RETURN(const ClassImage pred,
                        segmenter_internal::SegmentCounting(views[v].rgb, model, &hard));
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    stage2 += hard;
    const ClassImage truth = ClassesOfSimLabels(views[v].labels);
    const int w = truth.width, h = truth.height;
    for (size_t i = 0; i < truth.data.size(); ++i) ++m[truth.data[i]][pred.data[i]];
    // Wide foreground: inside an all-foreground 2x2 block.
    std::vector<uint8_t> wide(truth.data.size(), 0);
    const auto fg = static_cast<uint8_t>(PixelClass::kForeground);
    for (int y = 0; y + 1 < h; ++y) {
      for (int x = 0; x + 1 < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (truth.data[i] == fg && truth.data[i + 1] == fg && truth.data[i + w] == fg &&
            truth.data[i + w + 1] == fg) {
          wide[i] = wide[i + 1] = wide[i + w] = wide[i + w + 1] = 1;
        }
      }
    }
    for (size_t i = 0; i < wide.size(); ++i) {
      if (!wide[i]) continue;
      ++r.wide_foreground_px;
      wide_hit += pred.data[i] == fg;
    }
    r.pixels += static_cast<int64_t>(truth.data.size());
  }
  r.views = static_cast<int>(views.size());
  int64_t correct = 0;
  for (int c = 0; c < kC; ++c) {
    SegmenterClassScore& s = r.classes[c];
    for (int k = 0; k < kC; ++k) s.true_px += m[c][k], s.predicted_px += m[k][c];
    s.correct_px = m[c][c];
    correct += m[c][c];
    s.precision = s.predicted_px > 0 ? static_cast<double>(s.correct_px) / s.predicted_px : 1.0;
    s.recall = s.true_px > 0 ? static_cast<double>(s.correct_px) / s.true_px : 1.0;
  }
  r.accuracy = r.pixels > 0 ? static_cast<double>(correct) / r.pixels : 1.0;
  r.wide_foreground_recall =
      r.wide_foreground_px > 0 ? static_cast<double>(wide_hit) / r.wide_foreground_px : 1.0;
  r.stage2_fraction = r.pixels > 0 ? static_cast<double>(stage2) / r.pixels : 0.0;
  r.mean_segment_ms = views.empty() ? 0.0 : ms / views.size();
  return r;
}

nlohmann::json SegmenterReportToJson(const SegmenterReport& r) {
  static const char* const names[kC] = {"background", "foreground", "wire", "post"};
  nlohmann::json classes = nlohmann::json::object();
  for (int c = 0; c < kC; ++c) {
    const SegmenterClassScore& s = r.classes[c];
    classes[names[c]] = {{"precision", s.precision},   {"recall", s.recall},
                         {"true_px", s.true_px},       {"predicted_px", s.predicted_px},
                         {"correct_px", s.correct_px}};
  }
  return {{"views", r.views},
          {"pixels", r.pixels},
          {"accuracy", r.accuracy},
          {"classes", classes},
          {"wide_foreground_px", r.wide_foreground_px},
          {"wide_foreground_recall", r.wide_foreground_recall},
          {"stage2_fraction", r.stage2_fraction},
          {"mean_segment_ms", r.mean_segment_ms}};
}

}  // namespace vb::reconstruct
