// SPDX-License-Identifier: Apache-2.0
// Flags shared by `vinebot reconstruct` and `vinebot bench reconstruct` that set the match
// selection of correspondence (step 3; workers/reconstruct/correspondence.h), the depth sweep
// (step 4e; workers/reconstruct/depth_sweep.h), the head's options (step 5;
// workers/reconstruct/head.h), the cane bases at the head (workers/reconstruct/head_bases.h), the
// single-view extension's which-tips rules (step 4c; workers/reconstruct/extend.h), the
// connect stage's keep rules (step 6) and its head exits (step 6c; workers/reconstruct/connect.h).
#pragma once

#include "absl/status/status.h"
#include "app/flags.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/depth_sweep.h"
#include "workers/reconstruct/extend.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/head_bases.h"
#include "workers/reconstruct/strand_halves.h"

namespace vb::app {

// Reads into *options (defaults: its values as given):
//   --alpha A: the minimum expected loss selection's alpha (keep marginal P > 1 / (1 + A)), of
//     both passes (the first pass's matters only where the rig refinement is not applied: the
//     refinement takes pieces with P >= 0.8 whatever alpha);
//   --select-context true|false: the context-aware selection (context_selection.h);
//   --context-alpha A: its lower threshold 1 / (1 + A), at least --alpha;
//   --match-model quadratic|linear: the second pass's multi-view candidates scored by the
//     committed quadratic model or by the linear weights (match_classifier.h).
// INVALID_ARGUMENT naming the flag: a value that does not parse, --alpha or --context-alpha not
// finite or <= 0, --context-alpha below --alpha with --select-context on, --match-model neither.
absl::Status ReadSelectionFlags(Flags& flags, reconstruct::CorrespondenceOptions* options);

// Reads into *options (defaults: its values as given) the depth sweep of step 4e
// (workers/reconstruct/depth_sweep.h):
//   --sweep true|false: run it (on by default);
//   --sweep-min-views N, --sweep-max-step N, --sweep-accept-px X, --sweep-unique-steps N,
//   --sweep-max-ambiguous X, --sweep-min-stretch-share X: its fields min_views, max_step,
//     accept_px, unique_exclusion_steps, max_ambiguous_share and min_stretch_accepted_share.
//   --sweep-check true|false (on by default), --sweep-check-spread X, --sweep-check-excess X,
//   --sweep-check-foreground X: the check on each added run (check, check_max_width_log_spread,
//     check_max_width_log_excess, check_min_foreground).
// INVALID_ARGUMENT naming the flag: a value that does not parse or is out of the field's range
// (DepthSweepOptions::Validate).
absl::Status ReadSweepFlags(Flags& flags, reconstruct::DepthSweepOptions* options);

// Reads into *options (defaults: its values as given) the HeadOptions of those names:
//   --head-peel true|false (peel_canes), --head-min-cell M (min_cell_m),
//   --head-depth-factor F (head_depth_factor), --head-leaf-fraction F (leaf_radius_fraction),
//   --head-centre-on-trunk true|false (head_centre_on_trunk),
//   --head-leaf-wood-px X (leaf_wood_radius_px), --head-fg-reach-px N (foreground_reach_px),
//   --head-fg-reach-views K (foreground_reach_max_views).
// INVALID_ARGUMENT naming the flag: a value that does not parse, --head-min-cell not in
// (0, coarse_cell_m], --head-depth-factor not finite or <= 0, --head-leaf-fraction not in [0, 1],
// --head-leaf-wood-px not finite or < 0, --head-fg-reach-px not in [0, 100],
// --head-fg-reach-views not in [1, 100].
absl::Status ReadHeadFlags(Flags& flags, reconstruct::HeadOptions* options);

// Reads into *options (defaults: its values as given):
//   --head-bases true|false: extend the cane ends pointing at the head to it (enabled);
//   --head-bases-reach M: ends this near the head's spheres are looked at (reach_m);
//   --head-bases-thick-views N: the head is reached where N views show thick wood
//     (min_thick_views; 0: never);
//   --head-bases-inside M: ... or M inside the head's spheres (max_inside_m);
//   --head-bases-curve G: the course's curvature as a fraction G of the end's (curve_gain);
//   --head-bases-skeleton PX: drop extensions lying on average farther than PX from the views'
//     skeletons (max_skeleton_px; 0: never).
// INVALID_ARGUMENT naming the flag: a value that does not parse, --head-bases-reach not finite
// or <= 0, --head-bases-thick-views < 0, --head-bases-inside not finite or < 0,
// --head-bases-curve outside [0, 2], --head-bases-skeleton not finite or < 0.
absl::Status ReadHeadBasesFlags(Flags& flags, reconstruct::HeadBasesOptions* options);

// Reads into *options (defaults: its values as given) the head exits of connection (step 6c,
// connect.h): a cane hung on another cane whose inner end lies within reach of the head's
// surface and points at it hangs on the head instead:
//   --head-exit-reach M: head_exit_reach_m (0.3 by default since s22; 0 turns step 6c off);
//   --head-exit-cos C: head_exit_min_cos, the least cosine between the inner end's outward
//     tangent and the direction to the head;
//   --head-exit-min-radius M: head_exit_min_radius_m, the least mean radius over 3 cm at the
//     inner end (0.003 by default since s22; 0: no test);
//   --head-exit-left-out true|false: head_exit_left_out, left-out canes too.
// INVALID_ARGUMENT naming the flag: a value that does not parse, --head-exit-reach or
// --head-exit-min-radius not finite or < 0, --head-exit-cos not in [-1, 1].
absl::Status ReadHeadExitFlags(Flags& flags, reconstruct::ConnectOptions* options);

// Reads into *options (defaults: its values as given) the single-view extension's rules of step
// 4c (the stage itself is --extend, read by the commands):
//   --extend-row M (max_tip_row_distance_m), --extend-across X (max_tip_out_of_plane),
//   --extend-support PX (max_support_px): the which-tips rules, each off at 0;
//   --extend-depth-sd M (max_depth_sd_m): the depth's predicted sd that stops an extension.
// INVALID_ARGUMENT naming the flag: a value that does not parse, --extend-row, --extend-across or
// --extend-support not finite or < 0, --extend-depth-sd not finite or <= 0.
absl::Status ReadExtendFlags(Flags& flags, reconstruct::ExtendOptions* options);

// Reads into *options (defaults: its values as given) the strand halves of step 2b
// (strand_halves.h): --strand-halves BOOL (enabled), --strand-halves-dip G (min_seam_dip, grey
// levels). INVALID_ARGUMENT naming the flag: a value that does not parse, --strand-halves-dip not
// finite or < 0.
absl::Status ReadStrandHalfFlags(Flags& flags, reconstruct::StrandHalfOptions* options);

// Reads into *options (defaults: its values as given) the connect stage's rules of step 6 that
// decide which canes enter the tree:
//   --min-join-probability P (min_join_probability, "none"'s probability),
//   --rescue-min-probability P (rescue_min_probability; 0: off),
//   --rescue-min-taper R (rescue_min_taper; 0: no test),
//   --keep-within M (keep_within_m; 0: off), --keep-min-length M (keep_min_length_m),
//   --keep-taper R (keep_taper_ratio; 0: off), --drop-thickening R (drop_thickening_ratio; 0: off),
//   --join-model quadratic|linear: the joins scored by the committed quadratic models
//     (DefaultQuadraticJoinModels) or by the linear weights alone (join_classifier.h).
// INVALID_ARGUMENT naming the flag: a value that does not parse, --join-model neither,
// --min-join-probability not in
// (0, 1), --rescue-min-probability neither 0 nor in [--min-join-probability, 1),
// --rescue-min-taper, --keep-within or --keep-min-length not finite or < 0, --keep-taper or
// --drop-thickening neither 0 nor finite and > 1.
absl::Status ReadConnectFlags(Flags& flags, reconstruct::ConnectOptions* options);

}  // namespace vb::app
