// SPDX-License-Identifier: Apache-2.0
// Accuracy of a reconstructed vine model against ground truth: the metrics of ARCHITECTURE.md
// ("Accuracy metrics") that `vinebot evaluate` prints and the benchmarks average.
// Thread-safe (pure functions).
#pragma once

#include "absl/status/statusor.h"
#include "core/vine_model.h"
#include "nlohmann/json.hpp"

namespace vb {

struct MetricsOptions {
  double sample_step_m = 0.005;   // ground truth and model are sampled every 5 mm
  double match_distance_m = 0.010;  // a sample matches if within 10 mm of the other's axis
  // Wires are scored on the stretch of row the rig sees: |x| <= wire_half_span_m (the default
  // trinocular rig sees about +-0.9 m of the vine plane at 0.8 m).
  double wire_half_span_m = 0.8;
  double head_grid_m = 0.002;      // grid spacing for the head volume integral
  // cane_recall_near_head scores the true length within this distance of the true head's
  // surface (inside it included): where the cane bases, and so most cuts, are.
  double near_head_m = 0.05;
};

struct ReconstructionMetrics {
  // Fraction of ground-truth trunk + cane length (kinds trunk and cane; old spurs are part of
  // the head region and excluded) lying within match_distance_m of a reconstructed cane.
  double cane_recall = 0.0;
  // Fraction of reconstructed cane length (any kind) within match_distance_m of a ground-truth
  // cane (any kind, old spurs included).
  double cane_precision = 0.0;
  // Fraction of ground-truth trunk + cane length that is recalled by a reconstructed cane whose
  // route to the trunk is the true one: every cane on its parent chain below the trunk is mostly
  // (by length) a reconstruction of the true cane's own ancestors (or of the cane itself). A cane hung on a
  // neighbour it merely crosses is not connected. Unmatched length counts as unconnected, so
  // connectivity <= cane_recall.
  double connectivity = 0.0;
  // connectivity that also asks where the route meets the trunk: a model cane hung directly on
  // the trunk (or on the head, whose canes name the trunk as their parent) counts only if the true
  // cane it stands for grows from the trunk or head too. connectivity counts any cane hung there
  // as connected, so that a model hanging every cane on the trunk would score connectivity =
  // recall; this does not. Not a target of ARCHITECTURE.md (s28). connectivity_strict <=
  // connectivity.
  double connectivity_strict = 0.0;
  // cane_recall restricted to the true trunk + cane length within near_head_m of the surface of
  // the true head's spheres (1 if there is none), and that length's share of the whole. Not a
  // target of ARCHITECTURE.md: it shows how much of the wood the cuts are made on is modelled.
  double cane_recall_near_head = 0.0;
  double near_head_length_fraction = 0.0;
  // Fraction of ground-truth wire length with |x| <= wire_half_span_m within match_distance_m
  // of a reconstructed wire, and of reconstructed wire length (same span) near a true wire.
  double wire_recall = 0.0;
  double wire_precision = 0.0;
  // Fraction of the true head volume (union of spheres) inside the model's head spheres.
  // 1 if the truth has no head.
  double head_enclosed_fraction = 0.0;
  // Model head volume / true head volume (how loose the enclosure is); 0 if no true head.
  double head_volume_ratio = 0.0;
  double truth_cane_length_m = 0.0;   // the denominators, for weighting means over vines
  double model_cane_length_m = 0.0;
  int model_canes = 0;
  int truth_canes = 0;
};

// Compares `model` with `truth`. INVALID_ARGUMENT (naming "model" or "truth") if either fails
// VineModel::Validate or the options are not positive and finite.
absl::StatusOr<ReconstructionMetrics> EvaluateReconstruction(const VineModel& model,
                                                             const VineModel& truth,
                                                             const MetricsOptions& options = {});

// Volume (m^3) of the union of `spheres` by a grid integral: cells of side grid_m (coarsened so
// that the bounding box is at most 200 cells long) are counted when their centre lies inside a
// sphere. 0 for no spheres. Precondition: grid_m > 0.
double SphereUnionVolume(const std::vector<Sphere>& spheres, double grid_m);

// {"cane_recall": ..., ...} with the keys named as the fields above.
nlohmann::json MetricsToJson(const ReconstructionMetrics& metrics);

}  // namespace vb
