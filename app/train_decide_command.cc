// SPDX-License-Identifier: Apache-2.0
// vinebot train decide: learns the scheme cost's weights from labelled decisions
// (workers/decide/scheme_learning.h) and reports how often they reproduce the labels.
//   --labels DIR             labelled examples (NAME.model.json + NAME.plan.json)
//   --holdout DIR            held-out examples from elsewhere (then all of --labels trains)
//   --holdout-fraction F     else: this fraction of --labels is held out (default 0.3; fixed split)
//   --epochs N               constraint-generation rounds at most (default 30)
//   --regularization L       L2 weight on the scaled weights (default 1e-12)
//   --keep-loss K            margin of a wrong kept cane, in wrong spurs (default 4)
//   --out FILE               write the learned weights (SchemeWeightsToJson)
// Prints one JSON object: counts, skipped examples, agreement (train, held-out, and held-out with
// the default weights for comparison), the learned weights and the feature scales.
#include <iostream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "core/json_io.h"
#include "core/status_macros.h"
#include "workers/decide/labelled_examples.h"
#include "workers/decide/scheme_learning.h"

namespace vb::app {
namespace {

struct Loaded {
  std::vector<decide::RankingExample> examples;
  nlohmann::json skipped = nlohmann::json::array();
};

// Reads every example of `dir`; examples whose expert scheme the search cannot represent
// (MakeRankingExample's FAILED_PRECONDITION) are reported and skipped, other errors returned.
absl::StatusOr<Loaded> Load(const std::string& dir) {
  VB_ASSIGN_OR_RETURN(const std::vector<std::string> names, decide::ListLabelledExamples(dir));
  if (names.empty()) return absl::InvalidArgumentError(absl::StrCat(dir, ": no labelled examples"));
  Loaded loaded;
  for (const std::string& name : names) {
    VB_ASSIGN_OR_RETURN(const decide::LabelledExample example, decide::ReadLabelledExample(dir, name));
    absl::StatusOr<decide::RankingExample> r = decide::MakeRankingExample(example);
    if (r.ok()) {
      loaded.examples.push_back(*std::move(r));
    } else if (r.status().code() == absl::StatusCode::kFailedPrecondition) {
      std::cerr << "skipped: " << r.status().message() << "\n";
      loaded.skipped.push_back({{"name", name}, {"reason", std::string(r.status().message())}});
    } else {
      return r.status();
    }
  }
  return loaded;
}

nlohmann::json AgreementJson(const decide::AgreementReport& r) {
  return {{"examples", r.examples},
          {"agreement", r.agreement},
          {"keep_agreement", r.examples > 0 ? static_cast<double>(r.keep_agreements) / r.examples : 0.0},
          {"disagreements", r.disagreements}};
}

}  // namespace

absl::Status RunTrainDecide(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string labels, flags.RequiredString("labels"));
  VB_ASSIGN_OR_RETURN(const std::string holdout_dir, flags.String("holdout", ""));
  VB_ASSIGN_OR_RETURN(const double fraction, flags.Double("holdout-fraction", 0.3));
  decide::SchemeLearningOptions options;
  VB_ASSIGN_OR_RETURN(const int64_t epochs, flags.Int("epochs", options.max_rounds));
  VB_ASSIGN_OR_RETURN(options.regularization,
                      flags.Double("regularization", options.regularization));
  VB_ASSIGN_OR_RETURN(options.keep_loss, flags.Double("keep-loss", options.keep_loss));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.String("out", ""));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!(fraction >= 0.0 && fraction < 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--holdout-fraction: must be in [0, 1), is ", fraction));
  }
  if (epochs < 1 || epochs > 10000) {
    return absl::InvalidArgumentError(absl::StrCat("--epochs: must be in [1, 10000], is ", epochs));
  }
  options.max_rounds = static_cast<int>(epochs);
  VB_RETURN_IF_ERROR(options.Validate());

  VB_ASSIGN_OR_RETURN(Loaded loaded, Load(labels));
  std::vector<decide::RankingExample> train, held_out;
  nlohmann::json skipped = loaded.skipped;
  if (!holdout_dir.empty()) {
    train = std::move(loaded.examples);
    VB_ASSIGN_OR_RETURN(Loaded other, Load(holdout_dir));
    held_out = std::move(other.examples);
    for (const nlohmann::json& s : other.skipped) skipped.push_back(s);
  } else {
    const std::vector<size_t> held = decide::HoldOutIndices(loaded.examples.size(), fraction);
    size_t next = 0;
    for (size_t i = 0; i < loaded.examples.size(); ++i) {
      const bool is_held = next < held.size() && held[next] == i;
      next += is_held;
      (is_held ? held_out : train).push_back(std::move(loaded.examples[i]));
    }
  }
  if (train.empty()) return absl::InvalidArgumentError("no usable training examples");

  VB_ASSIGN_OR_RETURN(const decide::SchemeLearningResult result,
                      decide::LearnSchemeWeights(train, options));
  VB_ASSIGN_OR_RETURN(const decide::AgreementReport held,
                      decide::MeasureAgreement(held_out, result.weights));
  VB_ASSIGN_OR_RETURN(const decide::AgreementReport held_default,
                      decide::MeasureAgreement(held_out, decide::DefaultSchemeWeights()));
  if (!out.empty()) {
    VB_RETURN_IF_ERROR(WriteJsonFile(out, decide::SchemeWeightsToJson(result.weights)));
  }
  nlohmann::json scale;
  for (int f = 0; f < decide::kSchemeFeatureCount; ++f) {
    scale[std::string(decide::SchemeFeatureName(f))] = result.feature_scale[f];
  }
  const nlohmann::json report = {
      {"labels", labels},
      {"holdout", holdout_dir.empty() ? nlohmann::json(fraction) : nlohmann::json(holdout_dir)},
      {"train_examples", train.size()},
      {"held_out_examples", held_out.size()},
      {"skipped", skipped},
      {"rounds", result.rounds},
      {"constraints", result.constraints},
      {"train_agreement", result.train_agreement},
      {"held_out_agreement", held.agreement},
      {"held_out", AgreementJson(held)},
      {"held_out_default_weights", AgreementJson(held_default)},
      {"weights", decide::SchemeWeightsToJson(result.weights)},
      {"feature_scale", scale},
      {"out", out}};
  std::cout << report.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
