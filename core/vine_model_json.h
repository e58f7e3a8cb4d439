// SPDX-License-Identifier: Apache-2.0
// JSON I/O of the vine model, format "vinebot.vine_model.v1" (ARCHITECTURE.md "Formats").
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "core/vine_model.h"
#include "nlohmann/json.hpp"

namespace vb {

inline constexpr char kVineModelFormat[] = "vinebot.vine_model.v1";

nlohmann::json VineModelToJson(const VineModel& model);
// Parses and validates (VineModel::Validate). INVALID_ARGUMENT naming the field on any problem.
absl::StatusOr<VineModel> VineModelFromJson(const nlohmann::json& json);

absl::Status WriteVineModel(const std::string& path, const VineModel& model);
// Errors are prefixed with the path.
absl::StatusOr<VineModel> ReadVineModel(const std::string& path);

}  // namespace vb
