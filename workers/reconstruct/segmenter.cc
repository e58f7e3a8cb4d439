// SPDX-License-Identifier: Apache-2.0
// Segment() and the model file format. The classifier loop works on one image row at a time so
// the feature rows stay in cache; stage-1 weights are pre-multiplied by the normalisation.
#include "workers/reconstruct/segmenter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"
#include "workers/reconstruct/segmenter_features.h"

namespace vb::reconstruct {
namespace segmenter_internal {
// The committed model file, generated into the build tree by CMake (see CMakeLists.txt).
extern const char* const kBuiltinSegmenterModelJson;
}  // namespace segmenter_internal

namespace {

using segmenter_internal::FeatureExtractor;
using segmenter_internal::kFeatureCount;

constexpr int kM = kSegmenterClassCount;
constexpr const char* kClassNames[kM] = {"backdrop", "ground", "foreground", "wire", "post"};
constexpr uint8_t kPixelOf[kM] = {0, 0, 1, 2, 3};

// Shortest decimal that reads back as the same float, so model files stay small and diffable.
double Compact(float v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.7g", static_cast<double>(v));
  return std::strtod(buf, nullptr);
}

nlohmann::json FloatsToJson(const std::vector<float>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (float x : v) a.push_back(Compact(x));
  return a;
}

absl::StatusOr<std::vector<float>> ParseFloats(const nlohmann::json& object,
                                               const std::string& field, const std::string& what,
                                               size_t expected) {
  VB_ASSIGN_OR_RETURN(const nlohmann::json* f, Field(object, field));
  if (!f->is_array()) return absl::InvalidArgumentError(absl::StrCat(what, ": not an array"));
  if (f->size() != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": expected ", expected, " numbers, found ", f->size()));
  }
  std::vector<float> out;
  out.reserve(expected);
  for (size_t i = 0; i < f->size(); ++i) {
    const nlohmann::json& e = (*f)[i];
    if (!e.is_number()) {
      return absl::InvalidArgumentError(absl::StrCat(what, "[", i, "]: not a number"));
    }
    const double v = e.get<double>();
    if (!std::isfinite(v) || std::abs(v) > 1e30) {
      return absl::InvalidArgumentError(absl::StrCat(what, "[", i, "]: not finite"));
    }
    out.push_back(static_cast<float>(v));
  }
  return out;
}

absl::StatusOr<SegmenterLinearStage> ParseStage(const nlohmann::json& object,
                                                const std::string& name, size_t inputs) {
  VB_ASSIGN_OR_RETURN(const nlohmann::json* s, Field(object, name));
  if (!s->is_object()) return absl::InvalidArgumentError(absl::StrCat(name, ": not an object"));
  SegmenterLinearStage stage;
  VB_ASSIGN_OR_RETURN(stage.mean, ParseFloats(*s, "mean", name + ".mean", inputs));
  VB_ASSIGN_OR_RETURN(stage.scale, ParseFloats(*s, "scale", name + ".scale", inputs));
  VB_ASSIGN_OR_RETURN(const nlohmann::json* classes, Field(*s, "classes"));
  if (!classes->is_object()) {
    return absl::InvalidArgumentError(absl::StrCat(name, ".classes: not an object"));
  }
  for (int c = 0; c < kM; ++c) {
    const std::string cname = kClassNames[c];
    const std::string what = absl::StrCat(name, ".classes.", cname);
    VB_ASSIGN_OR_RETURN(const nlohmann::json* cls, Field(*classes, cname));
    if (!cls->is_object()) return absl::InvalidArgumentError(absl::StrCat(what, ": not an object"));
    VB_ASSIGN_OR_RETURN(stage.weights[c], ParseFloats(*cls, "weights", what + ".weights", inputs));
    auto bias = NumberField(*cls, "bias");
    if (!bias.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ".", std::string(bias.status().message())));
    }
    stage.bias[c] = static_cast<float>(*bias);
  }
  return stage;
}

nlohmann::json StageToJson(const SegmenterLinearStage& stage) {
  nlohmann::json classes = nlohmann::json::object();
  for (int c = 0; c < kM; ++c) {
    classes[kClassNames[c]] = {{"bias", Compact(stage.bias[c])},
                               {"weights", FloatsToJson(stage.weights[c])}};
  }
  return {{"mean", FloatsToJson(stage.mean)},
          {"scale", FloatsToJson(stage.scale)},
          {"classes", classes}};
}

