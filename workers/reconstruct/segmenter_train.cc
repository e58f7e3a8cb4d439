// SPDX-License-Identifier: Apache-2.0
// Training and scoring of the segmenter (segmenter.h).
//
// Pixels are drawn class-balanced from every training view, most of them near a class boundary
// (cane edges, thin canes, wires), where the decisions are hard; one linear SVM per class (one
// against the rest, dual coordinate descent) is trained on them. Class-balanced training
// over-weights the rare classes, so the per-class biases are then tuned on a uniform pixel sample
// of the training views (natural class frequencies) to maximise the mean F1 of the classes
// (foreground counted twice). Stage 2 is trained the same way on the pixels of the training views
// whose stage-1 margin is small.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/segmenter_features.h"

namespace vb::reconstruct {
namespace {

using segmenter_internal::FeatureExtractor;
using segmenter_internal::kFeatureCount;
constexpr int kC = kPixelClassCount;
constexpr int kM = kSegmenterClassCount;

uint8_t PixelOf(int model_class) {
  return static_cast<uint8_t>(PixelClassOf(static_cast<SegmenterClass>(model_class)));
}

// The SegmenterClass of every pixel: the labels' PixelClass, background split into backdrop
// (bluish, 2B > R + G over 3x3) and ground (everything else).
std::vector<uint8_t> ModelClassesOf(const LabelledView& view) {
  const ClassImage truth = ClassesOfSimLabels(view.labels);
  const int w = truth.width, h = truth.height;
  std::vector<uint8_t> out(truth.data.size());
  constexpr uint8_t kFrom[kC] = {static_cast<uint8_t>(SegmenterClass::kBackdrop),
                                 static_cast<uint8_t>(SegmenterClass::kForeground),
                                 static_cast<uint8_t>(SegmenterClass::kWire),
                                 static_cast<uint8_t>(SegmenterClass::kPost)};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      out[i] = kFrom[truth.data[i]];
      if (truth.data[i] != 0) continue;
      int blue = 0;
      for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy) {
        for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx) {
          const uint8_t* p = view.rgb.at(xx, yy);
          blue += 2 * p[2] - p[0] - p[1];
        }
      }
      if (blue <= 0) out[i] = static_cast<uint8_t>(SegmenterClass::kGround);
    }
  }
  return out;
}

// Features whose pairwise products feed stage 2: colour at the two finest scales, and the
// thin-structure responses.
const char* const kQuadraticFeatures[] = {"lum1",      "cb1",       "cr1",       "lum3",
                                          "cb3",       "cr3",       "cb7",       "ridge_cb2",
                                          "ridge_cb4", "ridge_lum2", "valley_lum3", "grad_cb",
                                          "cb63",      "side_cb40", "row"};

std::vector<int> QuadraticIndices() {
  std::vector<int> out;
  const auto& names = SegmenterFeatureNames();
  for (const char* q : kQuadraticFeatures) {
    out.push_back(static_cast<int>(std::find(names.begin(), names.end(), q) - names.begin()));
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct SampleSet {
  int dims = 0;
  std::vector<float> x;    // size() * dims
  std::vector<uint8_t> y;  // PixelClass values
  size_t size() const { return y.size(); }
  void Add(const float* f, uint8_t c) {
    x.insert(x.end(), f, f + dims);
    y.push_back(c);
  }
};

// 1 where another class lies within Chebyshev distance `r` (separable min/max filters).
std::vector<uint8_t> BoundaryMask(const std::vector<uint8_t>& classes, int w, int h, int r) {
  std::vector<uint8_t> lo(classes.size()), hi(classes.size());
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = &classes[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      uint8_t a = 255, b = 0;
      for (int k = std::max(0, x - r); k <= std::min(w - 1, x + r); ++k) {
        a = std::min(a, row[k]), b = std::max(b, row[k]);
      }
      lo[static_cast<size_t>(y) * w + x] = a, hi[static_cast<size_t>(y) * w + x] = b;
    }
  }
  std::vector<uint8_t> out(classes.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t a = 255, b = 0;
      for (int k = std::max(0, y - r); k <= std::min(h - 1, y + r); ++k) {
        a = std::min(a, lo[static_cast<size_t>(k) * w + x]);
        b = std::max(b, hi[static_cast<size_t>(k) * w + x]);
      }
      out[static_cast<size_t>(y) * w + x] = a != b;
    }
  }
  return out;
}

