// SPDX-License-Identifier: Apache-2.0
// Capture bundle import/export speed: ReadBundle of a trinocular 1280x1024 rig stored as rgb8 and
// as bayer_rg8 (+ demosaicing), and WriteBundle. Images are a synthetic scene (smooth backdrop,
// dark cane-like strokes, sensor noise) so that PNG compression behaves like a real capture.
// Run: vb_capture_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "benchmark/benchmark.h"
#include "workers/capture/bundle.h"

namespace vb::capture {
namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 1024;
constexpr int kCameras = 3;

Image SceneRgb(uint32_t seed) {
  Image image(kWidth, kHeight, PixelFormat::kRgb8);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 2.5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Cane-like strokes: lines y = a + b x with a few pixels of width.
  struct Stroke {
    double a, b, half_width;
  };
  std::vector<Stroke> strokes;
  for (int i = 0; i < 25; ++i) {
    strokes.push_back({unit(rng) * kHeight, (unit(rng) - 0.5) * 1.2, 2.0 + 6.0 * unit(rng)});
  }
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      double r = 60.0 + 80.0 * x / kWidth, g = 90.0 + 60.0 * y / kHeight, b = 150.0;
      for (const Stroke& s : strokes) {
        if (std::abs(y - (s.a + s.b * x)) < s.half_width) {
          r = 70.0;
          g = 50.0;
          b = 35.0;
        }
      }
      uint8_t* p = image.at(x, y);
      p[0] = static_cast<uint8_t>(std::clamp(r + noise(rng), 0.0, 255.0));
      p[1] = static_cast<uint8_t>(std::clamp(g + noise(rng), 0.0, 255.0));
      p[2] = static_cast<uint8_t>(std::clamp(b + noise(rng), 0.0, 255.0));
    }
  }
  return image;
}

Image MosaicRg(const Image& rgb) {  // PFNC BayerRG: R G / G B
  Image mosaic(rgb.width, rgb.height, PixelFormat::kBayerRg8);
  for (int y = 0; y < rgb.height; ++y) {
    for (int x = 0; x < rgb.width; ++x) {
      const int channel = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);
      *mosaic.at(x, y) = rgb.at(x, y)[channel];
    }
  }
  return mosaic;
}

CaptureBundle MakeBundle(PixelFormat format) {
  CaptureBundle bundle;
  bundle.metadata.row = "bench";
  bundle.metadata.vine_position_m = 1.0;
  bundle.metadata.captured_at = "2026-07-14T09:12:03Z";
  for (int i = 0; i < kCameras; ++i) {
    CameraCalibration c;
    c.name = absl::StrCat("cam", i);
    c.image_width = kWidth;
    c.image_height = kHeight;
    c.camera_matrix << 1400.0, 0.0, 640.0, 0.0, 1400.0, 512.0, 0.0, 0.0, 1.0;
    c.translation_camera_from_platform = Eigen::Vector3d(-0.2 * i, 0.0, 0.0);
    bundle.calibration.cameras.push_back(c);
    bundle.metadata.cameras.push_back({c.name, c.name + ".png", format});
    const Image rgb = SceneRgb(17 + i);
    bundle.images.push_back(format == PixelFormat::kRgb8 ? rgb : MosaicRg(rgb));
  }
  return bundle;
}

// Bundles written once per process, removed at exit.
struct Fixture {
  std::filesystem::path root;
  std::string rgb_dir, bayer_dir;
  CaptureBundle rgb_bundle;

  Fixture() {
    root = std::filesystem::temp_directory_path() / absl::StrCat("vb_capture_bench_", getpid());
    rgb_dir = (root / "rgb8").string();
    bayer_dir = (root / "bayer").string();
    rgb_bundle = MakeBundle(PixelFormat::kRgb8);
    if (!WriteBundle(rgb_dir, rgb_bundle).ok() ||
        !WriteBundle(bayer_dir, MakeBundle(PixelFormat::kBayerRg8)).ok()) {
      std::fprintf(stderr, "cannot write the benchmark bundles under %s\n", root.c_str());
      std::abort();
    }
  }
  ~Fixture() {
    std::error_code ec;
    std::filesystem::remove_all(root, ec);
  }
};

Fixture& GetFixture() {
  static Fixture fixture;
  return fixture;
}

void BM_ReadBundleRgb8(benchmark::State& state) {
  const std::string& dir = GetFixture().rgb_dir;
  for (auto _ : state) {
    absl::StatusOr<CaptureBundle> bundle = ReadBundle(dir);
    if (!bundle.ok()) state.SkipWithError(std::string(bundle.status().message()).c_str());
    benchmark::DoNotOptimize(bundle);
  }
}
BENCHMARK(BM_ReadBundleRgb8)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadBundleBayer(benchmark::State& state) {
  const std::string& dir = GetFixture().bayer_dir;
  for (auto _ : state) {
    absl::StatusOr<CaptureBundle> bundle = ReadBundle(dir);
    if (!bundle.ok()) state.SkipWithError(std::string(bundle.status().message()).c_str());
    benchmark::DoNotOptimize(bundle);
  }
}
BENCHMARK(BM_ReadBundleBayer)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadBundleBayerToRgb(benchmark::State& state) {
  const std::string& dir = GetFixture().bayer_dir;
  for (auto _ : state) {
    absl::StatusOr<CaptureBundle> bundle = ReadBundle(dir);
    if (!bundle.ok()) {
      state.SkipWithError(std::string(bundle.status().message()).c_str());
      break;
    }
    for (const Image& image : bundle->images) {
      absl::StatusOr<Image> rgb = ToRgb(image);
      benchmark::DoNotOptimize(rgb);
    }
  }
}
BENCHMARK(BM_ReadBundleBayerToRgb)->Unit(benchmark::kMillisecond)->UseRealTime();

// Demosaicing alone: the three mosaics of one Bayer bundle.
void BM_ToRgbBayer(benchmark::State& state) {
  absl::StatusOr<CaptureBundle> bundle = ReadBundle(GetFixture().bayer_dir);
  if (!bundle.ok()) {
    state.SkipWithError(std::string(bundle.status().message()).c_str());
    return;
  }
  for (auto _ : state) {
    for (const Image& image : bundle->images) {
      absl::StatusOr<Image> rgb = ToRgb(image);
      benchmark::DoNotOptimize(rgb);
    }
  }
}
BENCHMARK(BM_ToRgbBayer)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_WriteBundleRgb8(benchmark::State& state) {
  const Fixture& fixture = GetFixture();
  const std::string dir = (fixture.root / "write").string();
  for (auto _ : state) {
    const absl::Status status = WriteBundle(dir, fixture.rgb_bundle);
    if (!status.ok()) state.SkipWithError(std::string(status.message()).c_str());
  }
}
BENCHMARK(BM_WriteBundleRgb8)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace vb::capture

BENCHMARK_MAIN();
