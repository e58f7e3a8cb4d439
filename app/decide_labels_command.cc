// SPDX-License-Identifier: Apache-2.0
// vinebot sim decide-labels: labelled pruning decisions from simulated vines, for
// `vinebot train decide` (workers/decide/labelled_examples.h). Each vine's ground-truth model is
// pruned by the simulated expert (sim/expert_pruner.h); its decision is written as a cut plan
// whose cuts are placed by decide's cut-point rules (workers/decide/cut_points.h), as an approved
// plan from the tablet would carry them. Learning reads only the policy, keep and spurs.
//   --vines N          vines, seeds [S, S + N) (vine index seed % 7, as the other sim tools)
//   --seed-base S      (default 1100; seeds >= 9000 are refused: reserved for the benchmark)
//   --out DIR          the label directory (NAME = sim-SEED-VINE)
//   --policy FILE      the pruning policy (default: PruningPolicy defaults)
#include <cstdint>
#include <iostream>
#include <string>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "core/status_macros.h"
#include "sim/expert_pruner.h"
#include "sim/vine_generator.h"
#include "workers/decide/cut_points.h"
#include "workers/decide/decide.h"
#include "workers/decide/labelled_examples.h"
#include "workers/decide/scheme.h"

namespace vb::app {
namespace {

// Seeds from here on are reserved for the reported benchmark (docs/benchmarks.md).
constexpr int64_t kReservedSeedBegin = 9000;

}  // namespace

absl::Status RunSimDecideLabels(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const int64_t vines, flags.Int("vines", 0));
  VB_ASSIGN_OR_RETURN(const int64_t seed_base, flags.Int("seed-base", 1100));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  VB_ASSIGN_OR_RETURN(const std::string policy_path, flags.String("policy", ""));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (vines < 1 || vines > 100000) {
    return absl::InvalidArgumentError(absl::StrCat("--vines: must be in [1, 100000], is ", vines));
  }
  if (seed_base < 0 || seed_base + vines > kReservedSeedBegin) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--seed-base: the vines use seeds [", seed_base, ", ", seed_base + vines, "); seeds >= ",
        kReservedSeedBegin, " are reserved for the benchmark"));
  }
  PruningPolicy policy;
  if (!policy_path.empty()) {
    VB_ASSIGN_OR_RETURN(policy, ReadPruningPolicy(policy_path));
  }
  VB_RETURN_IF_ERROR(policy.Validate());

  const double max_head_slide_m = decide::DecideOptions{}.max_head_slide_m;
  int64_t kept = 0, spurs = 0, notes = 0, cuts = 0;
  for (int64_t i = 0; i < vines; ++i) {
    const auto seed = static_cast<uint64_t>(seed_base + i);
    const int vine = static_cast<int>(seed % 7);
    VB_ASSIGN_OR_RETURN(sim::Scene scene, sim::GenerateScene(seed, vine));
    VB_ASSIGN_OR_RETURN(const sim::ExpertDecision decision, sim::ExpertPrune(scene.vine, policy));
    decide::LabelledExample example;
    example.name = absl::StrCat("sim-", seed, "-", vine);
    example.model = std::move(scene.vine);
    example.plan.policy = policy;
    example.plan.keep = decision.keep;
    example.plan.spurs = decision.spurs;
    VB_ASSIGN_OR_RETURN(const std::vector<decide::Candidate> candidates,
                        decide::FindCandidates(example.model, policy));
    VB_ASSIGN_OR_RETURN(const decide::CutPlacement placement,
                        decide::PlaceCuts(example.model, candidates, policy,
                                          {decision.keep, decision.spurs}, max_head_slide_m));
    example.plan.cuts = placement.cuts;
    VB_RETURN_IF_ERROR(decide::WriteLabelledExample(out, example));
    cuts += static_cast<int64_t>(placement.cuts.size());
    kept += static_cast<int64_t>(decision.keep.size());
    spurs += static_cast<int64_t>(decision.spurs.size());
    notes += static_cast<int64_t>(decision.notes.size());
    for (const std::string& note : decision.notes) std::cerr << example.name << ": " << note << "\n";
  }
  const nlohmann::json summary = {{"out", out},
                                  {"examples", vines},
                                  {"seeds", {seed_base, seed_base + vines - 1}},
                                  {"kept_canes", kept},
                                  {"spurs", spurs},
                                  {"notes", notes},
                                  {"cuts", cuts}};
  std::cout << summary.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
