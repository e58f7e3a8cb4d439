// SPDX-License-Identifier: Apache-2.0
// The head's cropped distance maps (head_carve.h CroppedDistance, SetDistance) against OpenCV's
// full-frame transform, pixel by pixel.
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "gtest/gtest.h"
#include "opencv2/imgproc.hpp"
#include "workers/reconstruct/head_carve.h"

namespace vb::reconstruct {
namespace {

using head_internal::CroppedDistance;
using head_internal::SetDistance;

constexpr int kWidth = 320;
constexpr int kHeight = 240;

// A head-like set: a disc on a trunk running to the bottom edge, and a lobe.
std::vector<uint8_t> HeadSet() {
  cv::Mat mask = cv::Mat::zeros(kHeight, kWidth, CV_8U);
  cv::circle(mask, {150, 90}, 30, 1, -1);
  cv::rectangle(mask, {140, 90}, {158, kHeight - 1}, 1, -1);
  cv::ellipse(mask, {190, 80}, {18, 9}, 30.0, 0.0, 360.0, 1, -1);
  return std::vector<uint8_t>(mask.datastart, mask.dataend);
}

// cv::distanceTransform over the whole frame: to the set, or from inside it to the pixels off it.
cv::Mat FullFrame(const std::vector<uint8_t>& set, bool to_set) {
  const cv::Mat mask(kHeight, kWidth, CV_8U, const_cast<uint8_t*>(set.data()));
  cv::Mat distance;
  cv::distanceTransform(to_set ? (mask == 0) : (mask != 0), distance, cv::DIST_L2, 3);
  return distance;
}

// Inside its crop the map is the full frame's to the last bit; outside, +infinity where the
// full frame's exceeds kChamferStep x margin. The crop is a small share of the frame.
TEST(CroppedDistance, ToTheSetEqualsTheFullFrameWithinTheMargin) {
  const std::vector<uint8_t> set = HeadSet();
  const cv::Mat full = FullFrame(set, true);
  for (int margin : {0, 12, 40}) {
    const CroppedDistance cropped = CroppedDistance::ToSet(set, kWidth, kHeight, margin);
    int inside = 0, outside = 0;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const float got = cropped.At(x, y);
        if (std::isinf(got)) {
          ++outside;
          EXPECT_GT(full.at<float>(y, x), CroppedDistance::kChamferStep * margin)
              << "margin " << margin << " at " << x << ", " << y;
        } else {
          ++inside;
          ASSERT_EQ(got, full.at<float>(y, x)) << "margin " << margin << " at " << x << ", " << y;
        }
      }
    }
    EXPECT_EQ(inside, static_cast<int>(std::lround(cropped.CroppedShare() * kWidth * kHeight)));
    EXPECT_GT(outside, 0);
    EXPECT_LT(cropped.CroppedShare(), margin == 40 ? 0.6 : 0.35);
  }
}

TEST(CroppedDistance, InsideTheSetEqualsTheFullFrameEverywhere) {
  const std::vector<uint8_t> set = HeadSet();
  const cv::Mat full = FullFrame(set, false);
  const CroppedDistance cropped = CroppedDistance::InsideSet(set, kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      ASSERT_EQ(cropped.At(x, y), full.at<float>(y, x)) << x << ", " << y;
    }
  }
  EXPECT_LT(cropped.CroppedShare(), 0.25);
}

TEST(CroppedDistance, AnEmptySetIsFarEverywhere) {
  const std::vector<uint8_t> empty(static_cast<size_t>(kWidth) * kHeight, 0);
  const CroppedDistance to = CroppedDistance::ToSet(empty, kWidth, kHeight, 30);
  const CroppedDistance inside = CroppedDistance::InsideSet(empty, kWidth, kHeight);
  for (int y = 0; y < kHeight; y += 7) {
    for (int x = 0; x < kWidth; x += 7) {
      EXPECT_EQ(to.At(x, y), std::numeric_limits<float>::infinity());
      EXPECT_EQ(inside.At(x, y), 0.0f);
    }
  }
  EXPECT_EQ(to.CroppedShare(), 0.0);
}

// Only the columns asked for count: the head's columns alone give the distance to the head.
TEST(CroppedDistance, CountsOnlyTheColumnsAskedFor) {
  std::vector<uint8_t> set = HeadSet();
  const std::vector<uint8_t> head_only = set;
  for (int y = 0; y < kHeight; ++y) set[static_cast<size_t>(y) * kWidth + 20] = 1;  // a line
  const cv::Mat full = FullFrame(head_only, true);
  const CroppedDistance cropped = CroppedDistance::ToSet(set, kWidth, kHeight, 30, 100, 250);
  for (int y = 0; y < kHeight; y += 3) {
    for (int x = 0; x < kWidth; x += 3) {
      const float got = cropped.At(x, y);
      if (!std::isinf(got)) ASSERT_EQ(got, full.at<float>(y, x)) << x << ", " << y;
    }
  }
}

// Posts at both edges and a head between: three bands, a fraction of the frame; every threshold
// test agrees with the full-frame map, those above kChamferStep x margin through the fallback,
// which runs only when such a test falls outside every band.
TEST(SetDistance, ThresholdTestsAgreeWithTheFullFrame) {
  std::vector<uint8_t> set = HeadSet();
  for (int y = 0; y < kHeight; ++y) {
    for (int x : {3, 4, 5, 6, 300, 301, 302}) set[static_cast<size_t>(y) * kWidth + x] = 1;
  }
  const cv::Mat full = FullFrame(set, true);
  const int margin = 16;
  const SetDistance below(set, kWidth, kHeight, margin);
  EXPECT_LT(below.CroppedShare(), 0.75);
  for (double threshold : {0.0, 3.5, 10.0, 14.0}) {  // below 0.955 x 16
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        ASSERT_EQ(below.Exceeds(x, y, threshold), full.at<float>(y, x) > threshold)
            << threshold << " at " << x << ", " << y;
      }
    }
  }
  EXPECT_FALSE(below.FullFrameComputed());
  const SetDistance above(set, kWidth, kHeight, margin);
  for (double threshold : {20.0, 60.0}) {
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        ASSERT_EQ(above.Exceeds(x, y, threshold), full.at<float>(y, x) > threshold)
            << threshold << " at " << x << ", " << y;
      }
    }
  }
  EXPECT_TRUE(above.FullFrameComputed());
}

TEST(SetDistance, AnEmptySetExceedsEveryThreshold) {
  const std::vector<uint8_t> empty(static_cast<size_t>(kWidth) * kHeight, 0);
  const SetDistance none(empty, kWidth, kHeight, 16);
  EXPECT_EQ(none.CroppedShare(), 0.0);
  for (double threshold : {0.0, 5.0, 100.0}) EXPECT_TRUE(none.Exceeds(10, 10, threshold));
}

}  // namespace
}  // namespace vb::reconstruct
