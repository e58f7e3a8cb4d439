#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job, as far as it is built: simulate a few stops along a row, capture each through the
# simulated camera rig, check every bundle imports, reconstruct each vine, decide its pruning,
# measure its phenomics, plan the arm's motions to its cuts and score the model and cuts against
# the simulator's ground truth. Grows with every stage.
# Usage: scripts/demo.sh path/to/vinebot [OUT_DIR]
set -euo pipefail
vinebot=${1:?usage: scripts/demo.sh path/to/vinebot [OUT_DIR]}
out=${2:-out/demo}
seed=${VB_DEMO_SEED:-2026}
mkdir -p "$out"
echo "vinebot demo: simulated row (seed $seed), three stops -> $out"
for vine in 0 1 2; do
  dir="$out/vine_$vine"
  rm -rf "$dir"
  # Bayer capture with 1 px calibration error, as a real rig would deliver.
  "$vinebot" sim render --seed "$seed" --vine "$vine" --out "$dir" \
    --pixel-format bayer_rg8 --calibration-error-px 1.0
  "$vinebot" bundle info --bundle "$dir" > "$dir/info.json"
  "$vinebot" reconstruct --bundle "$dir" --out "$dir/model.json" > "$dir/reconstruct.json"
  "$vinebot" decide --model "$dir/model.json" --out "$dir/cut_plan.json" > "$dir/decide.json"
  "$vinebot" phenomics --model "$dir/model.json" --plan "$dir/cut_plan.json" > "$dir/phenomics.json"
  "$vinebot" plan --model "$dir/model.json" --cuts "$dir/cut_plan.json" \
    --calibration "$dir/calibration.yaml" \
    --out "$dir/trajectory.json" > "$dir/plan.json" 2> "$dir/plan_notes.txt"
  "$vinebot" evaluate --model "$dir/model.json" --truth "$dir/ground_truth.json" > "$dir/metrics.json"
  echo "  vine $vine: $(tr -d ' \n' < "$dir/metrics.json" | cut -c1-160)"
  echo "    plan: $(tr -d ' \n' < "$dir/plan.json" | cut -c1-160)"
done
echo "vinebot demo: bundles, model.json, cut_plan.json, phenomics.json, trajectory.json and"
echo "metrics.json per vine in $out. Later stages (cut, server) are not built yet."