absl::Status ValidateStage(const SegmenterLinearStage& stage, const std::string& name,
                           size_t inputs) {
  auto check = [&](const std::vector<float>& v, const std::string& what,
                   bool positive) -> absl::Status {
    if (v.size() != inputs) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ".", what, ": expected ", inputs, " values, found ", v.size()));
    }
    for (size_t i = 0; i < v.size(); ++i) {
      if (!std::isfinite(v[i]) || (positive && !(v[i] > 0.0f))) {
        return absl::InvalidArgumentError(absl::StrCat(name, ".", what, "[", i, "]: ",
                                                       positive ? "must be > 0" : "not finite"));
      }
    }
    return absl::OkStatus();
  };
  VB_RETURN_IF_ERROR(check(stage.mean, "mean", false));
  VB_RETURN_IF_ERROR(check(stage.scale, "scale", true));
  for (int c = 0; c < kM; ++c) {
    VB_RETURN_IF_ERROR(check(stage.weights[c], absl::StrCat("classes.", kClassNames[c], ".weights"),
                             false));
    if (!std::isfinite(stage.bias[c])) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ".classes.", kClassNames[c], ".bias: not finite"));
    }
  }
  return absl::OkStatus();
}

size_t Stage2Inputs(const SegmenterModel& model) {
  const size_t q = model.quadratic.size();
  return kFeatureCount + q * (q + 1) / 2;
}

// A stage with the normalisation folded into the weights: score = b + W x. Class-major weights.
struct FoldedStage {
  int inputs = 0;
  std::vector<float> w;  // kM * inputs
  float b[kM] = {};
};

FoldedStage Fold(const SegmenterLinearStage& stage) {
  FoldedStage f;
  f.inputs = static_cast<int>(stage.mean.size());
  f.w.resize(static_cast<size_t>(kM) * f.inputs);
  for (int c = 0; c < kM; ++c) {
    double b = stage.bias[c];
    for (int i = 0; i < f.inputs; ++i) {
      const float wi = stage.weights[c][i] / stage.scale[i];
      f.w[static_cast<size_t>(c) * f.inputs + i] = wi;
      b -= static_cast<double>(wi) * stage.mean[i];
    }
    f.b[c] = static_cast<float>(b);
  }
  return f;
}

// scores[c][i] = stage score of class c at pixel x0 + i, i < n <= 256.
void ScoreChunk(const FoldedStage& st, const float* const* rows, int x0, int n,
                float (*scores)[256]) {
  for (int c = 0; c < kM; ++c) std::fill(scores[c], scores[c] + n, st.b[c]);
  for (int f = 0; f < kFeatureCount; ++f) {
    const float* fr = rows[f] + x0;
    for (int c = 0; c < kM; ++c) {
      const float wf = st.w[static_cast<size_t>(c) * kFeatureCount + f];
      float* s = scores[c];
      for (int i = 0; i < n; ++i) s[i] += wf * fr[i];
    }
  }
}

}  // namespace

namespace segmenter_internal {

// Stage-2 inputs of one pixel from its raw features: the features, then the products of the
// stage-1-normalised features listed in `quadratic`.
void Stage2Input(const SegmenterModel& model, const float* features, float* out) {
  float z[kFeatureCount];
  for (int i = 0; i < kFeatureCount; ++i) {
    out[i] = features[i];
    z[i] = (features[i] - model.stage1.mean[i]) / model.stage1.scale[i];
  }
  int k = kFeatureCount;
  const int q = static_cast<int>(model.quadratic.size());
  for (int a = 0; a < q; ++a) {
    for (int b = a; b < q; ++b) out[k++] = z[model.quadratic[a]] * z[model.quadratic[b]];
  }
}

}  // namespace segmenter_internal

const std::vector<std::string>& SegmenterFeatureNames() {
  return segmenter_internal::FeatureNames();
}

