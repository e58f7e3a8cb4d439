// SPDX-License-Identifier: Apache-2.0
// The vinebot subcommands. Each parses its flags and calls library code; it returns the
// outcome, printed by main(). Results go to files or stdout; messages to stderr.
#pragma once

#include "absl/status/status.h"
#include "app/flags.h"

namespace vb::app {

// vinebot sim render --seed S --vine K --out DIR [...]: renders a simulated stop into a capture
// bundle with ground_truth.json and label images.
absl::Status RunSimRender(Flags& flags);

// vinebot capture --source sim|aravis --out DIR [...]: captures one stop into a bundle.
absl::Status RunCapture(Flags& flags);

// vinebot bundle info --bundle DIR: imports (validating everything) and prints a JSON summary.
absl::Status RunBundleInfo(Flags& flags);

// vinebot reconstruct --bundle DIR --out model.json [--deadline-s T]: one stop's images -> a
// vine model (workers/reconstruct).
absl::Status RunReconstruct(Flags& flags);

// vinebot evaluate --model model.json --truth ground_truth.json [--policy policy.json]
// [--calibration calibration.yaml]: prints the accuracy metrics of ARCHITECTURE.md as one JSON
// object, the cut-point metrics included (decide run on both models under the default or given
// policy), and with a calibration the view coverage of the truth (core/view_coverage.h).
absl::Status RunEvaluate(Flags& flags);

// vinebot decide --model model.json [--policy policy.json] [--weights weights.json]
// [--deadline-s T] --out cut_plan.json: decides the cut plan of a vine model (workers/decide);
// notes go to stderr, a one-line JSON summary to stdout.
absl::Status RunDecide(Flags& flags);

// vinebot phenomics --model model.json [--plan cut_plan.json | --policy policy.json]
// [--weights weights.json]: prints the vine's phenomics as JSON; without --plan the plan is
// decided here (default or given policy) so the pruning weight and kept length are filled in.
absl::Status RunPhenomics(Flags& flags);

// vinebot bench reconstruct --vines N --seed-base S: renders, reconstructs and evaluates N
// simulated vines; prints per-stage timings and mean metrics as JSON.
absl::Status RunBenchReconstruct(Flags& flags);

// vinebot train segmenter --out FILE [...]: trains the pixel classifier on simulated stops.
absl::Status RunTrainSegmenter(Flags& flags);

// vinebot sim decide-labels --vines N --seed-base S --out DIR [--policy policy.json]: simulated
// vines labelled by the expert rule set (sim/expert_pruner.h), as NAME.model.json + NAME.plan.json.
absl::Status RunSimDecideLabels(Flags& flags);

// vinebot train decide --labels DIR [--holdout DIR | --holdout-fraction F] [--epochs N]
// [--out weights.json]: learns the scheme weights (workers/decide/scheme_learning.h) and prints
// train and held-out agreement with the labels as JSON.
absl::Status RunTrainDecide(Flags& flags);

// vinebot plan --model model.json --cuts cut_plan.json --out trajectory.json [--tool T]
// [--checker C] [--calibration calibration.yaml] [--deadline-s T]: plans the arm's motions to
// every cut (workers/plan), avoiding the model's left-out wood (its obstacles) and the cameras
// where the stop's calibration puts them; prints a one-line JSON summary (planned cuts, unplanned
// cuts with reasons, duration).
absl::Status RunPlan(Flags& flags);

// vinebot bench plan --vines N --seed-base S [--checkers a,b,c] [--verify]: plans N simulated
// vines with each collision checker and prints the planning benchmark of issue 5 as JSON.
absl::Status RunBenchPlan(Flags& flags);

}  // namespace vb::app
