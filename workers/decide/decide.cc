// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/decide.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/decide/cut_points.h"

namespace vb::decide {

absl::Status DecideOptions::Validate() const {
  if (absl::Status s = weights.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("options.", s.message()));
  }
  if (!std::isfinite(max_head_slide_m) || max_head_slide_m < 0.0 || max_head_slide_m > 0.5) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.max_head_slide_m: ", max_head_slide_m, " is outside [0, 0.5]"));
  }
  return absl::OkStatus();
}

namespace {

// Notes for a scheme smaller than the policy asks for, so a supervisor sees why.
void NoteShortfall(const std::vector<Candidate>& candidates, const PruningPolicy& policy,
                   const SchemeSize& size, std::vector<std::string>* notes) {
  if (candidates.empty()) {
    notes->push_back("no candidate canes: nothing to keep, spur or cut");
    return;
  }
  const int keep_asked = policy.style == PruningStyle::kSpur ? 0 : policy.canes_to_keep;
  if (size.keep < keep_asked) {
    const auto long_enough = std::count_if(
        candidates.begin(), candidates.end(),
        [&policy](const Candidate& c) { return c.length_m >= policy.min_kept_length_m; });
    notes->push_back(absl::StrCat("only ", size.keep, " cane(s) can be kept (", long_enough,
                                  " of ", candidates.size(), " candidates are at least ",
                                  policy.min_kept_length_m, " m long and not growing from one "
                                  "another); policy asks for ", keep_asked));
  }
  if (size.spurs < policy.spurs) {
    notes->push_back(absl::StrCat("only ", size.spurs, " spur(s) can be left; policy asks for ",
                                  policy.spurs));
  }
}

}  // namespace

absl::StatusOr<Decision> Decide(const VineModel& model, const PruningPolicy& policy,
                                const DecideOptions& options, const Deadline& deadline) {
  VB_RETURN_IF_ERROR(deadline.Check("decide"));
  if (model.canes.empty()) {
    return absl::InvalidArgumentError("model: empty (no trunk and no canes)");
  }
  // A valid model with canes has a trunk (every chain of parents ends at the one parentless
  // cane, which must be the trunk); FindCandidates would say "model: no trunk" otherwise.
  VB_RETURN_IF_ERROR(model.Validate());
  VB_RETURN_IF_ERROR(policy.Validate());
  VB_RETURN_IF_ERROR(options.Validate());

  Decision decision;
  VB_ASSIGN_OR_RETURN(const std::vector<Candidate> candidates, FindCandidates(model, policy));
  NoteShortfall(candidates, policy, FeasibleSchemeSize(candidates, policy), &decision.notes);
  VB_ASSIGN_OR_RETURN(decision.scheme, FindBestScheme(candidates, policy, options.weights,
                                                      deadline, &decision.stats));
  VB_ASSIGN_OR_RETURN(CutPlacement placement, PlaceCuts(model, candidates, policy, decision.scheme,
                                                        options.max_head_slide_m));
  decision.plan.policy = policy;
  decision.plan.keep = decision.scheme.keep;
  decision.plan.spurs = decision.scheme.spurs;
  decision.plan.cuts = std::move(placement.cuts);
  for (std::string& note : placement.notes) decision.notes.push_back(std::move(note));
  if (absl::Status s = decision.plan.ValidateAgainst(model); !s.ok()) {
    return absl::InternalError(absl::StrCat("decide: produced an invalid plan: ", s.message()));
  }
  return decision;
}

}  // namespace vb::decide
