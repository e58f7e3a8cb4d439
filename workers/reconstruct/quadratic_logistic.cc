// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/quadratic_logistic.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "Eigen/Core"
#include "workers/reconstruct/logistic.h"

namespace vb::reconstruct {

absl::Status QuadraticLogistic::Validate(int feature_count) const {
  const size_t n = index.size();
  if (mean.size() != n || sd.size() != n) {
    return absl::InvalidArgumentError(
        absl::StrCat("quadratic model: index, mean and sd sizes differ (", n, ", ", mean.size(),
                     ", ", sd.size(), ")"));
  }
  if (weights.size() != 1 + n + n * (n + 1) / 2) {
    return absl::InvalidArgumentError(absl::StrCat("quadratic model: weights has ",
                                                   weights.size(), " values, needs ",
                                                   1 + n + n * (n + 1) / 2));
  }
  for (size_t k = 0; k < n; ++k) {
    if (index[k] < 0 || index[k] >= feature_count) {
      return absl::InvalidArgumentError(
          absl::StrCat("quadratic model: index[", k, "] = ", index[k], " outside [0, ",
                       feature_count, ")"));
    }
    if (!std::isfinite(mean[k]) || !(sd[k] > 0.0) || !std::isfinite(sd[k])) {
      return absl::InvalidArgumentError(
          absl::StrCat("quadratic model: mean[", k, "] or sd[", k, "] not finite or sd <= 0"));
    }
  }
  for (size_t k = 0; k < weights.size(); ++k) {
    if (!std::isfinite(weights[k])) {
      return absl::InvalidArgumentError(
          absl::StrCat("quadratic model: weights[", k, "] not finite"));
    }
  }
  return absl::OkStatus();
}

std::vector<double> QuadraticLogistic::Expand(std::span<const double> x) const {
  const size_t n = index.size();
  std::vector<double> out;
  out.reserve(1 + n + n * (n + 1) / 2);
  out.push_back(1.0);
  for (size_t k = 0; k < n; ++k) out.push_back((x[index[k]] - mean[k]) / sd[k]);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i; j < n; ++j) out.push_back(out[1 + i] * out[1 + j]);
  return out;
}

double QuadraticLogistic::Probability(std::span<const double> x) const {
  const std::vector<double> e = Expand(x);
  double z = 0.0;
  for (size_t k = 0; k < e.size() && k < weights.size(); ++k) z += e[k] * weights[k];
  return LogisticOfScore(z);
}

std::string QuadraticLogisticSource(const QuadraticLogistic& model, const std::string& name) {
  std::string out =
      absl::StrCat("  ", name, ".index = {", absl::StrJoin(model.index, ", "), "};\n");
  const std::pair<const char*, const std::vector<double>*> fields[] = {
      {"mean", &model.mean}, {"sd", &model.sd}, {"weights", &model.weights}};
  for (const auto& [field, values] : fields) {
    absl::StrAppend(&out, "  ", name, ".", field, " = {");
    for (size_t i = 0; i < values->size(); ++i) {
      absl::StrAppend(&out, i == 0 ? "\n      " : (i % 6 == 0 ? ",\n      " : ", "),
                      absl::StrFormat("%.9g", (*values)[i]));
    }
    absl::StrAppend(&out, "};\n");
  }
  return out;
}

absl::StatusOr<QuadraticLogistic> TrainQuadraticLogistic(
    const std::vector<std::vector<double>>& rows, const std::vector<bool>& right,
    const std::vector<int>& index, double l2, int iterations) {
  if (rows.empty()) return absl::InvalidArgumentError("rows: empty");
  if (right.size() != rows.size()) {
    return absl::InvalidArgumentError("right: one label per row needed");
  }
  const size_t features = rows[0].size();
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].size() != features) {
      return absl::InvalidArgumentError(absl::StrCat("rows[", r, "]: ", rows[r].size(),
                                                     " features, rows[0] has ", features));
    }
    for (double v : rows[r]) {
      if (!std::isfinite(v)) {
        return absl::InvalidArgumentError(absl::StrCat("rows[", r, "]: non-finite feature"));
      }
    }
  }
  const size_t positives = std::count(right.begin(), right.end(), true);
  if (positives == 0 || positives == rows.size()) {
    return absl::InvalidArgumentError("right: need both labels");
  }
  QuadraticLogistic model;
  model.index = index;
  const size_t n = index.size();
  model.mean.assign(n, 0.0);
  model.sd.assign(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    if (index[k] < 0 || static_cast<size_t>(index[k]) >= features) {
      return absl::InvalidArgumentError(absl::StrCat("index[", k, "] out of range"));
    }
    for (const auto& x : rows) model.mean[k] += x[index[k]];
    model.mean[k] /= static_cast<double>(rows.size());
    for (const auto& x : rows) model.sd[k] += std::pow(x[index[k]] - model.mean[k], 2);
    model.sd[k] /= static_cast<double>(rows.size());
    model.sd[k] = model.sd[k] > 1e-24 ? std::sqrt(model.sd[k]) : 1.0;
  }
  const int d = static_cast<int>(1 + n + n * (n + 1) / 2);
  model.weights.assign(d, 0.0);
  Eigen::MatrixXd expanded(static_cast<Eigen::Index>(rows.size()), d);
  for (size_t r = 0; r < rows.size(); ++r) {
    const std::vector<double> e = model.Expand(rows[r]);
    expanded.row(static_cast<Eigen::Index>(r)) = Eigen::Map<const Eigen::RowVectorXd>(e.data(), d);
  }
  Eigen::VectorXd y(expanded.rows());
  for (size_t r = 0; r < rows.size(); ++r) y(static_cast<Eigen::Index>(r)) = right[r] ? 1.0 : 0.0;
  Eigen::VectorXd ridge = Eigen::VectorXd::Constant(d, l2);
  ridge(0) = 0.0;
  const absl::StatusOr<Eigen::VectorXd> fitted =
      FitLogisticNewton(expanded, y, ridge, iterations, "TrainQuadraticLogistic");
  if (!fitted.ok()) return fitted.status();
  const Eigen::VectorXd& w = *fitted;
  for (int k = 0; k < d; ++k) model.weights[k] = w(k);
  return model;
}

}  // namespace vb::reconstruct