// `count` distinct elements of `from` (all of them if fewer), in increasing order.
std::vector<uint32_t> Draw(std::vector<uint32_t> from, size_t count, std::mt19937_64& rng) {
  if (from.size() > count) {
    for (size_t i = 0; i < count; ++i) {
      const size_t j = i + static_cast<size_t>(rng() % (from.size() - i));
      std::swap(from[i], from[j]);
    }
    from.resize(count);
  }
  std::sort(from.begin(), from.end());
  return from;
}

// Calls fn(index, features) for every listed pixel (sorted pixel indices) of the view.
template <typename Fn>
absl::Status ForPixels(const Image& rgb, const std::vector<uint32_t>& pixels, Fn fn) {
  VB_ASSIGN_OR_RETURN(FeatureExtractor fx, FeatureExtractor::Create(rgb));
  const int w = fx.width();
  const float* rows[kFeatureCount];
  float f[kFeatureCount];
  int loaded = -1;
  for (uint32_t p : pixels) {
    const int y = static_cast<int>(p / w), x = static_cast<int>(p % w);
    while (loaded < y) loaded = fx.Next(rows);
    for (int k = 0; k < kFeatureCount; ++k) f[k] = rows[k][x];
    fn(p, f);
  }
  return absl::OkStatus();
}

