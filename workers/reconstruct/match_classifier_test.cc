// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/match_classifier.h"

#include "gtest/gtest.h"

namespace vb::reconstruct {
namespace {

TEST(MatchClassifier, DefaultWeightsAreFinite) {
  const MatchClassifier c = DefaultMatchClassifier();
  for (int i = 0; i < kMatchFeatureCount; ++i) {
    EXPECT_TRUE(std::isfinite(c.multi_view[i]));
    EXPECT_TRUE(std::isfinite(c.two_view[i]));
  }
}

}  // namespace
}  // namespace vb::reconstruct
