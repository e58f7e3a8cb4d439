// SPDX-License-Identifier: Apache-2.0
#include "core/pruning_policy.h"

#include <cmath>
#include <functional>
#include <map>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb {

using nlohmann::json;

std::string_view PruningStyleName(PruningStyle style) {
  return style == PruningStyle::kSpur ? "spur" : "cane";
}

absl::StatusOr<PruningStyle> ParsePruningStyle(std::string_view name) {
  if (name == "cane") return PruningStyle::kCane;
  if (name == "spur") return PruningStyle::kSpur;
  return absl::InvalidArgumentError(absl::StrCat("policy.style: unknown style '", std::string(name),
                                                 "' (expected cane or spur)"));
}

namespace {

absl::Status OutOfRange(const std::string& field, double value, double lo, double hi) {
  return absl::InvalidArgumentError(
      absl::StrCat("policy.", field, ": ", value, " is outside [", lo, ", ", hi, "]"));
}

absl::Status CheckInt(const std::string& field, int value, int lo, int hi) {
  if (value < lo || value > hi) return OutOfRange(field, value, lo, hi);
  return absl::OkStatus();
}

// Closed range check that also rejects NaN and infinities.
absl::Status CheckReal(const std::string& field, double value, double lo, double hi) {
  if (!std::isfinite(value)) {
    return absl::InvalidArgumentError(absl::StrCat("policy.", field, ": not finite"));
  }
  if (value < lo || value > hi) return OutOfRange(field, value, lo, hi);
  return absl::OkStatus();
}

// Ranges are generous physical limits: they catch unit mistakes (mm for m) and typos, not taste.
constexpr double kMaxDiameterM = 0.05;
constexpr double kMaxLengthM = 5.0;
constexpr double kMaxWireZM = 3.0;

}  // namespace

absl::Status PruningPolicy::Validate() const {
  if (version != kVersion) {
    return absl::InvalidArgumentError(
        absl::StrCat("policy.version: ", version, " is not supported (expected ", kVersion, ")"));
  }
  if (style == PruningStyle::kCane) {
    VB_RETURN_IF_ERROR(CheckInt("canes_to_keep", canes_to_keep, 1, 6));
    VB_RETURN_IF_ERROR(CheckInt("spurs", spurs, 0, 6));
  } else {
    if (canes_to_keep != 0) {
      return absl::InvalidArgumentError(absl::StrCat(
          "policy.canes_to_keep: ", canes_to_keep, " but spur pruning keeps no canes (must be 0)"));
    }
    VB_RETURN_IF_ERROR(CheckInt("spurs", spurs, 1, 12));
  }
  VB_RETURN_IF_ERROR(CheckReal("spur_length_m", spur_length_m, 0.005, 1.0));
  VB_RETURN_IF_ERROR(CheckReal("cane_diameter_min_m", cane_diameter_min_m, 0.0, kMaxDiameterM));
  VB_RETURN_IF_ERROR(CheckReal("cane_diameter_max_m", cane_diameter_max_m, 0.0, kMaxDiameterM));
  if (cane_diameter_min_m > cane_diameter_max_m) {
    return absl::InvalidArgumentError(absl::StrCat(
        "policy.cane_diameter_min_m: ", cane_diameter_min_m,
        " is greater than policy.cane_diameter_max_m ", cane_diameter_max_m));
  }
  VB_RETURN_IF_ERROR(CheckReal("min_kept_length_m", min_kept_length_m, 0.0, kMaxLengthM));
  VB_RETURN_IF_ERROR(CheckReal("max_kept_length_m", max_kept_length_m, 0.01, kMaxLengthM));
  if (min_kept_length_m > max_kept_length_m) {
    return absl::InvalidArgumentError(absl::StrCat(
        "policy.min_kept_length_m: ", min_kept_length_m,
        " is greater than policy.max_kept_length_m ", max_kept_length_m));
  }
  VB_RETURN_IF_ERROR(CheckReal("cut_offset_m", cut_offset_m, 0.001, 0.2));
  if (fruiting_wire_z_m.has_value()) {
    VB_RETURN_IF_ERROR(CheckReal("fruiting_wire_z_m", *fruiting_wire_z_m, 0.05, kMaxWireZM));
  }
  for (size_t i = 0; i < foliage_wire_z_m.size(); ++i) {
    const std::string field = absl::StrCat("foliage_wire_z_m[", i, "]");
    VB_RETURN_IF_ERROR(CheckReal(field, foliage_wire_z_m[i], 0.05, kMaxWireZM));
    if (fruiting_wire_z_m.has_value() && foliage_wire_z_m[i] <= *fruiting_wire_z_m) {
      return absl::InvalidArgumentError(
          absl::StrCat("policy.", field, ": ", foliage_wire_z_m[i],
                       " is not above policy.fruiting_wire_z_m ", *fruiting_wire_z_m));
    }
  }
  return absl::OkStatus();
}