// A linear SVM (L2-regularised hinge loss, bias as a constant input) by dual coordinate descent
// (Hsieh et al., "A Dual Coordinate Descent Method for Large-scale Linear SVM", ICML 2008; the
// liblinear solver). cv::ml::SVM's SMO solver did not converge within minutes on the ~1e5
// samples used here, and this one needs a few passes over them. `x` is n x d, row-major;
// `positive[i]` the side of sample i; returns d weights followed by the bias.
std::vector<double> TrainLinearSvm(const std::vector<float>& x, int d,
                                   const std::vector<uint8_t>& positive,
                                   const SegmenterTrainOptions& options, std::mt19937_64& rng) {
  const size_t n = positive.size();
  size_t n_pos = 0;
  for (uint8_t p : positive) n_pos += p;
  // Both sides weigh the same in total.
  const double c_pos = options.svm_c * static_cast<double>(n - n_pos) / std::max<size_t>(n_pos, 1);
  const double c_neg = options.svm_c;
  std::vector<double> w(d + 1, 0.0), alpha(n, 0.0), qii(n);
  for (size_t i = 0; i < n; ++i) {
    double q = 1.0;  // the bias input
    for (int j = 0; j < d; ++j) q += static_cast<double>(x[i * d + j]) * x[i * d + j];
    qii[i] = q;
  }
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  for (int epoch = 0; epoch < options.svm_max_iterations; ++epoch) {
    for (size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
    double pg_max = -1e300, pg_min = 1e300;
    for (size_t i : order) {
      const double yi = positive[i] ? 1.0 : -1.0;
      const double ci = positive[i] ? c_pos : c_neg;
      const float* xi = &x[i * d];
      double wx = w[d];
      for (int j = 0; j < d; ++j) wx += w[j] * xi[j];
      const double g = yi * wx - 1.0;
      double pg = g;
      if (alpha[i] <= 0.0) pg = std::min(g, 0.0);
      else if (alpha[i] >= ci) pg = std::max(g, 0.0);
      pg_max = std::max(pg_max, pg), pg_min = std::min(pg_min, pg);
      if (std::abs(pg) < 1e-12) continue;
      const double old = alpha[i];
      alpha[i] = std::clamp(old - g / qii[i], 0.0, ci);
      const double step = (alpha[i] - old) * yi;
      for (int j = 0; j < d; ++j) w[j] += step * xi[j];
      w[d] += step;
    }
    if (pg_max - pg_min < 0.05) break;
  }
  return w;
}

// One linear SVM per class, one against the rest, on normalised inputs.
SegmenterLinearStage TrainLinearStage(const SampleSet& s, const SegmenterTrainOptions& options,
                                      std::mt19937_64& rng) {
  const int d = s.dims;
  const size_t n = s.size();
  SegmenterLinearStage stage;
  stage.mean.assign(d, 0.0f);
  stage.scale.assign(d, 1.0f);
  for (int j = 0; j < d; ++j) {
    double sum = 0, sum2 = 0;
    for (size_t i = 0; i < n; ++i) sum += s.x[i * d + j];
    const double mean = sum / std::max<size_t>(n, 1);
    for (size_t i = 0; i < n; ++i) {
      const double v = s.x[i * d + j] - mean;
      sum2 += v * v;
    }
    stage.mean[j] = static_cast<float>(mean);
    stage.scale[j] = static_cast<float>(std::max(std::sqrt(sum2 / std::max<size_t>(n, 1)), 1e-6));
  }
  std::vector<float> x(s.x.size());
  for (size_t i = 0; i < n; ++i) {
    for (int j = 0; j < d; ++j) x[i * d + j] = (s.x[i * d + j] - stage.mean[j]) / stage.scale[j];
  }
  for (int c = 0; c < kM; ++c) {
    std::vector<uint8_t> positive(n);
    size_t n_pos = 0;
    for (size_t i = 0; i < n; ++i) n_pos += positive[i] = s.y[i] == c;
    stage.weights[c].assign(d, 0.0f);
    if (n_pos == 0 || n_pos == n) {
      stage.bias[c] = n_pos == 0 ? -10.0f : 10.0f;
      continue;
    }
    const std::vector<double> w = TrainLinearSvm(x, d, positive, options, rng);
    for (int j = 0; j < d; ++j) stage.weights[c][j] = static_cast<float>(w[j]);
    stage.bias[c] = static_cast<float>(w[d]);
  }
  return stage;
}

void Scores(const SegmenterLinearStage& st, const float* x, float* out) {
  const size_t d = st.mean.size();
  for (int c = 0; c < kM; ++c) {
    float v = st.bias[c];
    for (size_t j = 0; j < d; ++j) v += st.weights[c][j] * (x[j] - st.mean[j]) / st.scale[j];
    out[c] = v;
  }
}

using Confusion = std::array<std::array<double, kC>, kC>;  // [truth][predicted]

// Mean F1 over the classes present, foreground counted twice.
double Objective(const Confusion& m) {
  double total = 0, weights = 0;
  for (int c = 0; c < kC; ++c) {
    double truth = 0, predicted = 0;
    for (int k = 0; k < kC; ++k) truth += m[c][k], predicted += m[k][c];
    if (truth == 0) continue;
    const double wgt = c == static_cast<int>(PixelClass::kForeground) ? 2.0 : 1.0;
    total += wgt * 2.0 * m[c][c] / (truth + predicted);
    weights += wgt;
  }
  return weights > 0 ? total / weights : 0.0;
}

// Adds offsets to the class biases (backdrop fixed) that maximise Objective over pixels with
// scores `scores` (n x kM) and model classes `y`, plus the fixed decisions in `fixed`.
// Coordinate search.
std::array<float, kM> TuneBiases(const std::vector<float>& scores, const std::vector<uint8_t>& y,
                                 const Confusion& fixed) {
  std::array<float, kM> off{};
  auto evaluate = [&](const std::array<float, kM>& o) {
    Confusion m = fixed;
    for (size_t i = 0; i < y.size(); ++i) {
      int best = 0;
      float top = scores[i * kM] + o[0];
      for (int c = 1; c < kM; ++c) {
        const float v = scores[i * kM + c] + o[c];
        if (v > top) top = v, best = c;
      }
      m[PixelOf(y[i])][PixelOf(best)] += 1;
    }
    return Objective(m);
  };
  double best = evaluate(off);
  for (int round = 0; round < 3; ++round) {
    for (int c = 1; c < kM; ++c) {
      std::array<float, kM> trial = off;
      float best_v = off[c];
      for (float v = -2.0f; v <= 2.0f; v += 0.05f) {
        trial[c] = v;
        const double o = evaluate(trial);
        if (o > best + 1e-9) best = o, best_v = v;
      }
      off[c] = best_v;
    }
  }
  return off;
}

// Pixels of one view: labels and sampled pixel lists.
struct ViewSamples {
  std::vector<uint32_t> stage1;   // class-balanced, boundary-heavy
  std::vector<uint32_t> uniform;  // uniform over the image (for bias tuning)
};

}  // namespace

absl::Status SegmenterTrainOptions::Validate() const {
  if (samples_per_class_per_view <= 0) {
    return absl::InvalidArgumentError("samples_per_class_per_view: must be > 0");
  }
  if (!(hard_fraction >= 0.0 && hard_fraction <= 1.0)) {
    return absl::InvalidArgumentError("hard_fraction: must be in [0, 1]");
  }
  if (boundary_radius_px < 0 || boundary_radius_px > 50) {
    return absl::InvalidArgumentError("boundary_radius_px: must be in [0, 50]");
  }
  if (!(svm_c > 0.0) || !std::isfinite(svm_c)) {
    return absl::InvalidArgumentError("svm_c: must be finite and > 0");
  }
  if (svm_max_iterations <= 0) {
    return absl::InvalidArgumentError("svm_max_iterations: must be > 0");
  }
  if (!(cascade_margin >= 0.0f) || !std::isfinite(cascade_margin)) {
    return absl::InvalidArgumentError("cascade_margin: must be finite and >= 0");
  }
  if (stage2_max_samples <= 0) return absl::InvalidArgumentError("stage2_max_samples: must be > 0");
  if (uniform_samples_per_view <= 0) {
    return absl::InvalidArgumentError("uniform_samples_per_view: must be > 0");
  }
  return absl::OkStatus();
}

