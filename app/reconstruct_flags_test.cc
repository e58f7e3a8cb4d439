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

TEST(ReconstructFlags, HeadBasesFlagsKeepTheDefaultsOrSetTheOptions) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::HeadBasesOptions options;
  ASSERT_TRUE(ReadHeadBasesFlags(*absent, &options).ok());
  const reconstruct::HeadBasesOptions defaults;
  EXPECT_EQ(options.enabled, defaults.enabled);
  EXPECT_EQ(options.reach_m, defaults.reach_m);
  EXPECT_EQ(options.min_thick_views, defaults.min_thick_views);
  EXPECT_EQ(options.max_inside_m, defaults.max_inside_m);

  auto flags = ParseAll({"--head-bases", "--head-bases-reach", "0.2",
                         "--head-bases-thick-views=3", "--head-bases-inside", "0.01"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadHeadBasesFlags(*flags, &options).ok());
  EXPECT_TRUE(options.enabled);
  EXPECT_DOUBLE_EQ(options.reach_m, 0.2);
  EXPECT_EQ(options.min_thick_views, 3);
  EXPECT_DOUBLE_EQ(options.max_inside_m, 0.01);
  EXPECT_TRUE(flags->Finish().ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadHeadBasesValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--head-bases-reach", "0"}, "--head-bases-reach"},
      {{"--head-bases-reach", "nan"}, "--head-bases-reach"},
      {{"--head-bases-thick-views", "0"}, "--head-bases-thick-views"},
      {{"--head-bases-inside", "-0.01"}, "--head-bases-inside"},
      {{"--head-bases", "maybe"}, "--head-bases"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::HeadBasesOptions options;
    const absl::Status status = ReadHeadBasesFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace vb::app
