// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/scheme_learning.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "Eigen/Dense"

namespace vb::decide {
namespace {

// One ranking constraint: w . d >= delta, d in raw feature units.
struct Constraint {
  FeatureVector d;
  double delta = 1.0;
};

// An example's alternatives so far; `initial` holds the one-swap constraints until the feature
// scales are known.
struct WorkingSet {
  std::set<Scheme> schemes;
  std::vector<Constraint> initial;
};

Scheme Sorted(Scheme s) {
  std::sort(s.keep.begin(), s.keep.end());
  std::sort(s.spurs.begin(), s.spurs.end());
  return s;
}

std::vector<CaneId> Replaced(const std::vector<CaneId>& ids, CaneId out, CaneId in) {
  std::vector<CaneId> r;
  for (CaneId id : ids) r.push_back(id == out ? in : id);
  std::sort(r.begin(), r.end());
  return r;
}

bool Contains(const std::vector<CaneId>& ids, CaneId id) {
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

// splitmix64 (Steele et al. 2014): a portable, fixed-seed stream for the hold-out permutation.
uint64_t SplitMix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The softmax-margin objective over the working sets, in scaled feature units:
//   lambda/2 |w|^2 + 1/N sum_i log(1 + sum_{y in W_i} exp(margin Delta_y - w . psi_y)).
class SoftmaxMargin {
 public:
  using Matrix = Eigen::Matrix<double, kSchemeFeatureCount, kSchemeFeatureCount>;

  SoftmaxMargin(const SchemeLearningOptions& options, const FeatureVector& scale, size_t examples)
      : options_(options), inv_scale_(scale.cwiseInverse()), groups_(examples) {}

  void Add(size_t example, const Constraint& c) {
    groups_[example].push_back({c.d.cwiseProduct(inv_scale_), c.delta});
    ++size_;
  }
  int size() const { return size_; }

  // Objective, and if asked its gradient and Hessian, at w.
  double Evaluate(const FeatureVector& w, FeatureVector* gradient, Matrix* hessian) const {
    const double inv_n = 1.0 / static_cast<double>(groups_.size());
    double value = 0.5 * options_.regularization * w.squaredNorm();
    if (gradient != nullptr) *gradient = options_.regularization * w;
    if (hessian != nullptr) *hessian = options_.regularization * Matrix::Identity();
    std::vector<double> scores;
    for (const std::vector<Constraint>& group : groups_) {
      // Scores of the alternatives; the expert's own scheme scores 0 (psi = 0, Delta = 0).
      scores.assign(1, 0.0);
      for (const Constraint& r : group) scores.push_back(options_.margin * r.delta - w.dot(r.d));
      const double top = *std::max_element(scores.begin(), scores.end());
      double z = 0.0;
      for (double& sc : scores) z += (sc = std::exp(sc - top));
      value += inv_n * (top + std::log(z));
      if (gradient == nullptr && hessian == nullptr) continue;
      FeatureVector mean = FeatureVector::Zero();
      Matrix second = Matrix::Zero();
      for (size_t k = 0; k < group.size(); ++k) {
        const double p = scores[k + 1] / z;
        if (p < 1e-300) continue;
        mean += p * group[k].d;
        if (hessian != nullptr) second += p * group[k].d * group[k].d.transpose();
      }
      if (gradient != nullptr) *gradient -= inv_n * mean;
      if (hessian != nullptr) *hessian += inv_n * (second - mean * mean.transpose());
    }
    return value;
  }

  // Newton's method with backtracking from `w` (the objective is smooth and strictly convex).
  FeatureVector Solve(FeatureVector w) const {
    FeatureVector g;
    Matrix h;
    double value = Evaluate(w, &g, &h);
    for (int it = 0; it < options_.newton_iterations; ++it) {
      const FeatureVector step = -h.ldlt().solve(g);
      const double decrease = -g.dot(step);
      if (!step.allFinite() || decrease < 1e-12 * std::max(1.0, std::abs(value))) break;
      double t = 1.0;
      FeatureVector next = w + step;
      double next_value = Evaluate(next, nullptr, nullptr);
      while (next_value > value - 0.25 * t * decrease && t > 1e-8) {
        t *= 0.5;
        next = w + t * step;
        next_value = Evaluate(next, nullptr, nullptr);
      }
      if (next_value > value) break;
      w = next;
      value = Evaluate(w, &g, &h);
    }
    return w;
  }

 private:
  const SchemeLearningOptions& options_;
  FeatureVector inv_scale_;
  std::vector<std::vector<Constraint>> groups_;
  int size_ = 0;
};

}  // namespace

absl::Status SchemeLearningOptions::Validate() const {
  if (!(std::isfinite(regularization) && regularization > 0.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "SchemeLearningOptions.regularization: must be finite and > 0, is ", regularization));
  }
  if (max_rounds < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("SchemeLearningOptions.max_rounds: must be >= 1, is ", max_rounds));
  }
  if (newton_iterations < 1) {
    return absl::InvalidArgumentError(absl::StrCat(
        "SchemeLearningOptions.newton_iterations: must be >= 1, is ", newton_iterations));
  }
  if (!(std::isfinite(keep_loss) && keep_loss > 0.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("SchemeLearningOptions.keep_loss: must be finite and > 0, is ", keep_loss));
  }
  if (!(std::isfinite(margin) && margin > 0.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("SchemeLearningOptions.margin: must be finite and > 0, is ", margin));
  }
  return absl::OkStatus();
}

