// SPDX-License-Identifier: Apache-2.0
// Support for CutLoss.DISABLED_Report (cut_loss_diagnose_test.cc): a stop rendered and
// reconstructed as `vinebot bench reconstruct` does it, and the geometric look-ups the report
// classes cuts with. Diagnosis only; pure functions but for MakeStop's cache files.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/vine_model.h"
#include "workers/decide/scheme.h"

namespace vb::cutloss {

struct Stop {
  VineModel truth;
  VineModel model;
};

// Vine 1 of `seed`, rendered as the bench renders it (Bayer, fiducials, 1 px calibration error)
// and reconstructed from `input`: "images" (the pipeline), "labels" (the renderer's labels
// replace segmentation) or "truth" (SyntheticViews of the ground truth). With a non-empty `cache`
// directory the truth and the model are written there (model_SEED_INPUT.json, truth_SEED.json)
// and read back instead when both exist. The environment's VB_HEAD_BASES (0 or 1) sets
// ReconstructOptions::head_bases.enabled, VB_HEAD_BASES_CURVE its curve_gain,
// VB_HEAD_BASES_SKELETON its max_skeleton_px; VB_HEAD_DEPTH_FACTOR, VB_HEAD_LEAF_FRACTION,
// VB_HEAD_MIN_CELL, VB_HEAD_CENTRE_ON_TRUNK and VB_HEAD_PEEL (0 or 1) the head's options.
// Errors: a variable that is not a number (EnvNumber) or fails the options' Validate, naming it;
// the renderer's, the reconstruction's, file I/O.
absl::StatusOr<Stop> MakeStop(uint64_t seed, const std::string& input, const std::string& cache);

// The number the environment variable `name` holds, or nullopt when it is not set. INVALID_ARGUMENT
// naming the variable when its value is not one finite number (empty, trailing text, "nan").
absl::StatusOr<std::optional<double>> EnvNumber(const char* name);

// Nearest cane of `m` to `p`: its index (-1 if `m` has no canes); its distance and the arc length
// of the nearest axis point are written to *distance and *arc.
int Nearest(const VineModel& m, const Eigen::Vector3d& p, double* distance, double* arc);

// Per model cane: the index of the truth cane most of its 5 mm samples lie within 10 mm of, or -1.
std::vector<int> Correspondence(const VineModel& model, const VineModel& truth);

// Distance from p to the surface of the head's union of spheres (negative inside); 1e9 without
// spheres.
double HeadSurfaceDistance(const HeadModel& head, const Eigen::Vector3d& p);

// The truth's scheme carried over to the model: each truth kept cane and spur to the model
// candidate that covers most of its first 0.3 m (within 10 mm), once each; a kept cane or spur
// growing from another chosen one is dropped. May be infeasible (decide::IsFeasible) when the
// model has fewer suitable candidates.
std::optional<decide::Scheme> CarryOver(const VineModel& truth, const CutPlan& truth_plan,
                                        const VineModel& model,
                                        const std::vector<decide::Candidate>& candidates);

}  // namespace vb::cutloss
