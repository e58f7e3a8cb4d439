// SPDX-License-Identifier: Apache-2.0
#include "app/flags.h"

#include <vector>

#include "gtest/gtest.h"

namespace vb::app {
namespace {

absl::StatusOr<Flags> ParseAll(std::vector<const char*> args) {
  args.insert(args.begin(), "vinebot");
  return Flags::Parse(static_cast<int>(args.size()), const_cast<char**>(args.data()), 1);
}

TEST(Flags, ParsesValuesInBothSpellings) {
  auto flags = ParseAll({"--seed", "7", "--out=/tmp/x", "--scale", "0.5", "--no-noise"});
  ASSERT_TRUE(flags.ok()) << flags.status();
  EXPECT_EQ(*flags->Int("seed", 0), 7);
  EXPECT_EQ(*flags->String("out", ""), "/tmp/x");
  EXPECT_DOUBLE_EQ(*flags->Double("scale", 1.0), 0.5);
  EXPECT_TRUE(*flags->Bool("no-noise", false));
  EXPECT_EQ(*flags->Int("vine", 3), 3);  // absent -> fallback
  EXPECT_TRUE(flags->Finish().ok());
}

TEST(Flags, NegativeNumbersAreValues) {
  auto flags = ParseAll({"--vine", "-3"});
  ASSERT_TRUE(flags.ok());
  // "-3" does not start with "--", so it is the value.
  EXPECT_EQ(*flags->Int("vine", 0), -3);
}

TEST(Flags, RejectsBadValuesNamingTheFlag) {
  auto flags = ParseAll({"--seed", "seven", "--scale", "nan", "--on", "maybe"});
  ASSERT_TRUE(flags.ok());
  auto seed = flags->Int("seed", 0);
  EXPECT_EQ(seed.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(seed.status().message().find("--seed"), std::string::npos);
  EXPECT_NE(flags->Double("scale", 0).status().message().find("--scale"), std::string::npos);
  EXPECT_NE(flags->Bool("on", false).status().message().find("--on"), std::string::npos);
  EXPECT_NE(flags->RequiredString("out").status().message().find("--out: required"),
            std::string::npos);
}

TEST(Flags, PixelFormatParsesOrNamesTheFlag) {
  auto flags = ParseAll({"--pixel-format", "bayer_gb8", "--other", "yuv"});
  ASSERT_TRUE(flags.ok());
  EXPECT_EQ(*flags->Format("pixel-format", PixelFormat::kRgb8), PixelFormat::kBayerGb8);
  EXPECT_EQ(*flags->Format("absent", PixelFormat::kMono8), PixelFormat::kMono8);
  auto bad = flags->Format("other", PixelFormat::kRgb8);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("--other: pixel_format: unknown 'yuv'"), std::string::npos)
      << bad.status().message();
}

TEST(Flags, FinishRejectsUnreadFlags) {
  auto flags = ParseAll({"--seed", "1", "--sede", "2"});
  ASSERT_TRUE(flags.ok());
  (void)flags->Int("seed", 0);
  const absl::Status s = flags->Finish();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("--sede"), std::string::npos);
}

TEST(Flags, ParseRejectsPositionalArguments) {
  EXPECT_FALSE(ParseAll({"render"}).ok());
  EXPECT_FALSE(ParseAll({"--"}).ok());
}

}  // namespace
}  // namespace vb::app
