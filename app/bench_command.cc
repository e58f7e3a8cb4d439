// SPDX-License-Identifier: Apache-2.0
// vinebot bench reconstruct: the reconstruction benchmark of issue 3. Renders N simulated stops
// (seeds seed_base .. seed_base + N - 1, vine 1 of each vineyard, sensor noise, the reported
// calibration perturbed by --calibration-error-px RMS), reconstructs each from the bundle's
// images exactly as `vinebot reconstruct` does (Bayer demosaicing included), evaluates it
// against the ground truth (the cut-point metrics by deciding on both, --policy or the default)
// and prints per-stage timings and mean metrics as one JSON object.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "app/commands.h"
#include "app/decide_evaluation.h"
#include "app/reconstruct_flags.h"
#include "app/reconstruct_report.h"
#include "core/model_metrics.h"
#include "core/statistics.h"
#include "core/status_macros.h"
#include "core/view_coverage.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/capture/sim_capture.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::app {
namespace {

// The nearest-rank quantile (core/statistics.h's Quantile interpolates; the p90 figures in
// docs/benchmarks.md were measured with this one).
double NearestRankQuantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

// Mean and median over vines of each cut-point metric. The cut errors are over the vines with at
// least one matched cut (a vine without one has no error to average); the fractions and counts
// are over every vine evaluated, those decide could not plan for included (all truth cuts
// missed).
nlohmann::json CutMetricsSummary(const std::vector<DecidedCutMetrics>& vines) {
  nlohmann::json mean = nlohmann::json::object();
  nlohmann::json median = nlohmann::json::object();
  auto summarise = [&](const char* key, auto value, bool matched_only) {
    std::vector<double> v;
    for (const DecidedCutMetrics& d : vines)
      if (!matched_only || d.metrics.matched_cuts > 0) v.push_back(value(d.metrics));
    double sum = 0.0;
    for (double x : v) sum += x;
    mean[key] = v.empty() ? 0.0 : sum / v.size();
    median[key] = Median(v);
  };
  summarise("cut_error_median_m", [](const CutMetrics& m) { return m.cut_error_median_m; }, true);
  summarise("cut_error_p95_m", [](const CutMetrics& m) { return m.cut_error_p95_m; }, true);
  summarise("cuts_missed_fraction", [](const CutMetrics& m) { return m.cuts_missed_fraction; },
            false);
  summarise("cuts_spurious_fraction",
            [](const CutMetrics& m) { return m.cuts_spurious_fraction; }, false);
  summarise("cuts_on_kept_canes",
            [](const CutMetrics& m) { return double(m.cuts_on_kept_canes); }, false);
  int truth_cuts = 0, model_cuts = 0, matched = 0, on_kept = 0, without_plan = 0;
  for (const DecidedCutMetrics& d : vines) {
    truth_cuts += d.metrics.truth_cuts;
    model_cuts += d.metrics.model_cuts;
    matched += d.metrics.matched_cuts;
    on_kept += d.metrics.cuts_on_kept_canes;
    without_plan += !d.model_decide_error.empty();
  }
  return {{"mean", mean},         {"median", median},       {"truth_cuts", truth_cuts},
          {"model_cuts", model_cuts}, {"matched_cuts", matched}, {"cuts_on_kept_canes", on_kept},
          {"vines_without_plan", without_plan}};
}

double MeanOf(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / v.size();
}

// "15,20,30" -> {0.015, 0.020, 0.030}: the --tolerances-mm list, each in (0, 1000] mm.
absl::StatusOr<std::vector<double>> ParseTolerancesMm(const std::string& list) {
  std::vector<double> metres;
  if (list.empty()) return metres;
  for (const absl::string_view item : absl::StrSplit(list, ',')) {
    double mm = 0.0;
    if (!absl::SimpleAtod(item, &mm) || !(mm > 0.0 && mm <= 1000.0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--tolerances-mm: '", item, "' is not a distance in (0, 1000] mm"));
    }
    metres.push_back(mm / 1000.0);
  }
  return metres;
}

// The key of a tolerance in the JSON: its millimetres, as few digits as needed ("20", "12.5").
std::string ToleranceKey(double metres) { return absl::StrCat(metres * 1000.0); }

// Recall, precision and connectivity of `model` scored with each tolerance in place of
// MetricsOptions::match_distance_m (the same 5 mm samples, the same route rule).
absl::StatusOr<nlohmann::json> ScoreAtTolerances(const VineModel& model, const VineModel& truth,
                                                 const std::vector<double>& tolerances_m) {
  nlohmann::json out = nlohmann::json::object();
  for (const double t : tolerances_m) {
    MetricsOptions options;
    options.match_distance_m = t;
    VB_ASSIGN_OR_RETURN(const ReconstructionMetrics m,
                        EvaluateReconstruction(model, truth, options));
    out[ToleranceKey(t)] = {{"cane_recall", m.cane_recall},
                            {"cane_precision", m.cane_precision},
                            {"connectivity", m.connectivity}};
  }
  return out;
}

}  // namespace

absl::Status RunBenchReconstruct(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const int64_t vines, flags.Int("vines", 10));
  VB_ASSIGN_OR_RETURN(const int64_t seed_base, flags.Int("seed-base", 9000));
  VB_ASSIGN_OR_RETURN(const double calibration_error_px, flags.Double("calibration-error-px", 1.0));
  VB_ASSIGN_OR_RETURN(const PixelFormat format,
                      flags.Format("pixel-format", PixelFormat::kBayerRg8));
  VB_ASSIGN_OR_RETURN(const int64_t threads, flags.Int("threads", 2));
  VB_ASSIGN_OR_RETURN(const bool per_vine, flags.Bool("per-vine", false));
  // --tolerances-mm 15,20,30: recall, precision and connectivity also scored with these match
  // distances in place of the metrics' 10 mm (how far the missed length lies from the model),
  // as "by_tolerance_mm" in the summary (means over vines) and in each --per-vine entry.
  VB_ASSIGN_OR_RETURN(const std::string tolerances_flag, flags.String("tolerances-mm", ""));
  VB_ASSIGN_OR_RETURN(const std::vector<double> tolerances_m,
                      ParseTolerancesMm(tolerances_flag));
  // --input images (the real pipeline), labels (perfect segmentation: the renderer's label
  // images replace step 1) or truth (perfect 2D: views drawn from the true model replace steps
  // 1-2). The last two locate where accuracy is lost.
  VB_ASSIGN_OR_RETURN(const std::string input, flags.String("input", "images"));
  // With --input truth: break each drawn cane at crossings (SyntheticViewOptions, a diagnosis).
  VB_ASSIGN_OR_RETURN(const double truth_break_px, flags.Double("truth-break-px", 0.0));
  VB_ASSIGN_OR_RETURN(const bool truth_merge, flags.Bool("truth-merge-overlaps", false));
  // Cut-point metrics decide under this policy (default: PruningPolicy's defaults).
  VB_ASSIGN_OR_RETURN(const std::string policy_path, flags.String("policy", ""));
  // --rig-refine off, canes (canes only) or trellis (canes, wires and posts): for comparisons.
  VB_ASSIGN_OR_RETURN(const std::string rig_refine, flags.String("rig-refine", "canes"));
  // --fiducials: the platform carries fiducials (sim/fiducials.h), drawn in the images and listed
  // in the calibration; the rig refinement uses them unless --rig-refine off.
  VB_ASSIGN_OR_RETURN(const bool fiducials,
                      flags.Bool("fiducials", capture::SimCaptureOptions{}.fiducials));
  // --rig-baseline M: the simulated rig's triangle side (sim::RigOptions::baseline_m), for
  // studies of the rig; the classifiers were trained with the default.
  VB_ASSIGN_OR_RETURN(const double rig_baseline,
                      flags.Double("rig-baseline", sim::RigOptions{}.baseline_m));
  // --rig-apex-raise M, --rig-apex-aim-up M: the apex camera raised this far above the
  // triangle, and aimed this far above the pair's target (apex_raise_m, apex_aim_up_m).
  VB_ASSIGN_OR_RETURN(const double rig_apex_raise,
                      flags.Double("rig-apex-raise", sim::RigOptions{}.apex_raise_m));
  VB_ASSIGN_OR_RETURN(const double rig_apex_aim_up,
                      flags.Double("rig-apex-aim-up", sim::RigOptions{}.apex_aim_up_m));
  // --rig-cameras N (1-4; camera_count) and --rig-upper-side M (upper_pair_side_m): a study of
  // four cameras, the triangle's pair with a second pair at the apex's height.
  VB_ASSIGN_OR_RETURN(const int64_t rig_cameras,
                      flags.Int("rig-cameras", sim::RigOptions{}.camera_count));
  VB_ASSIGN_OR_RETURN(const double rig_upper_side,
                      flags.Double("rig-upper-side", sim::RigOptions{}.upper_pair_side_m));
  // --extend on|off: the single-view extension of cane tips (step 4c); default as ExtendOptions.
  VB_ASSIGN_OR_RETURN(const bool extend,
                      flags.Bool("extend", reconstruct::ExtendOptions{}.enabled));
  // --grow on|off: two-view growth of assembled cane ends (step 4d); default as GrowOptions.
  VB_ASSIGN_OR_RETURN(const bool grow, flags.Bool("grow", reconstruct::GrowOptions{}.enabled));
  // --grow-refit M: GrowOptions::refit_span_m, the grown stretch refitted jointly (0: off);
  // --grow-max-length M: GrowOptions::max_length_m (and alongside_max_m at most M).
  VB_ASSIGN_OR_RETURN(const double grow_refit,
                      flags.Double("grow-refit", reconstruct::GrowOptions{}.refit_span_m));
  VB_ASSIGN_OR_RETURN(const double grow_max_length,
                      flags.Double("grow-max-length", reconstruct::GrowOptions{}.max_length_m));
  if (rig_refine != "off" && rig_refine != "canes" && rig_refine != "trellis")
    return absl::InvalidArgumentError("--rig-refine must be off, canes or trellis");
  if (input != "images" && input != "labels" && input != "truth")
    return absl::InvalidArgumentError("--input must be images, labels or truth");
  // --alpha, --select-context, --context-alpha: the match selection; --head-bases and its
  // --head-bases-* flags: the cane bases at the head (app/reconstruct_flags.h).
  reconstruct::ReconstructOptions options;
  VB_RETURN_IF_ERROR(ReadSelectionFlags(flags, &options.correspondence));
  VB_RETURN_IF_ERROR(ReadStrandHalfFlags(flags, &options.strand_halves));  // step 2b
  VB_RETURN_IF_ERROR(ReadSweepFlags(flags, &options.sweep));  // --sweep (step 4e)
  // --head-peel, --head-min-cell, --head-depth-factor, --head-leaf-fraction,
  // --head-centre-on-trunk, --head-leaf-wood-px: the head's options
  // (app/reconstruct_flags.h).
  VB_RETURN_IF_ERROR(ReadHeadFlags(flags, &options.head));
  VB_RETURN_IF_ERROR(ReadHeadBasesFlags(flags, &options.head_bases));
  // --extend-row, --extend-across, --extend-support, --extend-depth-sd (step 4c) and
  // --min-join-probability, --rescue-*, --keep-*, --drop-thickening (step 6).
  VB_RETURN_IF_ERROR(ReadExtendFlags(flags, &options.extend));
  VB_RETURN_IF_ERROR(ReadConnectFlags(flags, &options.connect));
  VB_RETURN_IF_ERROR(ReadHeadExitFlags(flags, &options.connect));  // --head-exit-* (step 6c)
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!(truth_break_px >= 0.0 && truth_break_px <= 100.0))
    return absl::InvalidArgumentError("--truth-break-px must be in [0, 100]");
  if (truth_break_px > 0.0 && input != "truth")
    return absl::InvalidArgumentError("--truth-break-px needs --input truth");
  if (truth_merge && truth_break_px <= 0.0)
    return absl::InvalidArgumentError("--truth-merge-overlaps needs --truth-break-px > 0");
  if (vines < 1 || vines > 10000)
    return absl::InvalidArgumentError("--vines must be in [1, 10000]");
  if (seed_base < 0) return absl::InvalidArgumentError("--seed-base must be >= 0");
  if (threads < 1 || threads > 64)
    return absl::InvalidArgumentError("--threads must be in [1, 64]");
  VB_ASSIGN_OR_RETURN(const PruningPolicy policy, PolicyOrDefault(policy_path));

  capture::SimCaptureOptions sim_options;
  sim_options.calibration_error_px = calibration_error_px;
  sim_options.render.pixel_format = format;
  sim_options.fiducials = fiducials;
  // Each rig flag is checked on its own against sim::RigOptions::Validate, whose message names
  // the field, so that a bad value is reported under the flag the user typed.
  for (const auto& [flag, field, value] :
       {std::tuple{"--rig-baseline", &sim::RigOptions::baseline_m, rig_baseline},
        std::tuple{"--rig-apex-raise", &sim::RigOptions::apex_raise_m, rig_apex_raise},
        std::tuple{"--rig-apex-aim-up", &sim::RigOptions::apex_aim_up_m, rig_apex_aim_up},
        std::tuple{"--rig-upper-side", &sim::RigOptions::upper_pair_side_m, rig_upper_side}}) {
    sim_options.rig.*field = value;
    if (const absl::Status s = sim_options.rig.Validate(); !s.ok())
      return absl::InvalidArgumentError(absl::StrCat(flag, ": ", s.message()));
  }
  if (rig_cameras < 1 || rig_cameras > 4)
    return absl::InvalidArgumentError(
        absl::StrCat("--rig-cameras: must be in [1, 4], is ", rig_cameras));
  sim_options.rig.camera_count = static_cast<int>(rig_cameras);
  VB_RETURN_IF_ERROR(sim_options.Validate());
  options.threads = static_cast<int>(threads);
  options.rig_refine.enabled = rig_refine != "off";
  options.rig_refine.use_trellis = rig_refine == "trellis";
  options.extend.enabled = extend;
  options.grow.enabled = grow;
  options.grow.refit_span_m = grow_refit;
  options.grow.max_length_m = grow_max_length;
  options.grow.alongside_max_m = std::min(options.grow.alongside_max_m, grow_max_length);
  // One clear error naming the field before any stop is rendered (--grow-refit and
  // --grow-max-length are checked here, by GrowOptions::Validate).
  VB_RETURN_IF_ERROR(options.Validate());
  const reconstruct::SegmenterModel& segmenter = reconstruct::BuiltinSegmenterModel();

  std::vector<ReconstructionMetrics> metrics;
  std::vector<ViewCoverage> coverage;
  std::vector<DecidedCutMetrics> cut_metrics;
  std::vector<reconstruct::StageTimings> timings;
  std::vector<double> render_s;
  // Per vine: the pieces of left-out wood the model carries as obstacles, and their length.
  std::vector<double> obstacles_per_vine, obstacle_length_per_vine_m;
  // Mean over cameras of the reprojection error (sim::ReprojectionRmsPx at 0.8 m) against the true
  // rig: of the reported calibration and of the rig the model was built with.
  std::vector<double> rig_error_reported_px, rig_error_used_px;
  nlohmann::json per_vine_json = nlohmann::json::array();
  std::vector<nlohmann::json> by_tolerance;  // per vine reconstructed, with --tolerances-mm
  int failures = 0, empty = 0;
  for (int64_t i = 0; i < vines; ++i) {
    const uint64_t seed = static_cast<uint64_t>(seed_base + i);
    const int vine = 1;
    auto t = std::chrono::steady_clock::now();
    VB_ASSIGN_OR_RETURN(const sim::Scene scene, sim::GenerateScene(seed, vine));
    VB_ASSIGN_OR_RETURN(const capture::SimCapture capture,
                        capture::RenderSimCapture(scene, sim_options, seed * 1000003 + vine));
    std::vector<Image> images;
    for (const Image& image : capture.bundle.images) {
      VB_ASSIGN_OR_RETURN(Image rgb, capture::ToRgb(image));
      images.push_back(std::move(rgb));
    }
    render_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
    // The bundle's calibration is the reported (perturbed) one, as a real rig's would be.
    RigCalibration rig;
    for (size_t c = 0; c < capture.bundle.images.size(); ++c)
      rig.cameras.push_back(capture.bundle.CalibrationOf(c));
    rig.fiducials = capture.bundle.calibration.fiducials;
    absl::StatusOr<reconstruct::ReconstructResult> result;
    if (input == "images") {
      result = reconstruct::Reconstruct(images, rig, segmenter, options, Deadline::In(60.0));
    } else {
      std::vector<reconstruct::View2D> views;
      if (input == "truth") {
        // Drawn through the reported calibration: the 3D stages see consistent 2D evidence.
        reconstruct::SyntheticViewOptions drawn;
        drawn.break_at_crossings_px = truth_break_px;
        drawn.merge_overlaps = truth_merge;
        views = reconstruct::SyntheticViews(capture.ground_truth, rig, drawn);
      } else {
        for (size_t c = 0; c < capture.labels.size(); ++c) {
          VB_ASSIGN_OR_RETURN(reconstruct::View2D view,
                              reconstruct::ExtractStructure(
                                  reconstruct::ClassesOfSimLabels(capture.labels[c]),
                                  rig.cameras[c], options.structure, Deadline::In(60.0)));
          // The halves as Reconstruct finds them, from the rendered image (none when off).
          VB_ASSIGN_OR_RETURN(view.strand_halves,
                              reconstruct::FindStrandHalves(view, images[c],
                                                            options.strand_halves));
          views.push_back(std::move(view));
        }
      }
      result = reconstruct::ReconstructFromViews(views, rig, options, Deadline::In(60.0));
    }
    nlohmann::json entry = {{"seed", seed}, {"vine", vine}};
    if (!result.ok()) {
      ++failures;
      entry["error"] = std::string(result.status().message());
      per_vine_json.push_back(entry);
      continue;
    }
    empty += result->model.canes.empty();
    obstacles_per_vine.push_back(static_cast<double>(result->model.obstacles.size()));
    obstacle_length_per_vine_m.push_back(0.0);
    for (const WoodObstacle& o : result->model.obstacles)
      obstacle_length_per_vine_m.back() += o.polyline.Length();
    {
      VB_ASSIGN_OR_RETURN(const capture::SimRig sim_rig,
                          capture::MakeSimRig(sim_options, seed * 1000003 + vine));
      double reported = 0.0, used = 0.0;
      for (size_t c = 0; c < rig.cameras.size(); ++c) {
        const auto truth = sim_rig.true_rig.IndexOf(rig.cameras[c].name);
        if (!truth) continue;
        reported += sim::ReprojectionRmsPx(sim_rig.true_rig.cameras[*truth], rig.cameras[c]);
        used += sim::ReprojectionRmsPx(sim_rig.true_rig.cameras[*truth], result->rig.cameras[c]);
      }
      rig_error_reported_px.push_back(reported / rig.cameras.size());
      rig_error_used_px.push_back(used / rig.cameras.size());
      entry["rig_error_px"] = {{"reported", rig_error_reported_px.back()},
                               {"used", rig_error_used_px.back()}};
    }
    VB_ASSIGN_OR_RETURN(const ReconstructionMetrics m,
                        EvaluateReconstruction(result->model, capture.ground_truth));
    metrics.push_back(m);
    // The ceiling the field of view puts on recall: true length inside two or more of the
    // images of the rig as it really is (not the perturbed calibration the pipeline is given).
    VB_ASSIGN_OR_RETURN(const capture::SimRig sim_rig,
                        capture::MakeSimRig(sim_options, seed * 1000003 + vine));
    VB_ASSIGN_OR_RETURN(const ViewCoverage view_coverage,
                        EvaluateViewCoverage(capture.ground_truth, sim_rig.true_rig));
    coverage.push_back(view_coverage);
    VB_ASSIGN_OR_RETURN(DecidedCutMetrics cuts,
                        EvaluateDecidedCuts(result->model, capture.ground_truth, policy));
    entry["cut_metrics"] = DecidedCutMetricsToJson(cuts);
    cut_metrics.push_back(std::move(cuts));
    timings.push_back(result->timings);
    entry["metrics"] = MetricsToJson(m);
    entry["metrics"].update(ViewCoverageToJson(view_coverage));
    entry["reconstruction"] = ReconstructReport(*result);
    if (!tolerances_m.empty()) {
      VB_ASSIGN_OR_RETURN(entry["by_tolerance_mm"],
                          ScoreAtTolerances(result->model, capture.ground_truth, tolerances_m));
      by_tolerance.push_back(entry["by_tolerance_mm"]);
    }
    per_vine_json.push_back(entry);
  }

  nlohmann::json mean = nlohmann::json::object();
  auto average = [&](const char* key, double ReconstructionMetrics::*field) {
    double sum = 0;
    for (const ReconstructionMetrics& m : metrics) sum += m.*field;
    mean[key] = metrics.empty() ? 0.0 : sum / metrics.size();
  };
  average("cane_recall", &ReconstructionMetrics::cane_recall);
  average("cane_precision", &ReconstructionMetrics::cane_precision);
  average("connectivity", &ReconstructionMetrics::connectivity);
  average("connectivity_strict", &ReconstructionMetrics::connectivity_strict);
  average("cane_recall_near_head", &ReconstructionMetrics::cane_recall_near_head);
  average("near_head_length_fraction", &ReconstructionMetrics::near_head_length_fraction);
  average("wire_recall", &ReconstructionMetrics::wire_recall);
  average("wire_precision", &ReconstructionMetrics::wire_precision);
  average("head_enclosed_fraction", &ReconstructionMetrics::head_enclosed_fraction);
  average("head_volume_ratio", &ReconstructionMetrics::head_volume_ratio);
  // Means over vines, like the metrics above (the same vines: those reconstructed).
  auto average_coverage = [&](const char* key, double ViewCoverage::*field) {
    double sum = 0;
    for (const ViewCoverage& c : coverage) sum += c.*field;
    mean[key] = coverage.empty() ? 0.0 : sum / coverage.size();
  };
  average_coverage("cane_length_in_two_views_fraction", &ViewCoverage::in_two_or_more_fraction);
  average_coverage("cane_length_in_one_view_fraction", &ViewCoverage::in_one_fraction);
  average_coverage("cane_length_in_no_view_fraction", &ViewCoverage::in_none_fraction);
  average_coverage("trunk_length_in_fewer_than_two_views_fraction",
                   &ViewCoverage::trunk_in_fewer_than_two_fraction);
  const nlohmann::json cuts = CutMetricsSummary(cut_metrics);
  double min_head = 1.0;
  for (const ReconstructionMetrics& m : metrics)
    min_head = std::min(min_head, m.head_enclosed_fraction);

  nlohmann::json stage_median = nlohmann::json::object();
  nlohmann::json stage_p90 = nlohmann::json::object();
  auto stage = [&](const char* key, double reconstruct::StageTimings::*field) {
    std::vector<double> v;
    for (const auto& t : timings) v.push_back(t.*field);
    stage_median[key] = Median(v);
    stage_p90[key] = NearestRankQuantile(v, 0.9);
  };
  stage("segment_s", &reconstruct::StageTimings::segment_s);
  stage("structure_s", &reconstruct::StageTimings::structure_s);
  stage("correspondence_s", &reconstruct::StageTimings::correspondence_s);
  stage("rig_refine_s", &reconstruct::StageTimings::rig_refine_s);
  stage("assembly_s", &reconstruct::StageTimings::assembly_s);
  stage("sweep_s", &reconstruct::StageTimings::sweep_s);
  stage("grow_s", &reconstruct::StageTimings::grow_s);
  stage("head_s", &reconstruct::StageTimings::head_s);
  stage("connect_s", &reconstruct::StageTimings::connect_s);
  stage("refine_s", &reconstruct::StageTimings::refine_s);
  stage("extend_s", &reconstruct::StageTimings::extend_s);
  stage("trellis_s", &reconstruct::StageTimings::trellis_s);
  stage("total_s", &reconstruct::StageTimings::total_s);

  nlohmann::json out = {{"vines", vines},
                        {"seed_base", seed_base},
                        {"vine_index", 1},
                        {"pixel_format", std::string(PixelFormatName(format))},
                        {"calibration_error_px", calibration_error_px},
                        {"threads", threads},
                        {"input", input},
                        {"failures", failures},
                        {"empty_models", empty},
                        {"mean", mean},
                        {"cut_metrics", cuts},
                        {"min_head_enclosed_fraction", min_head},
                        {"stage_median_s", stage_median},
                        {"stage_p90_s", stage_p90},
                        {"render_median_s", Median(render_s)},
                        {"obstacles_per_vine",
                         {{"median", Median(obstacles_per_vine)},
                          {"mean", MeanOf(obstacles_per_vine)},
                          {"max", obstacles_per_vine.empty()
                                      ? 0.0
                                      : *std::max_element(obstacles_per_vine.begin(),
                                                          obstacles_per_vine.end())},
                          {"length_median_m", Median(obstacle_length_per_vine_m)},
                          {"length_mean_m", MeanOf(obstacle_length_per_vine_m)}}},
                        {"fiducials", fiducials},
                        {"rig_error_px",
                         {{"reported_mean", MeanOf(rig_error_reported_px)},
                          {"used_mean", MeanOf(rig_error_used_px)},
                          {"used_median", Median(rig_error_used_px)}}}};
  if (!tolerances_m.empty()) {
    nlohmann::json& summary = out["by_tolerance_mm"];
    for (const double t : tolerances_m) {
      for (const char* key : {"cane_recall", "cane_precision", "connectivity"}) {
        double sum = 0.0;
        for (const nlohmann::json& v : by_tolerance) sum += v[ToleranceKey(t)][key].get<double>();
        summary[ToleranceKey(t)][key] = by_tolerance.empty() ? 0.0 : sum / by_tolerance.size();
      }
    }
  }
  if (per_vine) out["per_vine"] = per_vine_json;
  std::cout << out.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
