// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/logistic.h"

#include "Eigen/Cholesky"

namespace vb::reconstruct {

absl::StatusOr<Eigen::VectorXd> FitLogisticNewton(const Eigen::MatrixXd& x,
                                                  const Eigen::VectorXd& y,
                                                  const Eigen::VectorXd& ridge, int iterations,
                                                  const std::string& caller) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(x.cols());
  for (int it = 0; it < iterations; ++it) {
    const Eigen::VectorXd z = (x * w).cwiseMax(-40.0).cwiseMin(40.0);
    const Eigen::VectorXd p = (1.0 + (-z.array()).exp()).inverse().matrix();
    const Eigen::VectorXd g = x.transpose() * (p - y) + ridge.cwiseProduct(w);
    const Eigen::VectorXd s = (p.array() * (1.0 - p.array())).max(1e-9).matrix();
    Eigen::MatrixXd h = x.transpose() * s.asDiagonal() * x;
    h.diagonal() += ridge;
    h.diagonal().array() += 1e-9;
    const Eigen::VectorXd step = h.ldlt().solve(g);
    if (!step.allFinite()) return absl::InternalError(caller + ": diverged");
    w -= step;
    if (step.norm() < 1e-8) break;
  }
  return w;
}

}  // namespace vb::reconstruct