absl::Status ValidateSegmenterModel(const SegmenterModel& model) {
  if (model.features != SegmenterFeatureNames()) {
    return absl::InvalidArgumentError(
        absl::StrCat("features: the model was trained on features that differ from this "
                     "build's (", model.features.size(), " vs ", kFeatureCount,
                     "); retrain with `vinebot train segmenter`"));
  }
  VB_RETURN_IF_ERROR(ValidateStage(model.stage1, "stage1", kFeatureCount));
  if (!std::isfinite(model.cascade_margin)) {
    return absl::InvalidArgumentError("cascade_margin: not finite");
  }
  if (model.cascade_margin > 0.0f) {
    for (size_t i = 0; i < model.quadratic.size(); ++i) {
      const int q = model.quadratic[i];
      if (q < 0 || q >= kFeatureCount || (i > 0 && q <= model.quadratic[i - 1])) {
        return absl::InvalidArgumentError(
            absl::StrCat("quadratic[", i, "]: must be an increasing feature index in [0, ",
                         kFeatureCount, ")"));
      }
    }
    VB_RETURN_IF_ERROR(ValidateStage(model.stage2, "stage2", Stage2Inputs(model)));
  }
  return absl::OkStatus();
}

absl::StatusOr<SegmenterModel> ParseSegmenterModel(const nlohmann::json& json) {
  VB_RETURN_IF_ERROR(CheckFormat(json, kSegmenterModelFormat));
  SegmenterModel model;
  VB_ASSIGN_OR_RETURN(const nlohmann::json* features, Field(json, "features"));
  if (!features->is_array()) return absl::InvalidArgumentError("features: not an array");
  for (size_t i = 0; i < features->size(); ++i) {
    if (!(*features)[i].is_string()) {
      return absl::InvalidArgumentError(absl::StrCat("features[", i, "]: not a string"));
    }
    model.features.push_back((*features)[i].get<std::string>());
  }
  if (model.features != SegmenterFeatureNames()) {
    return absl::InvalidArgumentError(
        "features: differ from the features this build computes; retrain the model");
  }
  VB_ASSIGN_OR_RETURN(model.stage1, ParseStage(json, "stage1", kFeatureCount));
  VB_ASSIGN_OR_RETURN(const double margin, NumberField(json, "cascade_margin"));
  model.cascade_margin = static_cast<float>(margin);
  if (model.cascade_margin > 0.0f) {
    VB_ASSIGN_OR_RETURN(const nlohmann::json* quadratic, Field(json, "quadratic"));
    if (!quadratic->is_array()) return absl::InvalidArgumentError("quadratic: not an array");
    for (size_t i = 0; i < quadratic->size(); ++i) {
      const nlohmann::json& q = (*quadratic)[i];
      if (!q.is_number_integer()) {
        return absl::InvalidArgumentError(absl::StrCat("quadratic[", i, "]: not an integer"));
      }
      const int64_t v = q.get<int64_t>();
      if (v < 0 || v >= kFeatureCount) {
        return absl::InvalidArgumentError(absl::StrCat("quadratic[", i, "]: out of range"));
      }
      model.quadratic.push_back(static_cast<int>(v));
    }
    VB_ASSIGN_OR_RETURN(model.stage2, ParseStage(json, "stage2", Stage2Inputs(model)));
  }
  if (json.contains("notes") && json["notes"].is_string()) {
    model.notes = json["notes"].get<std::string>();
  }
  VB_RETURN_IF_ERROR(ValidateSegmenterModel(model));
  return model;
}

nlohmann::json SegmenterModelToJson(const SegmenterModel& model) {
  nlohmann::json j = {{"format", kSegmenterModelFormat},
                      {"notes", model.notes},
                      {"features", model.features},
                      {"stage1", StageToJson(model.stage1)},
                      {"cascade_margin", Compact(model.cascade_margin)}};
  if (model.cascade_margin > 0.0f) {
    j["quadratic"] = model.quadratic;
    j["stage2"] = StageToJson(model.stage2);
  }
  return j;
}

absl::StatusOr<SegmenterModel> ReadSegmenterModel(const std::string& path) {
  VB_ASSIGN_OR_RETURN(const nlohmann::json json, ReadJsonFile(path));
  auto model = ParseSegmenterModel(json);
  if (!model.ok()) {
    return absl::Status(model.status().code(),
                        absl::StrCat(path, ": ", std::string(model.status().message())));
  }
  return model;
}

absl::Status WriteSegmenterModel(const std::string& path, const SegmenterModel& model) {
  VB_RETURN_IF_ERROR(ValidateSegmenterModel(model));
  return WriteJsonFile(path, SegmenterModelToJson(model));
}

