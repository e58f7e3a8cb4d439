// SPDX-License-Identifier: Apache-2.0
#include "app/reconstruct_flags.h"

#include <string>
#include <vector>

#include "gtest/gtest.h"

namespace vb::app {
namespace {

absl::StatusOr<Flags> ParseAll(std::vector<const char*> args) {
  args.insert(args.begin(), "vinebot");
  return Flags::Parse(static_cast<int>(args.size()), const_cast<char**>(args.data()), 1);
}

TEST(ReconstructFlags, AbsentFlagsKeepTheDefaults) {
  auto flags = ParseAll({});
  ASSERT_TRUE(flags.ok());
  reconstruct::CorrespondenceOptions options;
  ASSERT_TRUE(ReadSelectionFlags(*flags, &options).ok());
  const reconstruct::CorrespondenceOptions defaults;
  EXPECT_EQ(options.alpha, defaults.alpha);
  EXPECT_EQ(options.context.enabled, defaults.context.enabled);
  EXPECT_EQ(options.context.alpha, defaults.context.alpha);
  EXPECT_TRUE(flags->Finish().ok());
}

TEST(ReconstructFlags, SetsAlphaAndTheContextSelection) {
  auto flags = ParseAll({"--alpha", "5.5", "--select-context", "--context-alpha=12"});
  ASSERT_TRUE(flags.ok());
  reconstruct::CorrespondenceOptions options;
  ASSERT_TRUE(ReadSelectionFlags(*flags, &options).ok());
  EXPECT_DOUBLE_EQ(options.alpha, 5.5);
  EXPECT_TRUE(options.context.enabled);
  EXPECT_DOUBLE_EQ(options.context.alpha, 12.0);
  EXPECT_TRUE(flags->Finish().ok());  // every flag was read
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--alpha", "0"}, "--alpha"},
      {{"--alpha", "-1"}, "--alpha"},
      {{"--alpha", "inf"}, "--alpha"},
      {{"--alpha", "x"}, "--alpha"},
      {{"--context-alpha", "0"}, "--context-alpha"},
      {{"--select-context", "maybe"}, "--select-context"},
      {{"--alpha", "6", "--select-context", "--context-alpha", "5"}, "--context-alpha"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::CorrespondenceOptions options;
    const absl::Status status = ReadSelectionFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
  // A context alpha below alpha is fine while the context selection is off.
  auto flags = ParseAll({"--alpha", "6", "--context-alpha", "5"});
  ASSERT_TRUE(flags.ok());
  reconstruct::CorrespondenceOptions options;
  EXPECT_TRUE(ReadSelectionFlags(*flags, &options).ok());
  EXPECT_DOUBLE_EQ(options.alpha, 6.0);
}

TEST(ReconstructFlags, SweepFlagsKeepTheDefaultsOrSetTheSweep) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::DepthSweepOptions options;
  ASSERT_TRUE(ReadSweepFlags(*absent, &options).ok());
  EXPECT_EQ(options.enabled, reconstruct::DepthSweepOptions{}.enabled);
  EXPECT_EQ(options.min_views, reconstruct::DepthSweepOptions{}.min_views);
  auto flags = ParseAll({"--sweep", "true", "--sweep-min-views", "2", "--sweep-max-step", "3",
                         "--sweep-accept-px", "1.25", "--sweep-max-ambiguous", "0.3",
                         "--sweep-min-stretch-share", "0.4", "--sweep-unique-steps", "2"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadSweepFlags(*flags, &options).ok());
  EXPECT_TRUE(options.enabled);
  EXPECT_EQ(options.min_views, 2);
  EXPECT_EQ(options.max_step, 3);
  EXPECT_DOUBLE_EQ(options.accept_px, 1.25);
  EXPECT_DOUBLE_EQ(options.max_ambiguous_share, 0.3);
  EXPECT_DOUBLE_EQ(options.min_stretch_accepted_share, 0.4);
  EXPECT_EQ(options.unique_exclusion_steps, 2);
  EXPECT_TRUE(flags->Finish().ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, SweepFlagsRejectBadValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--sweep", "maybe"}, "--sweep"},
      {{"--sweep-min-views", "1"}, "--sweep-min-views"},
      {{"--sweep-min-views", "x"}, "--sweep-min-views"},
      {{"--sweep-max-step", "0"}, "--sweep-max-step"},
      {{"--sweep-accept-px", "0"}, "--sweep-accept-px"},
      {{"--sweep-unique-steps", "-1"}, "--sweep-unique-steps"},
      {{"--sweep-max-ambiguous", "1.5"}, "--sweep-max-ambiguous"},
      {{"--sweep-min-stretch-share", "-0.1"}, "--sweep-min-stretch-share"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::DepthSweepOptions options;
    const absl::Status status = ReadSweepFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace vb::app
