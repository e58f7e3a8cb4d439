// SPDX-License-Identifier: Apache-2.0
// Connecting reconstructed canes into one tree rooted at the trunk (issue 3 step 6; Botterill
// et al. 2017 sec. 3.2.4 joins canes to their parents where they nearly meet in 3D).
//
// Greedy growth from the root: the trunk and head are connected; repeatedly the unconnected cane
// with an end nearest to anything connected (head surface, trunk, a connected cane) is attached
// there, oriented so that end is its base, and given a first point on its parent. Canes that
// never come within `max_attach_m` of the tree (a neighbour's canes, ghosts) are left out: the
// arm must avoid them, but they are not this vine's and are not pruned. Thread-safe (pure).
#pragma once

#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "core/vine_model.h"

namespace vb::reconstruct {

struct ConnectOptions {
  double max_attach_m = 0.04;        // an end this near the tree may attach to it
  double head_margin_m = 0.02;       // canes within this of the head surface attach to the head
  double inside_fraction = 0.7;      // canes with this much of their length inside the trunk or
                                     // head are duplicates of them and dropped
  double spur_length_m = 0.08;       // canes on the head or trunk shorter than this are spurs
  double trunk_axis_min_fraction = 0.3;  // a stereo cane inside the silhouette trunk at least
                                         // this fraction of its length replaces its axis
  double sample_step_m = 0.01;       // spacing of samples along canes for distances

  absl::Status Validate() const;
};

struct ConnectSummary {
  int attached = 0;       // canes in the tree (trunk excluded)
  int unattached = 0;     // canes left out: never near the tree
  int inside_trunk_or_head = 0;  // canes dropped as duplicates of the trunk or head
};

// Builds the model's canes: id 1 the trunk (from `trunk`, or if absent the thickest cane reaching
// lowest), then attached canes with ids 2, 3, ... in attachment order (parents first). `head`
// is copied into the model. An empty input gives a model without canes. INVALID_ARGUMENT for
// invalid options or a cane failing Polyline3::Validate (naming its index).
absl::StatusOr<VineModel> ConnectCanes(const std::vector<Polyline3>& canes,
                                       const std::optional<Polyline3>& trunk,
                                       const HeadModel& head, const ConnectOptions& options,
                                       ConnectSummary* summary = nullptr);

}  // namespace vb::reconstruct