const SegmenterModel& BuiltinSegmenterModel() {
  static const SegmenterModel* model = [] {
    const nlohmann::json json = nlohmann::json::parse(
        segmenter_internal::kBuiltinSegmenterModelJson, nullptr, /*allow_exceptions=*/false);
    auto parsed = ParseSegmenterModel(json);
    if (!parsed.ok()) {
      std::cerr << "built-in segmenter model is invalid: " << parsed.status() << "\n";
      std::abort();
    }
    return new SegmenterModel(std::move(parsed).value());
  }();
  return *model;
}

PixelClass PixelClassOf(SegmenterClass c) {
  return static_cast<PixelClass>(kPixelOf[static_cast<int>(c)]);
}

PixelClass ClassOfSimLabel(uint16_t label) {
  // Values of sim/scene.h: kLabelWire 1, kLabelPost 2, kLabelHead 3, kLabelOtherVine 4,
  // kLabelCaneBase 1000 (+ cane id, trunk included).
  if (label >= 1000 || label == 3 || label == 4) return PixelClass::kForeground;
  if (label == 1) return PixelClass::kWire;
  if (label == 2) return PixelClass::kPost;
  return PixelClass::kBackground;
}

ClassImage ClassesOfSimLabels(const LabelImage& labels) {
  ClassImage out(labels.width, labels.height);
  for (size_t i = 0; i < labels.data.size() && i < out.data.size(); ++i) {
    out.data[i] = static_cast<uint8_t>(ClassOfSimLabel(labels.data[i]));
  }
  return out;
}

namespace segmenter_internal {

// Segment with an optional count of the pixels that went to stage 2 (for reports).
absl::StatusOr<ClassImage> SegmentCounting(const Image& rgb, const SegmenterModel& model,
                                           int64_t* stage2_pixels) {
  VB_RETURN_IF_ERROR(ValidateSegmenterModel(model));
  VB_ASSIGN_OR_RETURN(FeatureExtractor fx, FeatureExtractor::Create(rgb));
  const int w = fx.width(), h = fx.height();
  const FoldedStage s1 = Fold(model.stage1);
  const bool cascade = model.cascade_margin > 0.0f;
  const FoldedStage s2 = cascade ? Fold(model.stage2) : FoldedStage{};
  const float* rows[kFeatureCount];
  std::vector<float> input(cascade ? s2.inputs : 0);
  float pixel[kFeatureCount];
  ClassImage out(w, h);
  int64_t hard = 0;
  constexpr int kChunk = 256;
  float scores[kM][kChunk];
  for (int y = 0; y < h; ++y) {
    fx.Next(rows);
    uint8_t* dst = out.data.data() + static_cast<size_t>(y) * w;
    for (int x0 = 0; x0 < w; x0 += kChunk) {
      const int n = std::min(kChunk, w - x0);
      ScoreChunk(s1, rows, x0, n, scores);
      // Best and second-best scores, vectorised over the chunk.
      int best_of[kChunk];
      float margin[kChunk];
      for (int i = 0; i < n; ++i) {
        float top = scores[0][i];
        int best = 0;
        for (int c = 1; c < kM; ++c) {
          best = scores[c][i] > top ? c : best;
          top = std::max(top, scores[c][i]);
        }
        float second = -1e30f;
        for (int c = 0; c < kM; ++c) second = std::max(second, c == best ? -1e30f : scores[c][i]);
        best_of[i] = best;
        margin[i] = top - second;
      }
      for (int i = 0; i < n; ++i) {
        int best = best_of[i];
        if (cascade && margin[i] < model.cascade_margin) {
          ++hard;
          for (int f = 0; f < kFeatureCount; ++f) pixel[f] = rows[f][x0 + i];
          Stage2Input(model, pixel, input.data());
          float best2 = -1e30f;
          for (int c = 0; c < kM; ++c) {
            const float* wc = s2.w.data() + static_cast<size_t>(c) * s2.inputs;
            float v = s2.b[c];
            for (int k = 0; k < s2.inputs; ++k) v += wc[k] * input[k];
            if (v > best2) best2 = v, best = c;
          }
        }
        dst[x0 + i] = kPixelOf[best];
      }
    }
  }
  if (stage2_pixels != nullptr) *stage2_pixels = hard;
  return out;
}

}  // namespace segmenter_internal

absl::StatusOr<ClassImage> Segment(const Image& rgb, const SegmenterModel& model) {
  return segmenter_internal::SegmentCounting(rgb, model, nullptr);
}

}  // namespace vb::reconstruct