absl::StatusOr<RankingExample> MakeRankingExample(const LabelledExample& example) {
  RankingExample r;
  r.name = example.name;
  r.policy = example.plan.policy;
  VB_ASSIGN_OR_RETURN(r.candidates, FindCandidates(example.model, example.plan.policy));
  r.expert = Sorted({example.plan.keep, example.plan.spurs});
  std::set<CaneId> ids;
  for (const Candidate& c : r.candidates) ids.insert(c.id);
  for (const std::vector<CaneId>* list : {&r.expert.keep, &r.expert.spurs}) {
    for (CaneId id : *list) {
      if (!ids.contains(id)) {
        return absl::FailedPreconditionError(absl::StrCat(
            "example ", example.name, ": the expert's scheme names cane ", id.value,
            ", which is not a candidate (FindCandidates)"));
      }
    }
  }
  if (!IsFeasible(r.candidates, r.policy, r.expert)) {
    return absl::FailedPreconditionError(absl::StrCat(
        "example ", example.name, ": the expert's scheme (", r.expert.keep.size(), " kept, ",
        r.expert.spurs.size(), " spurs) is not feasible under its policy (IsFeasible)"));
  }
  return r;
}

std::vector<Scheme> OneSwapNeighbours(const RankingExample& example) {
  const Scheme& y = example.expert;
  std::set<Scheme> out;
  auto consider = [&](Scheme s) {
    if (s != y && IsFeasible(example.candidates, example.policy, s)) out.insert(std::move(s));
  };
  for (const Candidate& c : example.candidates) {
    const bool kept = Contains(y.keep, c.id), spur = Contains(y.spurs, c.id);
    for (CaneId k : y.keep) {
      if (kept) continue;
      // c takes k's place; if c was a spur, k takes c's.
      consider({Replaced(y.keep, k, c.id), spur ? Replaced(y.spurs, c.id, k) : y.spurs});
    }
    for (CaneId s : y.spurs) {
      if (kept || spur) continue;
      consider({y.keep, Replaced(y.spurs, s, c.id)});
    }
  }
  return std::vector<Scheme>(out.begin(), out.end());
}

double SchemeLoss(const Scheme& a, const Scheme& b, double keep_loss) {
  std::map<CaneId, std::pair<int, int>> roles;  // 1 kept, 2 spur, 0 neither
  for (CaneId id : a.keep) roles[id].first = 1;
  for (CaneId id : a.spurs) roles[id].first = 2;
  for (CaneId id : b.keep) roles[id].second = 1;
  for (CaneId id : b.spurs) roles[id].second = 2;
  double loss = 0.0;
  for (const auto& [id, r] : roles) {
    loss += keep_loss * ((r.first == 1) != (r.second == 1)) + ((r.first == 2) != (r.second == 2));
  }
  return loss;
}

