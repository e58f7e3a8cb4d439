// SPDX-License-Identifier: Apache-2.0
// Where to cut, once the scheme is chosen (issue 4; Botterill et al. 2017 section 3.3: canes not
// kept are cut about 1 cm from their base, spurs are left about 10 cm long). Pure function;
// thread-safe.
//
// Rules, for every cane of kind `cane` (arc lengths s measured from the cane's base; `exit` is
// where the cane leaves its parent's wood, the first point farther from the parent's axis than
// the parent's radius, since a cane's base lies on its parent's axis):
//  - kept: no cut, unless it is longer than policy.max_kept_length_m + kMinTrimM; then a
//    `shorten` cut at s = max_kept_length_m.
//  - spur: a `spur` cut at s = exit + policy.spur_length_m, unless the cane is not longer than that
//    + kMinTrimM (then it is left as it is, with a note).
//  - neither, with a kept cane or spur growing from it (directly or through other canes): cutting
//    it at its base would drop that cane too, so instead it is shortened just beyond the base of
//    the farthest such cane: a `shorten` cut at s = attach + the child's base radius +
//    policy.cut_offset_m (attach: where the child's base projects onto this cane), with a note;
//    no cut if that is within kMinTrimM of its tip. (IsFeasible already forbids a kept cane or
//    spur growing from another kept cane or spur.)
//  - neither, otherwise: a `remove` cut at s = exit + policy.cut_offset_m (at most half the
//    cane's length).
//  - a cut point inside a head sphere slides outward (toward the tip) until it is outside, at
//    most max_head_slide_m and never past the tip; a slide, and a cut still inside the head
//    after the full slide, are noted.
//  - a cane that falls with a cut ancestor (it grows from a cane beyond that cane's cut point,
//    or from a cane that itself falls) gets no cut of its own.
//  - the trunk and old spurs (kind `spur`) are never cut: the head and last season's spurs are
//    the vine's permanent wood; a spur is renewed by pruning the cane that grows from it.
// Every cut point is on its cane's axis (Polyline3::PointAt), `direction` is the unit tangent
// there, `diameter_m` twice the radius there. A cane gets at most one cut; cut ids are 1..n in
// increasing cane id.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"
#include "workers/decide/scheme.h"

namespace vb::decide {

// A cut that would remove less than this of a cane's tip is not made.
inline constexpr double kMinTrimM = 0.01;

struct CutPlacement {
  std::vector<Cut> cuts;
  // One line per event a supervisor should see ("cane 7: cut slid 0.012 m out of the head").
  std::vector<std::string> notes;
};

// The cuts that realise `scheme` on `model`. `candidates` must be FindCandidates(model, policy).
// INVALID_ARGUMENT for an invalid policy, a negative or non-finite max_head_slide_m, candidates
// that do not match the model ("candidates[3]: ..."), or a scheme naming a non-candidate, a cane
// twice, or a kept cane or spur descending from another ("scheme.keep[1]: ...").
absl::StatusOr<CutPlacement> PlaceCuts(const VineModel& model,
                                       const std::vector<Candidate>& candidates,
                                       const PruningPolicy& policy, const Scheme& scheme,
                                       double max_head_slide_m);

}  // namespace vb::decide
