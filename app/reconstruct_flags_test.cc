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
  EXPECT_FALSE(options.classifier.multi_view_quadratic.empty());  // quadratic by default
  EXPECT_TRUE(flags->Finish().ok());
}

TEST(ReconstructFlags, MatchModelChoosesTheMultiViewClassifier) {
  auto linear = ParseAll({"--match-model", "linear"});
  ASSERT_TRUE(linear.ok());
  reconstruct::CorrespondenceOptions options;
  ASSERT_TRUE(ReadSelectionFlags(*linear, &options).ok());
  EXPECT_TRUE(options.classifier.multi_view_quadratic.empty());
  EXPECT_TRUE(options.Validate().ok());
  auto quadratic = ParseAll({"--match-model=quadratic"});
  ASSERT_TRUE(quadratic.ok());
  ASSERT_TRUE(ReadSelectionFlags(*quadratic, &options).ok());
  EXPECT_EQ(options.classifier.multi_view_quadratic.weights,
            reconstruct::DefaultQuadraticMatchModel().weights);
}

TEST(ReconstructFlags, JoinModelChoosesTheJoinClassifier) {
  auto linear = ParseAll({"--join-model", "linear"});
  ASSERT_TRUE(linear.ok());
  reconstruct::ConnectOptions options;
  EXPECT_FALSE(options.join_weights.cane_quadratic.empty());  // quadratic by default
  ASSERT_TRUE(ReadConnectFlags(*linear, &options).ok());
  EXPECT_TRUE(options.join_weights.cane_quadratic.empty());
  EXPECT_TRUE(options.join_weights.root_quadratic.empty());
  EXPECT_EQ(options.join_weights.cane, reconstruct::DefaultJoinWeights().cane);  // kept
  auto quadratic = ParseAll({"--join-model=quadratic"});
  ASSERT_TRUE(quadratic.ok());
  ASSERT_TRUE(ReadConnectFlags(*quadratic, &options).ok());
  EXPECT_EQ(options.join_weights.root_quadratic.weights,
            reconstruct::DefaultJoinWeights().root_quadratic.weights);
  auto bad = ParseAll({"--join-model", "tree"});
  ASSERT_TRUE(bad.ok());
  const absl::Status status = ReadConnectFlags(*bad, &options);
  EXPECT_NE(status.message().find("--join-model"), std::string::npos) << status;
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
      {{"--match-model", "cubic"}, "--match-model"},
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
  auto flags = ParseAll({"--sweep", "false", "--sweep-min-views", "2", "--sweep-max-step", "3",
                         "--sweep-accept-px", "1.25", "--sweep-max-ambiguous", "0.3",
                         "--sweep-min-stretch-share", "0.4", "--sweep-unique-steps", "2",
                         "--sweep-check", "false", "--sweep-check-spread", "0.35",
                         "--sweep-check-excess", "0.6", "--sweep-check-foreground", "0.7"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadSweepFlags(*flags, &options).ok());
  EXPECT_FALSE(options.enabled);
  EXPECT_EQ(options.min_views, 2);
  EXPECT_EQ(options.max_step, 3);
  EXPECT_DOUBLE_EQ(options.accept_px, 1.25);
  EXPECT_DOUBLE_EQ(options.max_ambiguous_share, 0.3);
  EXPECT_DOUBLE_EQ(options.min_stretch_accepted_share, 0.4);
  EXPECT_EQ(options.unique_exclusion_steps, 2);
  EXPECT_FALSE(options.check);
  EXPECT_DOUBLE_EQ(options.check_max_width_log_spread, 0.35);
  EXPECT_DOUBLE_EQ(options.check_max_width_log_excess, 0.6);
  EXPECT_DOUBLE_EQ(options.check_min_foreground, 0.7);
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
      {{"--sweep-check", "2"}, "--sweep-check"},
      {{"--sweep-check-spread", "-1"}, "--sweep-check-spread"},
      {{"--sweep-check-excess", "-0.1"}, "--sweep-check-excess"},
      {{"--sweep-check-foreground", "-0.5"}, "--sweep-check-foreground"},
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

TEST(ReconstructFlags, HeadFlagsSetTheHeadOptionsAndDefaultsStay) {
  auto none = ParseAll({});
  ASSERT_TRUE(none.ok());
  reconstruct::HeadOptions options;
  ASSERT_TRUE(ReadHeadFlags(*none, &options).ok());
  const reconstruct::HeadOptions defaults;
  EXPECT_EQ(options.peel_canes, defaults.peel_canes);
  EXPECT_EQ(options.min_cell_m, defaults.min_cell_m);
  EXPECT_EQ(options.head_depth_factor, defaults.head_depth_factor);
  EXPECT_EQ(options.leaf_radius_fraction, defaults.leaf_radius_fraction);
  EXPECT_EQ(options.head_centre_on_trunk, defaults.head_centre_on_trunk);
  EXPECT_EQ(options.leaf_wood_radius_px, defaults.leaf_wood_radius_px);
  EXPECT_EQ(options.foreground_reach_px, defaults.foreground_reach_px);
  EXPECT_EQ(options.foreground_reach_max_views, defaults.foreground_reach_max_views);
  auto flags = ParseAll({"--head-peel", "--head-min-cell", "0.005", "--head-depth-factor=0.6",
                         "--head-leaf-fraction", "0.25", "--head-centre-on-trunk",
                         "--head-leaf-wood-px", "5", "--head-fg-reach-px", "8",
                         "--head-fg-reach-views", "1"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadHeadFlags(*flags, &options).ok());
  EXPECT_TRUE(options.peel_canes);
  EXPECT_DOUBLE_EQ(options.min_cell_m, 0.005);
  EXPECT_DOUBLE_EQ(options.head_depth_factor, 0.6);
  EXPECT_DOUBLE_EQ(options.leaf_radius_fraction, 0.25);
  EXPECT_TRUE(options.head_centre_on_trunk);
  EXPECT_DOUBLE_EQ(options.leaf_wood_radius_px, 5.0);
  EXPECT_EQ(options.foreground_reach_px, 8);
  EXPECT_EQ(options.foreground_reach_max_views, 1);
  EXPECT_TRUE(flags->Finish().ok());  // every flag was read
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadHeadValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--head-min-cell", "0"}, "--head-min-cell"},
      {{"--head-min-cell", "0.05"}, "--head-min-cell"},  // above coarse_cell_m
      {{"--head-depth-factor", "0"}, "--head-depth-factor"},
      {{"--head-depth-factor", "inf"}, "--head-depth-factor"},
      {{"--head-leaf-fraction", "-0.1"}, "--head-leaf-fraction"},
      {{"--head-leaf-fraction", "1.5"}, "--head-leaf-fraction"},
      {{"--head-leaf-fraction", "nan"}, "--head-leaf-fraction"},
      {{"--head-centre-on-trunk", "maybe"}, "--head-centre-on-trunk"},
      {{"--head-leaf-wood-px", "-1"}, "--head-leaf-wood-px"},
      {{"--head-leaf-wood-px", "inf"}, "--head-leaf-wood-px"},
      {{"--head-fg-reach-px", "-1"}, "--head-fg-reach-px"},
      {{"--head-fg-reach-px", "101"}, "--head-fg-reach-px"},
      {{"--head-fg-reach-px", "2.5"}, "--head-fg-reach-px"},
      {{"--head-fg-reach-views", "0"}, "--head-fg-reach-views"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::HeadOptions options;
    const absl::Status status = ReadHeadFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
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
  EXPECT_EQ(options.curve_gain, defaults.curve_gain);
  EXPECT_EQ(options.max_skeleton_px, defaults.max_skeleton_px);

  auto flags = ParseAll({"--head-bases=false", "--head-bases-reach", "0.2",
                         "--head-bases-thick-views=3", "--head-bases-inside", "0.01",
                         "--head-bases-curve", "0.75", "--head-bases-skeleton=1.5"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadHeadBasesFlags(*flags, &options).ok());
  EXPECT_FALSE(options.enabled);  // on by default
  EXPECT_DOUBLE_EQ(options.reach_m, 0.2);
  EXPECT_EQ(options.min_thick_views, 3);
  EXPECT_DOUBLE_EQ(options.max_inside_m, 0.01);
  EXPECT_DOUBLE_EQ(options.curve_gain, 0.75);
  EXPECT_DOUBLE_EQ(options.max_skeleton_px, 1.5);
  EXPECT_TRUE(flags->Finish().ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadHeadBasesValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--head-bases-reach", "0"}, "--head-bases-reach"},
      {{"--head-bases-reach", "nan"}, "--head-bases-reach"},
      {{"--head-bases-thick-views", "-1"}, "--head-bases-thick-views"},
      {{"--head-bases-inside", "-0.01"}, "--head-bases-inside"},
      {{"--head-bases-curve", "-0.5"}, "--head-bases-curve"},
      {{"--head-bases-curve", "nan"}, "--head-bases-curve"},
      {{"--head-bases-skeleton", "-1"}, "--head-bases-skeleton"},
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

TEST(ReconstructFlags, ExtendFlagsKeepTheDefaultsOrSetTheRules) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::ExtendOptions options;
  ASSERT_TRUE(ReadExtendFlags(*absent, &options).ok());
  const reconstruct::ExtendOptions defaults;
  EXPECT_EQ(options.max_tip_row_distance_m, defaults.max_tip_row_distance_m);
  EXPECT_EQ(options.max_tip_out_of_plane, defaults.max_tip_out_of_plane);
  EXPECT_EQ(options.max_support_px, defaults.max_support_px);
  EXPECT_EQ(options.max_depth_sd_m, defaults.max_depth_sd_m);

  auto flags = ParseAll({"--extend-row", "0.95", "--extend-across=0.4", "--extend-support", "0",
                         "--extend-depth-sd", "0.008"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadExtendFlags(*flags, &options).ok());
  EXPECT_DOUBLE_EQ(options.max_tip_row_distance_m, 0.95);
  EXPECT_DOUBLE_EQ(options.max_tip_out_of_plane, 0.4);
  EXPECT_DOUBLE_EQ(options.max_support_px, 0.0);  // the rule off
  EXPECT_DOUBLE_EQ(options.max_depth_sd_m, 0.008);
  EXPECT_TRUE(flags->Finish().ok());  // every flag was read
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadExtendValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--extend-row", "-0.1"}, "--extend-row"},
      {{"--extend-row", "inf"}, "--extend-row"},
      {{"--extend-across", "-1"}, "--extend-across"},
      {{"--extend-across", "nan"}, "--extend-across"},
      {{"--extend-support", "-0.5"}, "--extend-support"},
      {{"--extend-depth-sd", "0"}, "--extend-depth-sd"},
      {{"--extend-depth-sd", "x"}, "--extend-depth-sd"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::ExtendOptions options;
    const absl::Status status = ReadExtendFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
}

TEST(ReconstructFlags, StrandHalfFlagsKeepTheDefaultsOrSetTheOptions) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::StrandHalfOptions options;
  ASSERT_TRUE(ReadStrandHalfFlags(*absent, &options).ok());
  const reconstruct::StrandHalfOptions defaults;
  EXPECT_EQ(options.enabled, defaults.enabled);
  EXPECT_EQ(options.min_seam_dip, defaults.min_seam_dip);

  auto flags = ParseAll({"--strand-halves", "true", "--strand-halves-dip=4.5"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadStrandHalfFlags(*flags, &options).ok());
  EXPECT_TRUE(options.enabled);
  EXPECT_DOUBLE_EQ(options.min_seam_dip, 4.5);
  EXPECT_TRUE(flags->Finish().ok());  // every flag was read
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadStrandHalfValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--strand-halves-dip", "-1"}, "--strand-halves-dip"},
      {{"--strand-halves-dip", "nan"}, "--strand-halves-dip"},
      {{"--strand-halves", "maybe"}, "--strand-halves"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::StrandHalfOptions options;
    const absl::Status status = ReadStrandHalfFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
}

TEST(ReconstructFlags, ConnectFlagsKeepTheDefaultsOrSetTheKeepRules) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::ConnectOptions options;
  ASSERT_TRUE(ReadConnectFlags(*absent, &options).ok());
  const reconstruct::ConnectOptions defaults;
  EXPECT_EQ(options.min_join_probability, defaults.min_join_probability);
  EXPECT_EQ(options.rescue_min_probability, defaults.rescue_min_probability);
  EXPECT_EQ(options.rescue_min_taper, defaults.rescue_min_taper);
  EXPECT_EQ(options.keep_within_m, defaults.keep_within_m);
  EXPECT_EQ(options.keep_min_length_m, defaults.keep_min_length_m);
  EXPECT_EQ(options.keep_taper_ratio, defaults.keep_taper_ratio);
  EXPECT_EQ(options.drop_thickening_ratio, defaults.drop_thickening_ratio);

  auto flags = ParseAll({"--min-join-probability", "0.1", "--rescue-min-probability=0.2",
                         "--rescue-min-taper", "0", "--keep-within", "0.6",
                         "--keep-min-length", "0.1", "--keep-taper", "1.15",
                         "--drop-thickening", "0"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadConnectFlags(*flags, &options).ok());
  EXPECT_DOUBLE_EQ(options.min_join_probability, 0.1);
  EXPECT_DOUBLE_EQ(options.rescue_min_probability, 0.2);
  EXPECT_DOUBLE_EQ(options.rescue_min_taper, 0.0);
  EXPECT_DOUBLE_EQ(options.keep_within_m, 0.6);
  EXPECT_DOUBLE_EQ(options.keep_min_length_m, 0.1);
  EXPECT_DOUBLE_EQ(options.keep_taper_ratio, 1.15);
  EXPECT_DOUBLE_EQ(options.drop_thickening_ratio, 0.0);  // the rule off
  EXPECT_TRUE(flags->Finish().ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadConnectValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--min-join-probability", "0"}, "--min-join-probability"},
      {{"--min-join-probability", "1"}, "--min-join-probability"},
      {{"--rescue-min-probability", "1"}, "--rescue-min-probability"},
      {{"--rescue-min-probability", "-0.1"}, "--rescue-min-probability"},
      // Below "none"'s probability (0.12 by default) but not 0.
      {{"--rescue-min-probability", "0.05"}, "--rescue-min-probability"},
      {{"--min-join-probability", "0.2", "--rescue-min-probability", "0.15"},
       "--rescue-min-probability"},
      {{"--rescue-min-taper", "-1"}, "--rescue-min-taper"},
      {{"--keep-within", "-0.1"}, "--keep-within"},
      {{"--keep-within", "inf"}, "--keep-within"},
      {{"--keep-min-length", "-0.01"}, "--keep-min-length"},
      {{"--keep-taper", "1"}, "--keep-taper"},
      {{"--keep-taper", "0.5"}, "--keep-taper"},
      {{"--keep-taper", "inf"}, "--keep-taper"},
      {{"--drop-thickening", "0.9"}, "--drop-thickening"},
      {{"--drop-thickening", "nan"}, "--drop-thickening"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::ConnectOptions options;
    const absl::Status status = ReadConnectFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
  // The rescue's threshold may be 0 (off) whatever "none"'s probability.
  auto flags = ParseAll({"--min-join-probability", "0.2", "--rescue-min-probability", "0"});
  ASSERT_TRUE(flags.ok());
  reconstruct::ConnectOptions options;
  EXPECT_TRUE(ReadConnectFlags(*flags, &options).ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, HeadExitFlagsKeepTheDefaultsOrSetTheOptions) {
  auto absent = ParseAll({});
  ASSERT_TRUE(absent.ok());
  reconstruct::ConnectOptions options;
  ASSERT_TRUE(ReadHeadExitFlags(*absent, &options).ok());
  const reconstruct::ConnectOptions defaults;
  EXPECT_EQ(options.head_exit_reach_m, defaults.head_exit_reach_m);
  EXPECT_EQ(options.head_exit_min_cos, defaults.head_exit_min_cos);
  EXPECT_EQ(options.head_exit_min_radius_m, defaults.head_exit_min_radius_m);
  EXPECT_EQ(options.head_exit_left_out, defaults.head_exit_left_out);

  auto flags = ParseAll({"--head-exit-reach", "0.35", "--head-exit-cos=0.9",
                         "--head-exit-min-radius", "0.004", "--head-exit-left-out", "true"});
  ASSERT_TRUE(flags.ok());
  ASSERT_TRUE(ReadHeadExitFlags(*flags, &options).ok());
  EXPECT_DOUBLE_EQ(options.head_exit_reach_m, 0.35);  // 0.3 by default
  EXPECT_DOUBLE_EQ(options.head_exit_min_cos, 0.9);
  EXPECT_DOUBLE_EQ(options.head_exit_min_radius_m, 0.004);  // 0.003 by default
  EXPECT_TRUE(options.head_exit_left_out);
  EXPECT_TRUE(flags->Finish().ok());
  EXPECT_TRUE(options.Validate().ok());
}

TEST(ReconstructFlags, RejectsBadHeadExitValuesNamingTheFlag) {
  const std::vector<std::pair<std::vector<const char*>, std::string>> cases = {
      {{"--head-exit-reach", "-0.1"}, "--head-exit-reach"},
      {{"--head-exit-reach", "inf"}, "--head-exit-reach"},
      {{"--head-exit-reach", "nan"}, "--head-exit-reach"},
      {{"--head-exit-cos", "1.5"}, "--head-exit-cos"},
      {{"--head-exit-cos", "-2"}, "--head-exit-cos"},
      {{"--head-exit-cos", "nan"}, "--head-exit-cos"},
      {{"--head-exit-min-radius", "-0.001"}, "--head-exit-min-radius"},
      {{"--head-exit-min-radius", "inf"}, "--head-exit-min-radius"},
      {{"--head-exit-left-out", "maybe"}, "--head-exit-left-out"},
  };
  for (const auto& [args, name] : cases) {
    auto flags = ParseAll(args);
    ASSERT_TRUE(flags.ok());
    reconstruct::ConnectOptions options;
    const absl::Status status = ReadHeadExitFlags(*flags, &options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << args[0] << " " << args[1];
    EXPECT_NE(status.message().find(name), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace vb::app
