// SPDX-License-Identifier: Apache-2.0
#include "app/reconstruct_flags.h"

#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "core/status_macros.h"

namespace vb::app {

namespace {

// OK when `value` is finite and > 0 (>= 0 when zero_ok); otherwise INVALID_ARGUMENT naming the
// flag: "<flag> must be finite and > 0<note>, got <value>".
absl::Status CheckFinite(double value, absl::string_view flag, bool zero_ok,
                         absl::string_view note = "") {
  if (std::isfinite(value) && (zero_ok ? value >= 0.0 : value > 0.0)) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(flag, " must be finite and ",
                                                 zero_ok ? ">= 0" : "> 0", note, ", got ", value));
}

// --NAME quadratic|linear: whether a classifier scores with its committed quadratic model(s)
// (true) or its linear weights; `quadratic` is the default.
absl::StatusOr<bool> ReadModelKind(Flags& flags, const std::string& name, bool quadratic) {
  VB_ASSIGN_OR_RETURN(const std::string kind,
                      flags.String(name, quadratic ? "quadratic" : "linear"));
  if (kind != "quadratic" && kind != "linear") {
    return absl::InvalidArgumentError(
        absl::StrCat("--", name, " must be quadratic or linear, is '", kind, "'"));
  }
  return kind == "quadratic";
}

}  // namespace

absl::Status ReadSelectionFlags(Flags& flags, reconstruct::CorrespondenceOptions* options) {
  VB_ASSIGN_OR_RETURN(const double alpha, flags.Double("alpha", options->alpha));
  VB_ASSIGN_OR_RETURN(const bool context,
                      flags.Bool("select-context", options->context.enabled));
  VB_ASSIGN_OR_RETURN(const double context_alpha,
                      flags.Double("context-alpha", options->context.alpha));
  VB_RETURN_IF_ERROR(CheckFinite(alpha, "--alpha", /*zero_ok=*/false));
  VB_RETURN_IF_ERROR(CheckFinite(context_alpha, "--context-alpha", /*zero_ok=*/false));
  if (context && context_alpha < alpha) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--context-alpha (", context_alpha, ") must be >= --alpha (", alpha, ")"));
  }
  VB_ASSIGN_OR_RETURN(
      const bool quadratic,
      ReadModelKind(flags, "match-model", !options->classifier.multi_view_quadratic.empty()));
  options->alpha = alpha;
  options->context.enabled = context;
  options->context.alpha = context_alpha;
  options->classifier.multi_view_quadratic =
      quadratic ? reconstruct::DefaultQuadraticMatchModel() : reconstruct::QuadraticLogistic{};
  return absl::OkStatus();
}

