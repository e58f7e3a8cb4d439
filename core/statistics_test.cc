// SPDX-License-Identifier: Apache-2.0
#include "core/statistics.h"

#include "gtest/gtest.h"

namespace vb {
namespace {

TEST(Quantile, InterpolatesBetweenOrderStatistics) {
  const std::vector<double> v = {5, 1, 4, 2, 3};  // sorted: 1 2 3 4 5
  EXPECT_DOUBLE_EQ(Quantile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Quantile(v, 1.0), 5.0);
  EXPECT_DOUBLE_EQ(Median(v), 3.0);
  EXPECT_DOUBLE_EQ(Quantile(v, 0.1), 1.4);  // position 0.4
  EXPECT_DOUBLE_EQ(Quantile(v, 0.95), 4.8);  // position 3.8
  EXPECT_DOUBLE_EQ(Median({1, 2, 3, 10}), 2.5);
  EXPECT_DOUBLE_EQ(Quantile(v, 7.0), 5.0);  // clamped
}

TEST(Quantile, EmptyAndSingle) {
  EXPECT_EQ(Quantile({}, 0.5), 0.0);
  EXPECT_EQ(Quantile({7}, 0.9), 7.0);
}

}  // namespace
}  // namespace vb
