// SPDX-License-Identifier: Apache-2.0
// Order statistics of samples, as the metrics and phenomics report them. Thread-safe (pure).
#pragma once

#include <vector>

namespace vb {

// The q-quantile (q in [0, 1], clamped) of `values` by linear interpolation between order
// statistics (Hyndman & Fan 1996 definition 7, numpy's default): position q * (n - 1).
// 0 for no values.
double Quantile(std::vector<double> values, double q);
inline double Median(std::vector<double> values) { return Quantile(std::move(values), 0.5); }

}  // namespace vb