absl::Status ReadSweepFlags(Flags& flags, reconstruct::DepthSweepOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool enabled, flags.Bool("sweep", options->enabled));
  VB_ASSIGN_OR_RETURN(const int64_t min_views, flags.Int("sweep-min-views", options->min_views));
  VB_ASSIGN_OR_RETURN(const int64_t max_step, flags.Int("sweep-max-step", options->max_step));
  VB_ASSIGN_OR_RETURN(const double accept_px, flags.Double("sweep-accept-px", options->accept_px));
  VB_ASSIGN_OR_RETURN(const int64_t unique_steps,
                      flags.Int("sweep-unique-steps", options->unique_exclusion_steps));
  VB_ASSIGN_OR_RETURN(const double max_ambiguous,
                      flags.Double("sweep-max-ambiguous", options->max_ambiguous_share));
  VB_ASSIGN_OR_RETURN(const double min_stretch_share,
                      flags.Double("sweep-min-stretch-share",
                                   options->min_stretch_accepted_share));
  VB_ASSIGN_OR_RETURN(const bool check, flags.Bool("sweep-check", options->check));
  VB_ASSIGN_OR_RETURN(const double check_spread, flags.Double("sweep-check-spread",
                                                              options->check_max_width_log_spread));
  VB_ASSIGN_OR_RETURN(const double check_excess, flags.Double("sweep-check-excess",
                                                              options->check_max_width_log_excess));
  VB_ASSIGN_OR_RETURN(const double check_foreground,
                      flags.Double("sweep-check-foreground", options->check_min_foreground));
  VB_RETURN_IF_ERROR(CheckFinite(check_spread, "--sweep-check-spread", /*zero_ok=*/true));
  VB_RETURN_IF_ERROR(CheckFinite(check_excess, "--sweep-check-excess", /*zero_ok=*/true));
  if (!(check_foreground >= 0.0 && check_foreground <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-check-foreground must be in [0, 1], got ", check_foreground));
  }
  if (min_views < 2 || min_views > 64) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-min-views must be in [2, 64], got ", min_views));
  }
  if (max_step < 1 || max_step > 20) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-max-step must be in [1, 20], got ", max_step));
  }
  if (unique_steps < 0 || unique_steps > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-unique-steps must be in [0, 1000], got ", unique_steps));
  }
  VB_RETURN_IF_ERROR(CheckFinite(accept_px, "--sweep-accept-px", /*zero_ok=*/false));
  if (!(max_ambiguous >= 0.0 && max_ambiguous <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-max-ambiguous must be in [0, 1], got ", max_ambiguous));
  }
  if (!(min_stretch_share >= 0.0 && min_stretch_share <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-min-stretch-share must be in [0, 1], got ", min_stretch_share));
  }
  options->enabled = enabled;
  options->min_views = static_cast<int>(min_views);
  options->max_step = static_cast<int>(max_step);
  options->accept_px = accept_px;
  options->unique_exclusion_steps = static_cast<int>(unique_steps);
  options->max_ambiguous_share = max_ambiguous;
  options->min_stretch_accepted_share = min_stretch_share;
  options->check = check;
  options->check_max_width_log_spread = check_spread;
  options->check_max_width_log_excess = check_excess;
  options->check_min_foreground = check_foreground;
  return absl::OkStatus();
}

absl::Status ReadHeadFlags(Flags& flags, reconstruct::HeadOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool peel, flags.Bool("head-peel", options->peel_canes));
  VB_ASSIGN_OR_RETURN(const double min_cell, flags.Double("head-min-cell", options->min_cell_m));
  VB_ASSIGN_OR_RETURN(const double depth_factor,
                      flags.Double("head-depth-factor", options->head_depth_factor));
  VB_ASSIGN_OR_RETURN(const double leaf_fraction,
                      flags.Double("head-leaf-fraction", options->leaf_radius_fraction));
  VB_ASSIGN_OR_RETURN(const bool centre_on_trunk,
                      flags.Bool("head-centre-on-trunk", options->head_centre_on_trunk));
  VB_ASSIGN_OR_RETURN(const double wood_px,
                      flags.Double("head-leaf-wood-px", options->leaf_wood_radius_px));
  VB_ASSIGN_OR_RETURN(const int64_t reach_px,
                      flags.Int("head-fg-reach-px", options->foreground_reach_px));
  VB_ASSIGN_OR_RETURN(const int64_t reach_views,
                      flags.Int("head-fg-reach-views", options->foreground_reach_max_views));
  if (!(min_cell > 0.0) || !(min_cell <= options->coarse_cell_m)) {
    return absl::InvalidArgumentError(absl::StrCat("--head-min-cell must be in (0, ",
                                                   options->coarse_cell_m, "], got ", min_cell));
  }
  VB_RETURN_IF_ERROR(CheckFinite(depth_factor, "--head-depth-factor", /*zero_ok=*/false));
  if (!(leaf_fraction >= 0.0 && leaf_fraction <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-leaf-fraction must be in [0, 1], got ", leaf_fraction));
  }
  VB_RETURN_IF_ERROR(CheckFinite(wood_px, "--head-leaf-wood-px", /*zero_ok=*/true));
  if (reach_px < 0 || reach_px > 100) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-fg-reach-px must be in [0, 100], got ", reach_px));
  }
  if (reach_views < 1 || reach_views > 100) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-fg-reach-views must be in [1, 100], got ", reach_views));
  }
  options->peel_canes = peel;
  options->min_cell_m = min_cell;
  options->head_depth_factor = depth_factor;
  options->leaf_radius_fraction = leaf_fraction;
  options->head_centre_on_trunk = centre_on_trunk;
  options->leaf_wood_radius_px = wood_px;
  options->foreground_reach_px = static_cast<int>(reach_px);
  options->foreground_reach_max_views = static_cast<int>(reach_views);
  return absl::OkStatus();
}

