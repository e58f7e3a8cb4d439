// SPDX-License-Identifier: Apache-2.0
// Small helpers for reading and writing the JSON formats of ARCHITECTURE.md with errors that name
// the file and the field. nlohmann::json exceptions never leave these functions.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "Eigen/Core"
#include "nlohmann/json.hpp"

namespace vb {

// Parses a file. NOT_FOUND if it cannot be opened; INVALID_ARGUMENT (naming the file and the
// byte offset) if it is not JSON.
absl::StatusOr<nlohmann::json> ReadJsonFile(const std::string& path);
// Writes pretty-printed JSON atomically (temp file + rename). INTERNAL on I/O failure.
absl::Status WriteJsonFile(const std::string& path, const nlohmann::json& json);

// Reads `path` and parses it with `parse`; parse errors are prefixed with the path.
template <typename T>
absl::StatusOr<T> ReadJsonFileAs(const std::string& path,
                                 absl::StatusOr<T> (*parse)(const nlohmann::json&)) {
  absl::StatusOr<nlohmann::json> json = ReadJsonFile(path);
  if (!json.ok()) return json.status();
  absl::StatusOr<T> value = parse(*json);
  if (!value.ok()) {
    return absl::Status(value.status().code(),
                        path + ": " + std::string(value.status().message()));
  }
  return value;
}

// Field accessors: INVALID_ARGUMENT naming `field` when missing or of the wrong type.
absl::StatusOr<const nlohmann::json*> Field(const nlohmann::json& object, const std::string& field);
absl::StatusOr<double> NumberField(const nlohmann::json& object, const std::string& field);
absl::StatusOr<std::string> StringField(const nlohmann::json& object, const std::string& field);
absl::StatusOr<int64_t> IntField(const nlohmann::json& object, const std::string& field);
// Converts [x, y, z]; `what` names the value in errors. Rejects non-finite entries.
absl::StatusOr<Eigen::Vector3d> ParseVec3(const nlohmann::json& value, const std::string& what);

nlohmann::json Vec3ToJson(const Eigen::Vector3d& v);

// Checks object["format"] == expected; INVALID_ARGUMENT otherwise.
absl::Status CheckFormat(const nlohmann::json& object, const std::string& expected);

}  // namespace vb
