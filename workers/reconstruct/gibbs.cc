// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/gibbs.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

// SplitMix64: tiny, portable, and deterministic (std distributions are not across libraries).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  // Uniform in [0, n).
  size_t Below(size_t n) { return static_cast<size_t>(Uniform() * static_cast<double>(n)); }

 private:
  uint64_t state_;
};

}  // namespace

absl::Status GibbsOptions::Validate() const {
  if (burn_in_sweeps < 0) {
    return absl::InvalidArgumentError(absl::StrCat("burn_in_sweeps must be >= 0, got ",
                                                   burn_in_sweeps));
  }
  if (sweeps < 1) {
    return absl::InvalidArgumentError(absl::StrCat("sweeps must be >= 1, got ", sweeps));
  }
  return absl::OkStatus();
}

std::vector<double> GibbsMarginals(const std::vector<double>& probabilities,
                                   const std::vector<std::vector<int>>& conflicts,
                                   const GibbsOptions& options_in) {
  const GibbsOptions options = options_in.Validate().ok() ? options_in : GibbsOptions{};
  const int n = static_cast<int>(probabilities.size());
  std::vector<double> p(n);
  for (int i = 0; i < n; ++i) {
    const double q = probabilities[i];
    p[i] = std::isnan(q) ? 0.0 : std::clamp(q, 0.0, 1.0);
  }
  // Symmetric, deduplicated adjacency.
  std::vector<std::vector<int>> adjacent(n);
  for (int i = 0; i < n && i < static_cast<int>(conflicts.size()); ++i) {
    for (int j : conflicts[i]) {
      if (j < 0 || j >= n || j == i) continue;
      adjacent[i].push_back(j);
      adjacent[j].push_back(i);
    }
  }
  std::vector<int> coupled;  // only variables with conflicts need sampling
  for (int i = 0; i < n; ++i) {
    auto& a = adjacent[i];
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    if (!a.empty() && p[i] > 0.0) coupled.push_back(i);
  }
  std::vector<double> marginals = p;
  if (coupled.empty()) return marginals;

  // blocking[i]: number of true neighbours of i; x_i may be true only when it is 0.
  std::vector<char> x(n, 0);
  std::vector<int> blocking(n, 0);
  std::vector<double> sum(n, 0.0);
  Rng rng(options.seed);
  std::vector<int> order = coupled;
  const int total = options.burn_in_sweeps + options.sweeps;
  for (int sweep = 0; sweep < total; ++sweep) {
    // Fisher-Yates shuffle: a random scan order avoids the bias of a fixed sweep direction.
    for (size_t k = order.size(); k > 1; --k) std::swap(order[k - 1], order[rng.Below(k)]);
    const bool record = sweep >= options.burn_in_sweeps;
    for (int i : order) {
      const double conditional = blocking[i] > 0 ? 0.0 : p[i];
      if (record) sum[i] += conditional;
      const char value = rng.Uniform() < conditional ? 1 : 0;
      if (value != x[i]) {
        const int delta = value ? 1 : -1;
        for (int j : adjacent[i]) blocking[j] += delta;
        x[i] = value;
      }
    }
  }
  for (int i : coupled) marginals[i] = sum[i] / options.sweeps;
  return marginals;
}

std::vector<int> SelectMinimumExpectedLoss(const std::vector<double>& marginals, double alpha) {
  std::vector<int> kept;
  if (!(alpha > 0.0)) return kept;
  const double threshold = std::isinf(alpha) ? 0.0 : 1.0 / (1.0 + alpha);
  for (size_t i = 0; i < marginals.size(); ++i) {
    if (marginals[i] > threshold) kept.push_back(static_cast<int>(i));
  }
  return kept;
}

}  // namespace vb::reconstruct
