// SPDX-License-Identifier: Apache-2.0
// A logistic model on the quadratic expansion of standardised features, for classifiers whose
// classes a linear score does not separate well (beyond the paper's linear classifiers; the match
// classifier since session 25, docs/reconstruction.md section 3, "A quadratic match classifier").
// Thread-safe (immutable after construction).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace vb::reconstruct {

// With z_k = (x[index[k]] - mean[k]) / sd[k] for the n base features, the score is
//   weights[0] + sum_k weights[1 + k] z_k + sum_{i <= j} w_ij z_i z_j,
// the products in the order i = 0..n-1, j = i..n-1 (1 + n + n (n + 1) / 2 weights), and the
// probability 1 / (1 + exp(-score)), the score clamped to [-40, 40].
struct QuadraticLogistic {
  std::vector<int> index;
  std::vector<double> mean;
  std::vector<double> sd;
  std::vector<double> weights;

  bool empty() const { return weights.empty(); }
  // OK if the sizes agree, every index lies in [0, feature_count), every sd is > 0 and every
  // value is finite; INVALID_ARGUMENT naming the field otherwise.
  absl::Status Validate(int feature_count) const;
  // The expansion (1, z, products) of x; x must hold every index.
  std::vector<double> Expand(std::span<const double> x) const;
  double Probability(std::span<const double> x) const;
};

// `model` as C++ statements assigning its fields to the variable `name` (for pasting the trained
// model into a source file: the training tools print it).
std::string QuadraticLogisticSource(const QuadraticLogistic& model, const std::string& name);

// Trains a QuadraticLogistic on `rows` (each a feature vector) labelled by `right`: the base
// features `index`, standardised by their mean and population sd over `rows` (sd 1 where
// constant), fitted by Newton's method with a ridge `l2` on every weight but the bias.
// INVALID_ARGUMENT if rows is empty, the sizes disagree, an index is out of range, a value is not
// finite or only one label occurs; INTERNAL if the iteration diverges.
absl::StatusOr<QuadraticLogistic> TrainQuadraticLogistic(
    const std::vector<std::vector<double>>& rows, const std::vector<bool>& right,
    const std::vector<int>& index, double l2, int iterations = 30);

}  // namespace vb::reconstruct
