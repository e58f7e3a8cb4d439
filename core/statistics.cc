// SPDX-License-Identifier: Apache-2.0
#include "core/statistics.h"

#include <algorithm>
#include <cmath>

namespace vb {

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  q = std::clamp(q, 0.0, 1.0);
  const double position = q * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(position));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  // Two partial selections instead of a full sort: the quantile needs only two order statistics.
  std::nth_element(values.begin(), values.begin() + lo, values.end());
  const double a = values[lo];
  if (hi == lo) return a;
  const double b = *std::min_element(values.begin() + lo + 1, values.end());
  return a + (position - static_cast<double>(lo)) * (b - a);
}

}  // namespace vb
