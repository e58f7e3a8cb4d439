// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/labelled_examples.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <string_view>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "core/vine_model_json.h"

namespace vb::decide {
namespace {

namespace fs = std::filesystem;

std::string PathOf(const std::string& dir, const std::string& name, const char* suffix) {
  return (fs::path(dir) / (name + suffix)).string();
}

bool EndsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

}  // namespace

absl::Status ValidateExampleName(const std::string& name) {
  const bool chars_ok = std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           c == '.' || c == '_' || c == '-';
  });
  if (name.empty() || name.size() > 128 || name.front() == '.' || !chars_ok) {
    return absl::InvalidArgumentError(absl::StrCat(
        "example name '", name, "': must be 1-128 characters of [A-Za-z0-9._-], not starting with '.'"));
  }
  return absl::OkStatus();
}

absl::Status WriteLabelledExample(const std::string& dir, const LabelledExample& example) {
  VB_RETURN_IF_ERROR(ValidateExampleName(example.name));
  if (absl::Status s = example.plan.ValidateAgainst(example.model); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("example ", example.name, ": ", s.message()));
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return absl::InternalError(absl::StrCat(dir, ": cannot create: ", ec.message()));
  VB_RETURN_IF_ERROR(WriteVineModel(PathOf(dir, example.name, kLabelModelSuffix), example.model));
  return WriteCutPlan(PathOf(dir, example.name, kLabelPlanSuffix), example.plan);
}

absl::StatusOr<std::vector<std::string>> ListLabelledExamples(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    return absl::NotFoundError(absl::StrCat(dir, ": not a directory of labelled examples"));
  }
  std::set<std::string> models, plans;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string file = entry.path().filename().string();
    if (EndsWith(file, kLabelModelSuffix)) {
      models.insert(file.substr(0, file.size() - std::string_view(kLabelModelSuffix).size()));
    } else if (EndsWith(file, kLabelPlanSuffix)) {
      plans.insert(file.substr(0, file.size() - std::string_view(kLabelPlanSuffix).size()));
    }
  }
  if (ec) return absl::InternalError(absl::StrCat(dir, ": cannot list: ", ec.message()));
  for (const std::string& name : models) {
    if (!plans.contains(name)) {
      return absl::InvalidArgumentError(
          absl::StrCat(PathOf(dir, name, kLabelModelSuffix), ": has no ", name, kLabelPlanSuffix));
    }
  }
  for (const std::string& name : plans) {
    if (!models.contains(name)) {
      return absl::InvalidArgumentError(
          absl::StrCat(PathOf(dir, name, kLabelPlanSuffix), ": has no ", name, kLabelModelSuffix));
    }
  }
  return std::vector<std::string>(models.begin(), models.end());
}

absl::StatusOr<LabelledExample> ReadLabelledExample(const std::string& dir,
                                                    const std::string& name) {
  VB_RETURN_IF_ERROR(ValidateExampleName(name));
  LabelledExample example;
  example.name = name;
  VB_ASSIGN_OR_RETURN(example.model, ReadVineModel(PathOf(dir, name, kLabelModelSuffix)));
  VB_ASSIGN_OR_RETURN(example.plan, ReadCutPlan(PathOf(dir, name, kLabelPlanSuffix)));
  if (absl::Status s = example.plan.ValidateAgainst(example.model); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("example ", name, ": ", s.message()));
  }
  return example;
}

}  // namespace vb::decide