absl::Status ReadHeadBasesFlags(Flags& flags, reconstruct::HeadBasesOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool enabled, flags.Bool("head-bases", options->enabled));
  VB_ASSIGN_OR_RETURN(const double reach, flags.Double("head-bases-reach", options->reach_m));
  VB_ASSIGN_OR_RETURN(const int64_t thick_views,
                      flags.Int("head-bases-thick-views", options->min_thick_views));
  VB_ASSIGN_OR_RETURN(const double inside,
                      flags.Double("head-bases-inside", options->max_inside_m));
  VB_ASSIGN_OR_RETURN(const double curve, flags.Double("head-bases-curve", options->curve_gain));
  VB_ASSIGN_OR_RETURN(const double skeleton,
                      flags.Double("head-bases-skeleton", options->max_skeleton_px));
  VB_RETURN_IF_ERROR(CheckFinite(skeleton, "--head-bases-skeleton", /*zero_ok=*/true));
  if (!(curve >= 0.0 && curve <= 2.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-bases-curve must be in [0, 2], got ", curve));
  }
  VB_RETURN_IF_ERROR(CheckFinite(reach, "--head-bases-reach", /*zero_ok=*/false));
  if (thick_views < 0 || thick_views > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-bases-thick-views must be in [0, 1000], got ", thick_views));
  }
  VB_RETURN_IF_ERROR(CheckFinite(inside, "--head-bases-inside", /*zero_ok=*/true));
  options->enabled = enabled;
  options->reach_m = reach;
  options->min_thick_views = static_cast<int>(thick_views);
  options->max_inside_m = inside;
  options->curve_gain = curve;
  options->max_skeleton_px = skeleton;
  return absl::OkStatus();
}

absl::Status ReadExtendFlags(Flags& flags, reconstruct::ExtendOptions* options) {
  VB_ASSIGN_OR_RETURN(const double row,
                      flags.Double("extend-row", options->max_tip_row_distance_m));
  VB_ASSIGN_OR_RETURN(const double across,
                      flags.Double("extend-across", options->max_tip_out_of_plane));
  VB_ASSIGN_OR_RETURN(const double support,
                      flags.Double("extend-support", options->max_support_px));
  VB_ASSIGN_OR_RETURN(const double depth_sd,
                      flags.Double("extend-depth-sd", options->max_depth_sd_m));
  for (const auto& [value, name] : {std::pair{row, "--extend-row"},
                                    {across, "--extend-across"},
                                    {support, "--extend-support"}}) {
    VB_RETURN_IF_ERROR(CheckFinite(value, name, /*zero_ok=*/true, " (0: off)"));
  }
  VB_RETURN_IF_ERROR(CheckFinite(depth_sd, "--extend-depth-sd", /*zero_ok=*/false));
  options->max_tip_row_distance_m = row;
  options->max_tip_out_of_plane = across;
  options->max_support_px = support;
  options->max_depth_sd_m = depth_sd;
  return absl::OkStatus();
}

absl::Status ReadStrandHalfFlags(Flags& flags, reconstruct::StrandHalfOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool enabled, flags.Bool("strand-halves", options->enabled));
  VB_ASSIGN_OR_RETURN(const double dip, flags.Double("strand-halves-dip", options->min_seam_dip));
  VB_RETURN_IF_ERROR(CheckFinite(dip, "--strand-halves-dip", /*zero_ok=*/true));
  options->enabled = enabled;
  options->min_seam_dip = dip;
  return absl::OkStatus();
}