absl::StatusOr<SchemeLearningResult> LearnSchemeWeights(
    const std::vector<RankingExample>& examples, const SchemeLearningOptions& options,
    const Deadline& deadline) {
  VB_RETURN_IF_ERROR(options.Validate());
  if (examples.empty()) {
    return absl::InvalidArgumentError("LearnSchemeWeights: no examples to learn from");
  }
  std::vector<WorkingSet> sets(examples.size());
  std::vector<FeatureVector> expert_features(examples.size());
  FeatureVector sum_sq = FeatureVector::Zero();
  int initial = 0;
  for (size_t i = 0; i < examples.size(); ++i) {
    const RankingExample& e = examples[i];
    expert_features[i] = SchemeFeatures(e.candidates, e.policy, e.expert);
    for (Scheme& s : OneSwapNeighbours(e)) {
      const FeatureVector d = SchemeFeatures(e.candidates, e.policy, s) - expert_features[i];
      sets[i].initial.push_back({d, SchemeLoss(e.expert, s, options.keep_loss)});
      sets[i].schemes.insert(std::move(s));
      sum_sq += d.cwiseAbs2();
      ++initial;
    }
    VB_RETURN_IF_ERROR(deadline.Check("learning scheme weights"));
  }
  SchemeLearningResult result;
  result.examples = static_cast<int>(examples.size());
  for (int f = 0; f < kSchemeFeatureCount; ++f) {
    const double rms = initial > 0 ? std::sqrt(sum_sq[f] / initial) : 0.0;
    result.feature_scale[f] = rms > 1e-12 ? rms : 1.0;
  }

  SoftmaxMargin objective(options, result.feature_scale, examples.size());
  for (size_t i = 0; i < sets.size(); ++i) {
    for (const Constraint& c : sets[i].initial) objective.Add(i, c);
  }
  FeatureVector w_scaled = FeatureVector::Zero();
  for (int round = 1; round <= options.max_rounds; ++round) {
    w_scaled = objective.Solve(w_scaled);
    result.rounds = round;
    result.weights.w = w_scaled.cwiseQuotient(result.feature_scale);
    int added = 0;
    result.train_agreements = 0;
    for (size_t i = 0; i < examples.size(); ++i) {
      const RankingExample& e = examples[i];
      VB_ASSIGN_OR_RETURN(const Scheme best,
                          FindBestScheme(e.candidates, e.policy, result.weights, deadline));
      if (best == e.expert) {
        ++result.train_agreements;
        continue;
      }
      if (!sets[i].schemes.insert(best).second) continue;
      const FeatureVector d = SchemeFeatures(e.candidates, e.policy, best) - expert_features[i];
      const Constraint c{d, SchemeLoss(e.expert, best, options.keep_loss)};
      objective.Add(i, c);
      ++added;
    }
    if (added == 0) break;
  }
  result.constraints = objective.size();
  result.train_agreement = static_cast<double>(result.train_agreements) / result.examples;
  result.objective = objective.Evaluate(w_scaled, nullptr, nullptr);
  return result;
}

absl::StatusOr<AgreementReport> MeasureAgreement(const std::vector<RankingExample>& examples,
                                                 const SchemeWeights& weights,
                                                 const Deadline& deadline) {
  VB_RETURN_IF_ERROR(weights.Validate());
  AgreementReport report;
  report.examples = static_cast<int>(examples.size());
  for (const RankingExample& e : examples) {
    VB_ASSIGN_OR_RETURN(const Scheme best, FindBestScheme(e.candidates, e.policy, weights, deadline));
    report.keep_agreements += best.keep == e.expert.keep;
    if (best == e.expert) {
      ++report.agreements;
    } else {
      report.disagreements.push_back(e.name);
    }
  }
  report.agreement =
      report.examples > 0 ? static_cast<double>(report.agreements) / report.examples : 0.0;
  return report;
}

std::vector<size_t> HoldOutIndices(size_t count, double fraction) {
  std::vector<size_t> order(count);
  std::iota(order.begin(), order.end(), size_t{0});
  uint64_t state = 0x5EED0004;  // fixed: the split must not change between runs
  for (size_t i = count; i > 1; --i) {
    std::swap(order[i - 1], order[SplitMix64(state) % i]);
  }
  const size_t held = std::min(
      count, static_cast<size_t>(std::llround(std::clamp(fraction, 0.0, 1.0) * count)));
  std::vector<size_t> out(order.begin(), order.begin() + held);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace vb::decide
