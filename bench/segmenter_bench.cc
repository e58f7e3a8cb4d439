// SPDX-License-Identifier: Apache-2.0
// Segmenter speed on one core: Segment() with the built-in model on a rendered 1280x1024 stop
// (seed 1500, vine 2, camera 0 of the default rig; a training-range seed), and the feature
// extraction alone. OpenCV's own threads are disabled so the figure is single-core.
// Run: build/bench/vb_segmenter_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <vector>

#include "opencv2/core.hpp"
#include "sim/renderer.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/segmenter_features.h"

namespace vb::reconstruct {
namespace {

const Image& StopImage() {
  static const Image* image = [] {
    cv::setNumThreads(0);
    const auto scene = sim::GenerateScene(1500, 2);
    const auto rig = sim::MakeRig();
    if (!scene.ok() || !rig.ok()) std::abort();
    auto view = sim::Render(*scene, rig->cameras[0], {}, 77);
    if (!view.ok()) std::abort();
    return new Image(std::move(view->image));
  }();
  return *image;
}

void BM_Segment(benchmark::State& state) {
  const Image& image = StopImage();
  const SegmenterModel& model = BuiltinSegmenterModel();
  for (auto _ : state) {
    auto classes = Segment(image, model);
    if (!classes.ok()) std::abort();
    benchmark::DoNotOptimize(classes->data.data());
  }
}
BENCHMARK(BM_Segment)->Unit(benchmark::kMillisecond);

void BM_SegmentFeatures(benchmark::State& state) {
  const Image& image = StopImage();
  const float* rows[segmenter_internal::kFeatureCount];
  for (auto _ : state) {
    auto fx = segmenter_internal::FeatureExtractor::Create(image);
    if (!fx.ok()) std::abort();
    for (int y = 0; y < image.height; ++y) fx->Next(rows);
    benchmark::DoNotOptimize(rows[0]);
  }
}
BENCHMARK(BM_SegmentFeatures)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vb::reconstruct
BENCHMARK_MAIN();
