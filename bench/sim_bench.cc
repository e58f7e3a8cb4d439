// SPDX-License-Identifier: Apache-2.0
// Renderer speed: one trinocular capture (three 1280x1024 cameras of the default rig) of a typical
// scene on one core (the hand-built demo scene; BM_RenderTrinocularGenerated uses the vine
// generator). Ray tables are built once, outside the timed loop (they are cached per
// calibration in normal use). Run: build/bench/vb_sim_bench --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include "sim/render_demo_scene.h"
#include "sim/render_rays.h"
#include "sim/renderer.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"

namespace vb::sim {
namespace {

struct Fixture {
  Scene scene = MakeDemoScene();
  RigCalibration rig = *MakeRig();
  std::vector<std::shared_ptr<const RayTable>> rays;
  Fixture() {
    for (const CameraCalibration& c : rig.cameras) rays.push_back(RayTableFor(c));
  }
};

Fixture& GetFixture() {
  static Fixture* f = new Fixture();
  return *f;
}

void BM_RenderTrinocular(benchmark::State& state) {
  Fixture& f = GetFixture();
  RenderOptions options;
  uint64_t seed = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.rig.cameras.size(); ++i) {
      auto view = Render(f.scene, f.rig.cameras[i], *f.rays[i], options, ++seed);
      if (!view.ok()) std::abort();
      benchmark::DoNotOptimize(view->image.data.data());
    }
  }
}
BENCHMARK(BM_RenderTrinocular)->Unit(benchmark::kMillisecond);

// The same with a scene from the vine generator (seed 3, vine 2), for comparison.
void BM_RenderTrinocularGenerated(benchmark::State& state) {
  Fixture& f = GetFixture();
  const auto scene = GenerateScene(3, 2);
  if (!scene.ok()) {
    state.SkipWithError("GenerateScene failed");
    return;
  }
  RenderOptions options;
  uint64_t seed = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < f.rig.cameras.size(); ++i) {
      auto view = Render(*scene, f.rig.cameras[i], *f.rays[i], options, ++seed);
      if (!view.ok()) std::abort();
      benchmark::DoNotOptimize(view->image.data.data());
    }
  }
}
BENCHMARK(BM_RenderTrinocularGenerated)->Unit(benchmark::kMillisecond);

void BM_RenderOneCamera(benchmark::State& state) {
  Fixture& f = GetFixture();
  RenderOptions options;
  options.pixel_format = static_cast<PixelFormat>(state.range(0));
  uint64_t seed = 0;
  for (auto _ : state) {
    auto view = Render(f.scene, f.rig.cameras[0], *f.rays[0], options, ++seed);
    if (!view.ok()) std::abort();
    benchmark::DoNotOptimize(view->image.data.data());
  }
}
BENCHMARK(BM_RenderOneCamera)
    ->Arg(static_cast<int>(PixelFormat::kRgb8))
    ->Arg(static_cast<int>(PixelFormat::kBayerRg8))
    ->Unit(benchmark::kMillisecond);

void BM_BuildRayTable(benchmark::State& state) {
  const CameraCalibration camera = MakeRig()->cameras[0];
  for (auto _ : state) {
    RayTable table(camera);
    benchmark::DoNotOptimize(&table);
  }
}
BENCHMARK(BM_BuildRayTable)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
}  // namespace vb::sim

BENCHMARK_MAIN();
