// SPDX-License-Identifier: Apache-2.0
#include "core/json_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"

namespace vb {

absl::StatusOr<nlohmann::json> ReadJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open for reading"));
  std::stringstream buffer;
  buffer << in.rdbuf();
  nlohmann::json json = nlohmann::json::parse(buffer.str(), nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) {
    // Re-parse with exceptions only to get the position for the message.
    try {
      (void)nlohmann::json::parse(buffer.str());
    } catch (const nlohmann::json::parse_error& e) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": not valid JSON: ", e.what()));
    }
    return absl::InvalidArgumentError(absl::StrCat(path, ": not valid JSON"));
  }
  return json;
}

absl::Status WriteJsonFile(const std::string& path, const nlohmann::json& json) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) return absl::InternalError(absl::StrCat(tmp, ": cannot open for writing"));
    out << json.dump(1) << "\n";
    if (!out) return absl::InternalError(absl::StrCat(tmp, ": write failed"));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    return absl::InternalError(absl::StrCat(path, ": cannot rename from ", tmp));
  }
  return absl::OkStatus();
}

absl::StatusOr<const nlohmann::json*> Field(const nlohmann::json& object, const std::string& field) {
  if (!object.is_object()) {
    return absl::InvalidArgumentError(absl::StrCat("expected an object holding '", field, "'"));
  }
  auto it = object.find(field);
  if (it == object.end()) return absl::InvalidArgumentError(absl::StrCat(field, ": missing"));
  return &*it;
}

absl::StatusOr<double> NumberField(const nlohmann::json& object, const std::string& field) {
  auto f = Field(object, field);
  if (!f.ok()) return f.status();
  if (!(*f)->is_number()) return absl::InvalidArgumentError(absl::StrCat(field, ": not a number"));
  const double v = (*f)->get<double>();
  if (!std::isfinite(v)) return absl::InvalidArgumentError(absl::StrCat(field, ": not finite"));
  return v;
}

absl::StatusOr<std::string> StringField(const nlohmann::json& object, const std::string& field) {
  auto f = Field(object, field);
  if (!f.ok()) return f.status();
  if (!(*f)->is_string()) return absl::InvalidArgumentError(absl::StrCat(field, ": not a string"));
  return (*f)->get<std::string>();
}

absl::StatusOr<int64_t> IntField(const nlohmann::json& object, const std::string& field) {
  auto f = Field(object, field);
  if (!f.ok()) return f.status();
  if (!(*f)->is_number_integer()) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": not an integer"));
  }
  return (*f)->get<int64_t>();
}

absl::StatusOr<Eigen::Vector3d> ParseVec3(const nlohmann::json& value, const std::string& what) {
  if (!value.is_array() || value.size() != 3) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": expected [x, y, z]"));
  }
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!value[i].is_number()) {
      return absl::InvalidArgumentError(absl::StrCat(what, "[", i, "]: not a number"));
    }
    v[i] = value[i].get<double>();
    if (!std::isfinite(v[i])) {
      return absl::InvalidArgumentError(absl::StrCat(what, "[", i, "]: not finite"));
    }
  }
  return v;
}

nlohmann::json Vec3ToJson(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

absl::Status CheckFormat(const nlohmann::json& object, const std::string& expected) {
  auto format = StringField(object, "format");
  if (!format.ok()) return format.status();
  if (*format != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat("format: expected '", expected, "', found '", *format, "'"));
  }
  return absl::OkStatus();
}

}  // namespace vb
