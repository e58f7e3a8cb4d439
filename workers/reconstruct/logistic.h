// SPDX-License-Identifier: Apache-2.0
// Logistic regression shared by the trained classifiers of reconstruction (match_classifier.h,
// join_classifier.h, quadratic_logistic.h): the probability of a linear score, and maximum a
// posteriori training by Newton's method (iteratively reweighted least squares) with a ridge
// penalty. TrainLogistic is templated on the feature count; FitLogisticNewton (logistic.cc) is
// the solver both it and TrainQuadraticLogistic use. Thread-safe.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "Eigen/Core"

namespace vb::reconstruct {

// 1 / (1 + exp(-score)), the score clamped to [-40, 40].
inline double LogisticOfScore(double score) {
  return 1.0 / (1.0 + std::exp(-std::clamp(score, -40.0, 40.0)));
}

// 1 / (1 + exp(-w . x)), the score clamped to [-40, 40].
template <size_t N>
double LogisticProbability(const std::array<double, N>& x, const std::array<double, N>& w) {
  double z = 0.0;
  for (size_t i = 0; i < N; ++i) z += x[i] * w[i];
  return LogisticOfScore(z);
}

// Newton's method for the weights w maximising sum_r log P(y_r | x_r) - sum_i ridge_i w_i^2 / 2,
// P(1 | x) = 1 / (1 + exp(-w . x)): the rows of `x` are the examples, `y` their labels (0 or 1),
// `ridge` one penalty per column. Scores are clamped to [-40, 40], weights p (1 - p) below 1e-9
// raised to it and 1e-9 added to the Hessian's diagonal; stops after `iterations` steps or a
// step shorter than 1e-8. INTERNAL naming `caller` if a step is not finite. The caller checks
// the examples (sizes, finite values, both labels).
absl::StatusOr<Eigen::VectorXd> FitLogisticNewton(const Eigen::MatrixXd& x,
                                                  const Eigen::VectorXd& y,
                                                  const Eigen::VectorXd& ridge, int iterations,
                                                  const std::string& caller);

// Trains on `examples`, each with `features` (std::array<double, N>) and `right` (its label):
// FitLogisticNewton with ridge `l2` on every weight but the first (the bias, 1e-6).
// `what` names the examples in errors ("matches"), `caller` the trainer.
// INVALID_ARGUMENT if `examples` is empty, holds only one label, or a non-finite feature;
// INTERNAL if the iteration diverges.
template <size_t N, typename Example>
absl::StatusOr<std::array<double, N>> TrainLogistic(const std::vector<Example>& examples,
                                                    double l2, int iterations,
                                                    const std::string& what,
                                                    const std::string& caller) {
  if (examples.empty()) return absl::InvalidArgumentError("examples: empty");
  int positives = 0;
  for (size_t i = 0; i < examples.size(); ++i) {
    positives += examples[i].right ? 1 : 0;
    for (double v : examples[i].features) {
      if (!std::isfinite(v)) {
        return absl::InvalidArgumentError("examples[" + std::to_string(i) +
                                          "]: non-finite feature");
      }
    }
  }
  if (positives == 0 || positives == static_cast<int>(examples.size())) {
    return absl::InvalidArgumentError("examples: need both right and wrong " + what);
  }
  const Eigen::Index d = static_cast<Eigen::Index>(N);
  Eigen::MatrixXd x(static_cast<Eigen::Index>(examples.size()), d);
  Eigen::VectorXd y(x.rows());
  for (size_t r = 0; r < examples.size(); ++r) {
    const auto row = static_cast<Eigen::Index>(r);
    for (Eigen::Index i = 0; i < d; ++i) x(row, i) = examples[r].features[i];
    y(row) = examples[r].right ? 1.0 : 0.0;
  }
  Eigen::VectorXd ridge = Eigen::VectorXd::Constant(d, l2);
  ridge(0) = 1e-6;
  const absl::StatusOr<Eigen::VectorXd> w = FitLogisticNewton(x, y, ridge, iterations, caller);
  if (!w.ok()) return w.status();
  std::array<double, N> out;
  for (Eigen::Index i = 0; i < d; ++i) out[i] = (*w)(i);
  return out;
}

}  // namespace vb::reconstruct
