// SPDX-License-Identifier: Apache-2.0
// Logistic regression shared by the trained classifiers of reconstruction (match_classifier.h,
// join_classifier.h): the probability of a linear score, and maximum a posteriori training by
// Newton's method (iteratively reweighted least squares) with a ridge penalty on every weight
// but the first (the bias). Header-only (templated on the feature count); thread-safe.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "Eigen/Cholesky"
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

// Trains on `examples`, each with `features` (std::array<double, N>) and `right` (its label).
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
  constexpr int d = static_cast<int>(N);
  using Vector = Eigen::Matrix<double, d, 1>;
  Vector w = Vector::Zero();
  Vector ridge = Vector::Constant(l2);
  ridge(0) = 1e-6;
  for (int it = 0; it < iterations; ++it) {
    Eigen::Matrix<double, d, d> h = ridge.asDiagonal();
    Vector g = ridge.cwiseProduct(w);
    for (const Example& e : examples) {
      const Eigen::Map<const Vector> x(e.features.data());
      const double z = std::clamp(w.dot(x), -40.0, 40.0);
      const double p = 1.0 / (1.0 + std::exp(-z));
      g += (p - (e.right ? 1.0 : 0.0)) * x;
      h += std::max(p * (1.0 - p), 1e-9) * x * x.transpose();
    }
    const Vector step = h.ldlt().solve(g);
    if (!step.allFinite()) return absl::InternalError(caller + ": diverged");
    w -= step;
    if (step.norm() < 1e-8) break;
  }
  std::array<double, N> out;
  for (int i = 0; i < d; ++i) out[i] = w(i);
  return out;
}

}  // namespace vb::reconstruct
