#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job, as far as it is built: simulate a few stops along a row, capture each through the
# simulated camera rig, and check every bundle imports. Grows with every stage.
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
  echo "  vine $vine: $(ls "$dir" | tr '\n' ' ')"
done
echo "vinebot demo: bundles in $out (images cam*.png, labels_cam*.png, ground_truth.json)."
echo "Later stages (reconstruct, decide, plan, cut) are not built yet."
