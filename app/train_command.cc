// SPDX-License-Identifier: Apache-2.0
// vinebot train segmenter: renders simulated stops with varied lighting and pixel formats, trains
// the segmenter on them and reports it on further, held-out stops.
//   --out FILE            the model to write
//   --vines N             training stops, seeds [S, S + N) (default 16)
//   --seed-base S         (default 1000; seeds >= 9000 are refused: reserved for the benchmark)
//   --held-out M          held-out stops, seeds [S + N, S + N + M) (default 4)
//   --evaluate FILE|builtin  only score a model on the held-out stops (no training, no --out)
//   --dump-dir DIR        write held-out images, classes and errors as PNGs
//   --samples-per-class, --svm-c, --cascade-margin, --no-cascade: SegmenterTrainOptions
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "core/status_macros.h"
#include "sim/vine_generator.h"
#include "workers/capture/bundle.h"
#include "workers/capture/sim_capture.h"
#include "workers/reconstruct/segmenter.h"

namespace vb::app {
namespace {

// Seeds from here on are reserved for the reported benchmark (docs/benchmarks.md).
constexpr int64_t kReservedSeedBegin = 9000;

// A deterministic value in [0, 1) from a stop and a purpose, so every stop gets its own lighting.
double Unit(uint64_t seed, uint64_t salt) {
  uint64_t z = seed * 0x9E3779B97F4A7C15ull + salt * 0xBF58476D1CE4E5B9ull + 1;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

// Renders the stop of `seed` (vine index from the seed) through the default trinocular rig and
// appends one labelled rgb8 view per camera. Half the stops are Bayer mosaics (demosaiced as a
// real capture would be); exposure, ambient light and vignetting vary per stop.
absl::Status RenderStop(uint64_t seed, std::vector<reconstruct::LabelledView>& out) {
  const int vine = static_cast<int>(seed % 7);
  VB_ASSIGN_OR_RETURN(const sim::Scene scene, sim::GenerateScene(seed, vine));
  capture::SimCaptureOptions options;
  constexpr PixelFormat kFormats[] = {PixelFormat::kRgb8, PixelFormat::kBayerRg8,
                                      PixelFormat::kRgb8, PixelFormat::kBayerGb8,
                                      PixelFormat::kBayerGr8, PixelFormat::kBayerBg8};
  options.render.pixel_format = kFormats[seed % 6];
  options.render.exposure = 0.55 + 1.0 * Unit(seed, 1);
  options.render.ambient = 0.06 + 0.14 * Unit(seed, 2);
  options.render.vignetting = 0.2 + 0.3 * Unit(seed, 3);
  VB_ASSIGN_OR_RETURN(const capture::SimCapture capture,
                      capture::RenderSimCapture(scene, options, seed * 1000003 + vine));
  for (size_t i = 0; i < capture.bundle.images.size(); ++i) {
    VB_ASSIGN_OR_RETURN(Image rgb, capture::ToRgb(capture.bundle.images[i]));
    out.push_back({std::move(rgb), capture.labels[i]});
  }
  return absl::OkStatus();
}

// Writes each held-out view, its segmentation and its errors as PNGs for inspection: classes as
// colours (background black, foreground brown, wire white, post yellow), and in the error image
// missed pixels of a class in its colour, false detections in red.
absl::Status DumpHeldOut(const std::string& dir, const std::vector<reconstruct::LabelledView>& views,
                         const reconstruct::SegmenterModel& model) {
  constexpr uint8_t kColours[4][3] = {{0, 0, 0}, {160, 110, 60}, {255, 255, 255}, {230, 200, 0}};
  std::filesystem::create_directories(dir);
  for (size_t v = 0; v < views.size(); ++v) {
    VB_ASSIGN_OR_RETURN(const reconstruct::ClassImage pred,
                        reconstruct::Segment(views[v].rgb, model));
    const reconstruct::ClassImage truth = reconstruct::ClassesOfSimLabels(views[v].labels);
    Image classes(pred.width, pred.height, PixelFormat::kRgb8);
    Image errors(pred.width, pred.height, PixelFormat::kRgb8);
    for (size_t i = 0; i < pred.data.size(); ++i) {
      std::copy(kColours[pred.data[i]], kColours[pred.data[i]] + 3, &classes.data[3 * i]);
      if (pred.data[i] != truth.data[i]) {
        const bool missed = truth.data[i] != 0;
        const uint8_t red[3] = {255, 0, 0};
        const uint8_t* c = missed ? kColours[truth.data[i]] : red;
        std::copy(c, c + 3, &errors.data[3 * i]);
      }
    }
    VB_ASSIGN_OR_RETURN(const reconstruct::SegmenterReport r,
                        reconstruct::EvaluateSegmenter({views[v]}, model));
    std::cerr << "held-out view " << v << ": "
              << reconstruct::SegmenterReportToJson(r)["classes"].dump() << "\n";
    const std::string base = absl::StrCat(dir, "/view", v);
    VB_RETURN_IF_ERROR(capture::WritePng(base + "_image.png", views[v].rgb));
    VB_RETURN_IF_ERROR(capture::WritePng(base + "_classes.png", classes));
    VB_RETURN_IF_ERROR(capture::WritePng(base + "_errors.png", errors));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status RunTrainSegmenter(Flags& flags) {
  // --evaluate FILE|builtin: score an existing model on the held-out stops instead of training.
  VB_ASSIGN_OR_RETURN(const std::string evaluate, flags.String("evaluate", ""));
  std::string out;
  if (evaluate.empty()) {
    VB_ASSIGN_OR_RETURN(out, flags.RequiredString("out"));
  }
  VB_ASSIGN_OR_RETURN(const int64_t vines, flags.Int("vines", evaluate.empty() ? 16 : 0));
  VB_ASSIGN_OR_RETURN(const int64_t seed_base, flags.Int("seed-base", 1000));
  VB_ASSIGN_OR_RETURN(const int64_t held_out_vines, flags.Int("held-out", 4));
  reconstruct::SegmenterTrainOptions options;
  VB_ASSIGN_OR_RETURN(const int64_t samples,
                      flags.Int("samples-per-class", options.samples_per_class_per_view));
  options.samples_per_class_per_view = static_cast<int>(samples);
  VB_ASSIGN_OR_RETURN(options.svm_c, flags.Double("svm-c", options.svm_c));
  VB_ASSIGN_OR_RETURN(const double margin, flags.Double("cascade-margin", options.cascade_margin));
  options.cascade_margin = static_cast<float>(margin);
  VB_ASSIGN_OR_RETURN(const bool no_cascade, flags.Bool("no-cascade", false));
  options.cascade = !no_cascade;
  VB_ASSIGN_OR_RETURN(const std::string dump_dir, flags.String("dump-dir", ""));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (vines < (evaluate.empty() ? 1 : 0) || vines > 1000) {
    return absl::InvalidArgumentError("--vines: must be in [1, 1000] (>= 0 with --evaluate)");
  }
  if (held_out_vines < 0 || held_out_vines > 1000) {
    return absl::InvalidArgumentError("--held-out: must be in [0, 1000]");
  }
  if (seed_base < 0 || seed_base + vines + held_out_vines > kReservedSeedBegin) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--seed-base: the stops use seeds [", seed_base, ", ", seed_base + vines + held_out_vines,
        "); seeds >= ", kReservedSeedBegin, " are reserved for the benchmark"));
  }
  VB_RETURN_IF_ERROR(options.Validate());

  const auto start = std::chrono::steady_clock::now();
  std::vector<reconstruct::LabelledView> train, held_out;
  for (int64_t i = 0; i < vines + held_out_vines; ++i) {
    const auto seed = static_cast<uint64_t>(seed_base + i);
    VB_RETURN_IF_ERROR(RenderStop(seed, i < vines ? train : held_out));
    std::cerr << "rendered stop " << i + 1 << "/" << vines + held_out_vines << " (seed " << seed
              << ")\n";
  }
  const double render_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!evaluate.empty()) {
    reconstruct::SegmenterModel model = reconstruct::BuiltinSegmenterModel();
    if (evaluate != "builtin") {
      VB_ASSIGN_OR_RETURN(model, reconstruct::ReadSegmenterModel(evaluate));
    }
    VB_ASSIGN_OR_RETURN(const reconstruct::SegmenterReport report,
                        reconstruct::EvaluateSegmenter(held_out, model));
    if (!dump_dir.empty()) VB_RETURN_IF_ERROR(DumpHeldOut(dump_dir, held_out, model));
    const nlohmann::json json = {
        {"model", evaluate},
        {"held_out_seeds", {seed_base + vines, seed_base + vines + held_out_vines - 1}},
        {"held_out", reconstruct::SegmenterReportToJson(report)}};
    std::cout << json.dump(1) << "\n";
    return absl::OkStatus();
  }
  VB_ASSIGN_OR_RETURN(const reconstruct::SegmenterTrainResult result,
                      reconstruct::TrainSegmenter(train, held_out, options));
  reconstruct::SegmenterModel model = result.model;
  model.notes = absl::StrCat("vinebot train segmenter --vines ", vines, " --seed-base ", seed_base,
                             " --held-out ", held_out_vines, ": ", model.notes);
  VB_RETURN_IF_ERROR(reconstruct::WriteSegmenterModel(out, model));
  if (!dump_dir.empty()) VB_RETURN_IF_ERROR(DumpHeldOut(dump_dir, held_out, model));
  const nlohmann::json report = {
      {"model", out},
      {"train_seeds", {seed_base, seed_base + vines - 1}},
      {"held_out_seeds", {seed_base + vines, seed_base + vines + held_out_vines - 1}},
      {"train_views", train.size()},
      {"stage1_samples", result.stage1_samples},
      {"stage2_samples", result.stage2_samples},
      {"render_s", render_s},
      {"train_s", result.train_seconds},
      {"held_out", reconstruct::SegmenterReportToJson(result.held_out)}};
  std::cout << report.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