json PruningPolicyToJson(const PruningPolicy& policy) {
  return {{"version", policy.version},
          {"style", std::string(PruningStyleName(policy.style))},
          {"canes_to_keep", policy.canes_to_keep},
          {"spurs", policy.spurs},
          {"spur_length_m", policy.spur_length_m},
          {"cane_diameter_min_m", policy.cane_diameter_min_m},
          {"cane_diameter_max_m", policy.cane_diameter_max_m},
          {"min_kept_length_m", policy.min_kept_length_m},
          {"max_kept_length_m", policy.max_kept_length_m},
          {"cut_offset_m", policy.cut_offset_m},
          {"fruiting_wire_z_m",
           policy.fruiting_wire_z_m ? json(*policy.fruiting_wire_z_m) : json(nullptr)},
          {"foliage_wire_z_m", policy.foliage_wire_z_m}};
}

namespace {

absl::Status WrongType(const std::string& field, const char* expected) {
  return absl::InvalidArgumentError(absl::StrCat("policy.", field, ": not ", expected));
}

absl::StatusOr<int> ParseInt(const json& value, const std::string& field) {
  if (!value.is_number_integer()) return WrongType(field, "an integer");
  const int64_t v = value.get<int64_t>();
  // Values far outside any valid range are rejected before they could overflow an int.
  if (v < -1000000 || v > 1000000) return OutOfRange(field, static_cast<double>(v), -1e6, 1e6);
  return static_cast<int>(v);
}

absl::StatusOr<double> ParseReal(const json& value, const std::string& field) {
  if (!value.is_number()) return WrongType(field, "a number");
  return value.get<double>();
}

}  // namespace

absl::StatusOr<PruningPolicy> PruningPolicyFromJson(const json& j) {
  if (!j.is_object()) return absl::InvalidArgumentError("policy: not a JSON object");
  PruningPolicy policy;
  // One parser per field; a key not in this table is an error naming it.
  using Parser = std::function<absl::Status(const json&)>;
  auto real = [](const std::string& field, double* out) -> Parser {
    return [field, out](const json& v) -> absl::Status {
      VB_ASSIGN_OR_RETURN(*out, ParseReal(v, field));
      return absl::OkStatus();
    };
  };
  auto integer = [](const std::string& field, int* out) -> Parser {
    return [field, out](const json& v) -> absl::Status {
      VB_ASSIGN_OR_RETURN(*out, ParseInt(v, field));
      return absl::OkStatus();
    };
  };
  const std::map<std::string, Parser> parsers = {
      {"version", integer("version", &policy.version)},
      {"style",
       [&policy](const json& v) -> absl::Status {
         if (!v.is_string()) return WrongType("style", "a string");
         VB_ASSIGN_OR_RETURN(policy.style, ParsePruningStyle(v.get<std::string>()));
         return absl::OkStatus();
       }},
      {"canes_to_keep", integer("canes_to_keep", &policy.canes_to_keep)},
      {"spurs", integer("spurs", &policy.spurs)},
      {"spur_length_m", real("spur_length_m", &policy.spur_length_m)},
      {"cane_diameter_min_m", real("cane_diameter_min_m", &policy.cane_diameter_min_m)},
      {"cane_diameter_max_m", real("cane_diameter_max_m", &policy.cane_diameter_max_m)},
      {"min_kept_length_m", real("min_kept_length_m", &policy.min_kept_length_m)},
      {"max_kept_length_m", real("max_kept_length_m", &policy.max_kept_length_m)},
      {"cut_offset_m", real("cut_offset_m", &policy.cut_offset_m)},
      {"fruiting_wire_z_m",
       [&policy](const json& v) -> absl::Status {
         if (v.is_null()) {
           policy.fruiting_wire_z_m.reset();
           return absl::OkStatus();
         }
         VB_ASSIGN_OR_RETURN(policy.fruiting_wire_z_m, ParseReal(v, "fruiting_wire_z_m"));
         return absl::OkStatus();
       }},
      {"foliage_wire_z_m",
       [&policy](const json& v) -> absl::Status {
         if (!v.is_array()) return WrongType("foliage_wire_z_m", "an array");
         policy.foliage_wire_z_m.clear();
         for (size_t i = 0; i < v.size(); ++i) {
           VB_ASSIGN_OR_RETURN(double z, ParseReal(v[i], absl::StrCat("foliage_wire_z_m[", i, "]")));
           policy.foliage_wire_z_m.push_back(z);
         }
         return absl::OkStatus();
       }},
  };
  for (const auto& [key, value] : j.items()) {
    auto it = parsers.find(key);
    if (it == parsers.end()) {
      return absl::InvalidArgumentError(absl::StrCat("policy.", key, ": unknown field"));
    }
    VB_RETURN_IF_ERROR(it->second(value));
  }
  // Spur pruning keeps no canes: a spur-style file need not say canes_to_keep is 0.
  if (policy.style == PruningStyle::kSpur && !j.contains("canes_to_keep")) {
    policy.canes_to_keep = 0;
  }
  VB_RETURN_IF_ERROR(policy.Validate());
  return policy;
}

absl::StatusOr<PruningPolicy> ReadPruningPolicy(const std::string& path) {
  VB_ASSIGN_OR_RETURN(json j, ReadJsonFile(path));
  auto policy = PruningPolicyFromJson(j);
  if (!policy.ok()) {
    return absl::Status(policy.status().code(), absl::StrCat(path, ": ", policy.status().message()));
  }
  return policy;
}

}  // namespace vb
