// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/labelled_examples.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::decide {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

namespace fs = std::filesystem;

class LabelledExamplesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::path(::testing::TempDir()) /
            (std::string("vb_labels_") +
             ::testing::UnitTest::GetInstance()->current_test_info()->name() +
             "_" + std::to_string(getpid())))
               .string();
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static LabelledExample Example(const std::string& name) {
    absl::StatusOr<sim::Scene> scene = sim::GenerateScene(1100, 3);
    EXPECT_TRUE(scene.ok()) << scene.status();
    LabelledExample e;
    e.name = name;
    e.model = scene->vine;
    e.plan.keep = {CaneId(2), CaneId(3)};
    e.plan.spurs = {CaneId(4)};
    e.plan.policy.spurs = 1;
    return e;
  }

  std::string dir_;
};

TEST_F(LabelledExamplesTest, WritesListsAndReadsBack) {
  ASSERT_TRUE(WriteLabelledExample(dir_, Example("b-2")).ok());
  ASSERT_TRUE(WriteLabelledExample(dir_, Example("a_1")).ok());
  absl::StatusOr<std::vector<std::string>> names = ListLabelledExamples(dir_);
  ASSERT_TRUE(names.ok()) << names.status();
  EXPECT_THAT(*names, ElementsAre("a_1", "b-2"));
  absl::StatusOr<LabelledExample> read = ReadLabelledExample(dir_, "b-2");
  ASSERT_TRUE(read.ok()) << read.status();
  const LabelledExample expected = Example("b-2");
  EXPECT_EQ(read->plan.keep, expected.plan.keep);
  EXPECT_EQ(read->plan.spurs, expected.plan.spurs);
  EXPECT_EQ(read->plan.policy.spurs, 1);
  EXPECT_EQ(read->model.canes.size(), expected.model.canes.size());
}

TEST_F(LabelledExamplesTest, ListRejectsAModelWithoutAPlan) {
  ASSERT_TRUE(WriteLabelledExample(dir_, Example("x")).ok());
  fs::remove(fs::path(dir_) / "x.plan.json");
  absl::StatusOr<std::vector<std::string>> names = ListLabelledExamples(dir_);
  ASSERT_FALSE(names.ok());
  EXPECT_THAT(names.status().message(), HasSubstr("x.model.json"));
}

TEST_F(LabelledExamplesTest, ListOfAMissingDirectoryFails) {
  EXPECT_EQ(ListLabelledExamples(dir_ + "/nope").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(LabelledExamplesTest, RejectsBadNamesAndUnknownCanes) {
  EXPECT_FALSE(WriteLabelledExample(dir_, Example("../escape")).ok());
  EXPECT_FALSE(WriteLabelledExample(dir_, Example(".hidden")).ok());
  EXPECT_FALSE(WriteLabelledExample(dir_, Example("")).ok());
  LabelledExample unknown = Example("unknown");
  unknown.plan.keep = {CaneId(999)};
  absl::Status s = WriteLabelledExample(dir_, unknown);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("unknown"));
  EXPECT_THAT(s.message(), HasSubstr("999"));
}

TEST_F(LabelledExamplesTest, ReadRejectsAPlanNamingCanesTheModelLacks) {
  ASSERT_TRUE(WriteLabelledExample(dir_, Example("y")).ok());
  {
    std::ofstream plan(fs::path(dir_) / "y.plan.json");
    plan << R"({"format":"vinebot.cut_plan.v1","policy":{},"keep":[77],"spurs":[],"cuts":[]})";
  }
  absl::StatusOr<LabelledExample> read = ReadLabelledExample(dir_, "y");
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(read.status().message(), HasSubstr("77"));
}

}  // namespace
}  // namespace vb::decide
