// SPDX-License-Identifier: Apache-2.0
#include "app/reconstruct_flags.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::app {

absl::Status ReadSelectionFlags(Flags& flags, reconstruct::CorrespondenceOptions* options) {
  VB_ASSIGN_OR_RETURN(const double alpha, flags.Double("alpha", options->alpha));
  VB_ASSIGN_OR_RETURN(const bool context,
                      flags.Bool("select-context", options->context.enabled));
  VB_ASSIGN_OR_RETURN(const double context_alpha,
                      flags.Double("context-alpha", options->context.alpha));
  if (!(alpha > 0.0) || !std::isfinite(alpha)) {
    return absl::InvalidArgumentError(absl::StrCat("--alpha must be finite and > 0, got ", alpha));
  }
  if (!(context_alpha > 0.0) || !std::isfinite(context_alpha)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--context-alpha must be finite and > 0, got ", context_alpha));
  }
  if (context && context_alpha < alpha) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--context-alpha (", context_alpha, ") must be >= --alpha (", alpha, ")"));
  }
  options->alpha = alpha;
  options->context.enabled = context;
  options->context.alpha = context_alpha;
  return absl::OkStatus();
}

absl::Status ReadHeadBasesFlags(Flags& flags, reconstruct::HeadBasesOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool enabled, flags.Bool("head-bases", options->enabled));
  VB_ASSIGN_OR_RETURN(const double reach, flags.Double("head-bases-reach", options->reach_m));
  VB_ASSIGN_OR_RETURN(const int64_t thick_views,
                      flags.Int("head-bases-thick-views", options->min_thick_views));
  VB_ASSIGN_OR_RETURN(const double inside,
                      flags.Double("head-bases-inside", options->max_inside_m));
  if (!(reach > 0.0) || !std::isfinite(reach)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-bases-reach must be finite and > 0, got ", reach));
  }
  if (thick_views < 1 || thick_views > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-bases-thick-views must be in [1, 1000], got ", thick_views));
  }
  if (!(inside >= 0.0) || !std::isfinite(inside)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--head-bases-inside must be finite and >= 0, got ", inside));
  }
  options->enabled = enabled;
  options->reach_m = reach;
  options->min_thick_views = static_cast<int>(thick_views);
  options->max_inside_m = inside;
  return absl::OkStatus();
}

}  // namespace vb::app
