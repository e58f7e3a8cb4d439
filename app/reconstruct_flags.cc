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

absl::Status ReadSweepFlags(Flags& flags, reconstruct::DepthSweepOptions* options) {
  VB_ASSIGN_OR_RETURN(const bool enabled, flags.Bool("sweep", options->enabled));
  VB_ASSIGN_OR_RETURN(const int64_t min_views, flags.Int("sweep-min-views", options->min_views));
  if (min_views < 2 || min_views > 64) {
    return absl::InvalidArgumentError(
        absl::StrCat("--sweep-min-views must be in [2, 64], got ", min_views));
  }
  options->enabled = enabled;
  options->min_views = static_cast<int>(min_views);
  return absl::OkStatus();
}

}  // namespace vb::app
