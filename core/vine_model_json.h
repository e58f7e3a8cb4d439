// SPDX-License-Identifier: Apache-2.0
// JSON I/O of the vine model, format "vinebot.vine_model.v1" (ARCHITECTURE.md "Formats"), with
// one optional addition (since 2026-11-22; docs/reconstruction.md step 9): a top-level
// "obstacles": [{"points": [[x, y, z], ...], "radii": [r, ...]}, ...] of seen wood the model's
// canes leave out (VineModel::obstacles; at least two points, one radius per point). Written only
// when there are some, so files without obstacles are byte for byte as before and older files
// read unchanged. A reader from before it ignores the field (its planner would not avoid them).
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