absl::Status ReadConnectFlags(Flags& flags, reconstruct::ConnectOptions* options) {
  VB_ASSIGN_OR_RETURN(const double min_join,
                      flags.Double("min-join-probability", options->min_join_probability));
  VB_ASSIGN_OR_RETURN(const double rescue,
                      flags.Double("rescue-min-probability", options->rescue_min_probability));
  VB_ASSIGN_OR_RETURN(const double rescue_taper,
                      flags.Double("rescue-min-taper", options->rescue_min_taper));
  VB_ASSIGN_OR_RETURN(const double keep_within,
                      flags.Double("keep-within", options->keep_within_m));
  VB_ASSIGN_OR_RETURN(const double keep_length,
                      flags.Double("keep-min-length", options->keep_min_length_m));
  VB_ASSIGN_OR_RETURN(const double keep_taper,
                      flags.Double("keep-taper", options->keep_taper_ratio));
  VB_ASSIGN_OR_RETURN(const double drop,
                      flags.Double("drop-thickening", options->drop_thickening_ratio));
  VB_ASSIGN_OR_RETURN(
      const bool quadratic,
      ReadModelKind(flags, "join-model", !options->join_weights.cane_quadratic.empty()));
  if (!(min_join > 0.0 && min_join < 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--min-join-probability must be in (0, 1), got ", min_join));
  }
  if (!(rescue == 0.0 || (rescue >= min_join && rescue < 1.0))) {
    return absl::InvalidArgumentError(
        absl::StrCat("--rescue-min-probability must be 0 (off) or in [--min-join-probability (",
                     min_join, "), 1), got ", rescue));
  }
  for (const auto& [value, name] : {std::pair{rescue_taper, "--rescue-min-taper"},
                                    {keep_within, "--keep-within"},
                                    {keep_length, "--keep-min-length"}}) {
    VB_RETURN_IF_ERROR(CheckFinite(value, name, /*zero_ok=*/true));
  }
  for (const auto& [value, name] : {std::pair{keep_taper, "--keep-taper"},
                                    {drop, "--drop-thickening"}}) {
    if (!(value == 0.0 || (value > 1.0 && std::isfinite(value)))) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, " must be 0 (off) or finite and > 1, got ", value));
    }
  }
  options->min_join_probability = min_join;
  options->rescue_min_probability = rescue;
  options->rescue_min_taper = rescue_taper;
  options->keep_within_m = keep_within;
  options->keep_min_length_m = keep_length;
  options->keep_taper_ratio = keep_taper;
  options->drop_thickening_ratio = drop;
  const reconstruct::JoinWeights models =
      quadratic ? reconstruct::DefaultQuadraticJoinModels() : reconstruct::JoinWeights{};
  options->join_weights.cane_quadratic = models.cane_quadratic;
  options->join_weights.root_quadratic = models.root_quadratic;
  return absl::OkStatus();
}

absl::Status ReadHeadExitFlags(Flags& flags, reconstruct::ConnectOptions* options) {
  VB_ASSIGN_OR_RETURN(const double reach,
                      flags.Double("head-exit-reach", options->head_exit_reach_m));
  VB_ASSIGN_OR_RETURN(const double min_cos,
                      flags.Double("head-exit-cos", options->head_exit_min_cos));
  VB_ASSIGN_OR_RETURN(const double min_radius,
                      flags.Double("head-exit-min-radius", options->head_exit_min_radius_m));
  VB_ASSIGN_OR_RETURN(const bool left_out,
                      flags.Bool("head-exit-left-out", options->head_exit_left_out));
  VB_RETURN_IF_ERROR(CheckFinite(reach, "--head-exit-reach", /*zero_ok=*/true));
  if (!(min_cos >= -1.0 && min_cos <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-exit-cos must be in [-1, 1], got ", min_cos));
  }
  VB_RETURN_IF_ERROR(CheckFinite(min_radius, "--head-exit-min-radius", /*zero_ok=*/true));
  options->head_exit_reach_m = reach;
  options->head_exit_min_radius_m = min_radius;
  options->head_exit_min_cos = min_cos;
  options->head_exit_left_out = left_out;
  return absl::OkStatus();
}

}  // namespace vb::app
