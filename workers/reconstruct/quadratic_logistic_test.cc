// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/quadratic_logistic.h"

#include <cmath>
#include <utility>
#include <vector>

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

// A model of two base features with zero weights.
QuadraticLogistic TwoFeatures(std::vector<int> index, std::vector<double> mean,
                              std::vector<double> sd) {
  QuadraticLogistic m;
  m.index = std::move(index);
  m.mean = std::move(mean);
  m.sd = std::move(sd);
  m.weights.assign(6, 0.0);
  return m;
}

TEST(QuadraticLogistic, ExpandsStandardisedFeaturesAndTheirProductsInOrder) {
  QuadraticLogistic m = TwoFeatures({2, 0}, {1.0, 10.0}, {2.0, 5.0});
  ASSERT_TRUE(m.Validate(3).ok());
  const std::vector<double> x = {25.0, -1.0, 5.0};  // z = ((5 - 1) / 2, (25 - 10) / 5) = (2, 3)
  const std::vector<double> e = m.Expand(x);
  ASSERT_EQ(e.size(), 6u);
  EXPECT_DOUBLE_EQ(e[0], 1.0);
  EXPECT_DOUBLE_EQ(e[1], 2.0);
  EXPECT_DOUBLE_EQ(e[2], 3.0);
  EXPECT_DOUBLE_EQ(e[3], 4.0);  // z0 z0
  EXPECT_DOUBLE_EQ(e[4], 6.0);  // z0 z1
  EXPECT_DOUBLE_EQ(e[5], 9.0);  // z1 z1
  m.weights = {-1.0, 0.5, 0.0, 0.0, -0.25, 0.0};  // score -1 + 1 - 1.5 = -1.5
  EXPECT_NEAR(m.Probability(x), 1.0 / (1.0 + std::exp(1.5)), 1e-12);
}

TEST(QuadraticLogistic, ValidateNamesTheBadField) {
  QuadraticLogistic m = TwoFeatures({0, 1}, {0.0, 0.0}, {1.0, 1.0});
  EXPECT_TRUE(m.Validate(2).ok());
  EXPECT_NE(m.Validate(1).message().find("index[1]"), std::string::npos);
  m.weights.pop_back();
  EXPECT_NE(m.Validate(2).message().find("weights has 5 values, needs 6"), std::string::npos);
  m.weights.assign(6, 0.0);
  m.sd[0] = 0.0;
  EXPECT_NE(m.Validate(2).message().find("sd[0]"), std::string::npos);
  m.sd[0] = 1.0;
  m.weights[3] = NAN;
  EXPECT_NE(m.Validate(2).message().find("weights[3]"), std::string::npos);
}

// Labels set by the sign of x0 * x1 (no linear score separates them): the quadratic model
// learns them.
TEST(QuadraticLogistic, LearnsAnInteractionALinearScoreCannot) {
  std::vector<std::vector<double>> rows;
  std::vector<bool> right;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const double a = -1.0 + 0.1 * i + 0.05, b = 3.0 + 0.2 * j + 0.1;  // b - 5 changes sign
      rows.push_back({a, b, 7.0});                                      // feature 2 constant
      right.push_back(a * (b - 5.0) > 0.0);
    }
  const auto m = TrainQuadraticLogistic(rows, right, {0, 1, 2}, 0.1);
  ASSERT_TRUE(m.ok()) << m.status();
  ASSERT_TRUE(m->Validate(3).ok());
  EXPECT_DOUBLE_EQ(m->sd[2], 1.0);  // constant: left unscaled
  int correct = 0;
  for (size_t r = 0; r < rows.size(); ++r) correct += (m->Probability(rows[r]) > 0.5) == right[r];
  EXPECT_GE(correct, 390);  // of 400
}

TEST(QuadraticLogistic, TrainingRejectsBadInput) {
  EXPECT_FALSE(TrainQuadraticLogistic({}, {}, {0}, 1.0).ok());
  EXPECT_FALSE(TrainQuadraticLogistic({{1.0}, {2.0}}, {true, true}, {0}, 1.0).ok());
  EXPECT_FALSE(TrainQuadraticLogistic({{1.0}, {2.0}}, {true, false}, {1}, 1.0).ok());
  EXPECT_FALSE(TrainQuadraticLogistic({{1.0}, {NAN}}, {true, false}, {0}, 1.0).ok());
  EXPECT_FALSE(TrainQuadraticLogistic({{1.0}, {2.0, 3.0}}, {true, false}, {0}, 1.0).ok());
}

}  // namespace
}  // namespace vb::reconstruct