absl::StatusOr<SegmenterTrainResult> TrainSegmenter(const std::vector<LabelledView>& train,
                                                    const std::vector<LabelledView>& held_out,
                                                    const SegmenterTrainOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  VB_RETURN_IF_ERROR(options.Validate());
  if (train.empty()) return absl::InvalidArgumentError("train: no views");
  for (size_t v = 0; v < train.size(); ++v) {
    VB_RETURN_IF_ERROR(
        segmenter_internal::CheckLabelledView(train[v], absl::StrCat("train[", v, "]")));
  }
  for (size_t v = 0; v < held_out.size(); ++v) {
    VB_RETURN_IF_ERROR(
        segmenter_internal::CheckLabelledView(held_out[v], absl::StrCat("held_out[", v, "]")));
  }
  std::mt19937_64 rng(options.seed);
  SegmenterTrainResult result;
  SegmenterModel& model = result.model;
  model.features = SegmenterFeatureNames();

  // Pass 1: stage-1 samples and the uniform tuning pool.
  SampleSet s1{kFeatureCount}, pool{kFeatureCount};
  std::array<int64_t, kC> class_px{};
  for (const LabelledView& view : train) {
    const std::vector<uint8_t> classes = ModelClassesOf(view);
    const std::vector<uint8_t> boundary =
        BoundaryMask(classes, view.rgb.width, view.rgb.height, options.boundary_radius_px);
    std::array<std::vector<uint32_t>, kM> all, hard;
    for (uint32_t i = 0; i < classes.size(); ++i) {
      all[classes[i]].push_back(i);
      if (boundary[i]) hard[classes[i]].push_back(i);
      ++class_px[PixelOf(classes[i])];
    }
    std::vector<uint32_t> picked;
    for (int c = 0; c < kM; ++c) {
      const auto n_hard = static_cast<size_t>(options.samples_per_class_per_view *
                                              options.hard_fraction);
      std::vector<uint32_t> h = Draw(hard[c], n_hard, rng);
      std::vector<uint32_t> a = Draw(all[c], options.samples_per_class_per_view - h.size(), rng);
      picked.insert(picked.end(), h.begin(), h.end());
      picked.insert(picked.end(), a.begin(), a.end());
    }
    std::vector<uint32_t> uniform(options.uniform_samples_per_view);
    for (uint32_t& u : uniform) u = static_cast<uint32_t>(rng() % classes.size());
    // One walk over the rows for both lists: uniform samples are tagged in the low bit.
    std::vector<uint64_t> tagged;
    for (uint32_t p : picked) tagged.push_back(static_cast<uint64_t>(p) << 1);
    for (uint32_t p : uniform) tagged.push_back((static_cast<uint64_t>(p) << 1) | 1);
    std::sort(tagged.begin(), tagged.end());
    std::vector<uint32_t> pixels;
    for (uint64_t t : tagged) pixels.push_back(static_cast<uint32_t>(t >> 1));
    size_t k = 0;
    VB_RETURN_IF_ERROR(ForPixels(view.rgb, pixels, [&](uint32_t p, const float* f) {
      ((tagged[k++] & 1) ? pool : s1).Add(f, classes[p]);
    }));
  }
  static const char* const kNames[kC] = {"background", "foreground", "wire", "post"};
  for (int c = 0; c < kC; ++c) {
    if (class_px[c] == 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("train: no ", kNames[c], " pixels in any view"));
    }
  }
  result.stage1_samples = static_cast<int64_t>(s1.size());
  model.stage1 = TrainLinearStage(s1, options, rng);

  // Bias tuning at natural class frequencies.
  std::vector<float> pool_scores(pool.size() * kM);
  for (size_t i = 0; i < pool.size(); ++i) {
    Scores(model.stage1, &pool.x[i * kFeatureCount], &pool_scores[i * kM]);
  }
  {
    const std::array<float, kM> off = TuneBiases(pool_scores, pool.y, Confusion{});
    for (int c = 0; c < kM; ++c) {
      model.stage1.bias[c] += off[c];
      for (size_t i = 0; i < pool.size(); ++i) pool_scores[i * kM + c] += off[c];
    }
  }

  if (options.cascade && options.cascade_margin > 0.0f) {
    model.quadratic = QuadraticIndices();
    model.cascade_margin = options.cascade_margin;
    auto is_hard = [&](const float* sc) {
      float top = -1e30f, second = -1e30f;
      for (int c = 0; c < kM; ++c) {
        if (sc[c] > top) second = top, top = sc[c];
        else if (sc[c] > second) second = sc[c];
      }
      return top - second < options.cascade_margin;
    };
    // Pass 2: hard pixels of every training view, up to a per-class share of the cap.
    const size_t d2 = kFeatureCount + model.quadratic.size() * (model.quadratic.size() + 1) / 2;
    SampleSet s2{static_cast<int>(d2)};
    const size_t per_view_class =
        std::max<size_t>(1, options.stage2_max_samples / (kM * train.size()));
    std::vector<float> in2(d2);
    for (const LabelledView& view : train) {
      const std::vector<uint8_t> classes = ModelClassesOf(view);
      std::array<std::vector<uint32_t>, kM> hard;
      std::vector<uint32_t> all(classes.size());
      for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
      float sc[kM];
      VB_RETURN_IF_ERROR(ForPixels(view.rgb, all, [&](uint32_t p, const float* f) {
        Scores(model.stage1, f, sc);
        if (is_hard(sc)) hard[classes[p]].push_back(p);
      }));
      std::vector<uint32_t> picked;
      for (int c = 0; c < kM; ++c) {
        const std::vector<uint32_t> h = Draw(hard[c], per_view_class, rng);
        picked.insert(picked.end(), h.begin(), h.end());
      }
      std::sort(picked.begin(), picked.end());
      VB_RETURN_IF_ERROR(ForPixels(view.rgb, picked, [&](uint32_t p, const float* f) {
        segmenter_internal::Stage2Input(model, f, in2.data());
        s2.Add(in2.data(), classes[p]);
      }));
    }
    result.stage2_samples = static_cast<int64_t>(s2.size());
    model.stage2 = TrainLinearStage(s2, options, rng);
    // Tune stage-2 biases on the pool's hard pixels, the easy ones fixed by stage 1.
    Confusion fixed{};
    std::vector<float> hard_scores;
    std::vector<uint8_t> hard_y;
    for (size_t i = 0; i < pool.size(); ++i) {
      const float* sc = &pool_scores[i * kM];
      if (is_hard(sc)) {
        segmenter_internal::Stage2Input(model, &pool.x[i * kFeatureCount], in2.data());
        float sc2[kM];
        Scores(model.stage2, in2.data(), sc2);
        hard_scores.insert(hard_scores.end(), sc2, sc2 + kM);
        hard_y.push_back(pool.y[i]);
      } else {
        fixed[PixelOf(pool.y[i])][PixelOf(static_cast<int>(std::max_element(sc, sc + kM) - sc))] += 1;
      }
    }
    const std::array<float, kM> off = TuneBiases(hard_scores, hard_y, fixed);
    for (int c = 0; c < kM; ++c) model.stage2.bias[c] += off[c];
  }

  model.notes = absl::StrCat("trained on ", train.size(), " views, ", result.stage1_samples,
                             " stage-1 and ", result.stage2_samples, " stage-2 samples");
  VB_RETURN_IF_ERROR(ValidateSegmenterModel(model));
  if (!held_out.empty()) {
    VB_ASSIGN_OR_RETURN(result.held_out, EvaluateSegmenter(held_out, model));
  }
  result.train_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

namespace segmenter_internal {

absl::Status CheckLabelledView(const LabelledView& v, const std::string& what) {
  if (v.rgb.format != PixelFormat::kRgb8) {
    return absl::InvalidArgumentError(absl::StrCat(what, ".rgb: not rgb8"));
  }
  if (v.rgb.width <= 0 || v.rgb.height <= 0 ||
      v.rgb.data.size() != static_cast<size_t>(v.rgb.width) * v.rgb.height * 3) {
    return absl::InvalidArgumentError(absl::StrCat(what, ".rgb: size and bytes disagree"));
  }
  if (v.labels.width != v.rgb.width || v.labels.height != v.rgb.height ||
      v.labels.data.size() != static_cast<size_t>(v.rgb.width) * v.rgb.height) {
    return absl::InvalidArgumentError(absl::StrCat(what, ".labels: size differs from the image"));
  }
  return absl::OkStatus();
}

}  // namespace segmenter_internal

}  // namespace vb::reconstruct
