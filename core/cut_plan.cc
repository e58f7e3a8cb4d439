// SPDX-License-Identifier: Apache-2.0
#include "core/cut_plan.h"

#include <cmath>
#include <set>
#include <unordered_set>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb {

using nlohmann::json;

std::string_view CutReasonName(CutReason reason) {
  switch (reason) {
    case CutReason::kRemove:
      return "remove";
    case CutReason::kSpur:
      return "spur";
    case CutReason::kShorten:
      return "shorten";
  }
  return "remove";
}

absl::StatusOr<CutReason> ParseCutReason(std::string_view name) {
  if (name == "remove") return CutReason::kRemove;
  if (name == "spur") return CutReason::kSpur;
  if (name == "shorten") return CutReason::kShorten;
  return absl::InvalidArgumentError(absl::StrCat(
      "reason: unknown cut reason '", std::string(name), "' (expected remove, spur or shorten)"));
}

namespace {

// A JSON round trip of a unit vector keeps it unit to ~1e-16; 1e-6 admits hand-written files
// with six decimals.
constexpr double kUnitTolerance = 1e-6;

absl::Status CheckUniqueIds(const std::vector<CaneId>& ids, const char* field) {
  std::unordered_set<int64_t> seen;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (!seen.insert(ids[i].value).second) {
      return absl::InvalidArgumentError(
          absl::StrCat(field, "[", i, "]: cane ", ids[i].value, " is listed twice"));
    }
  }
  return absl::OkStatus();
}

std::string CutName(size_t i, const Cut& cut) {
  return absl::StrCat("cuts[", i, "] (id ", cut.id.value, ")");
}

}  // namespace

absl::Status CutPlan::Validate() const {
  VB_RETURN_IF_ERROR(policy.Validate());
  VB_RETURN_IF_ERROR(CheckUniqueIds(keep, "keep"));
  VB_RETURN_IF_ERROR(CheckUniqueIds(spurs, "spurs"));
  const std::set<CaneId> kept(keep.begin(), keep.end());
  for (size_t i = 0; i < spurs.size(); ++i) {
    if (kept.contains(spurs[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("spurs[", i, "]: cane ", spurs[i].value, " is also kept"));
    }
  }
  std::unordered_set<int64_t> cut_ids;
  for (size_t i = 0; i < cuts.size(); ++i) {
    const Cut& cut = cuts[i];
    const std::string what = CutName(i, cut);
    if (cut.id.value <= 0) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".id: must be positive"));
    }
    if (!cut_ids.insert(cut.id.value).second) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".id: duplicate cut id"));
    }
    if (!cut.point.allFinite()) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".point: not finite"));
    }
    const double norm = cut.direction.norm();
    if (!cut.direction.allFinite() || std::abs(norm - 1.0) > kUnitTolerance) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ".direction: not a unit vector (norm ", norm, ")"));
    }
    if (!std::isfinite(cut.diameter_m) || cut.diameter_m <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat(what, ".diameter_m: must be finite and > 0, is ", cut.diameter_m));
    }
  }
  return absl::OkStatus();
}

absl::Status CutPlan::ValidateAgainst(const VineModel& model) const {
  VB_RETURN_IF_ERROR(Validate());
  std::unordered_set<int64_t> ids;
  for (const Cane& cane : model.canes) ids.insert(cane.id.value);
  auto check = [&ids](const std::vector<CaneId>& list, const char* field) -> absl::Status {
    for (size_t i = 0; i < list.size(); ++i) {
      if (!ids.contains(list[i].value)) {
        return absl::InvalidArgumentError(
            absl::StrCat(field, "[", i, "]: cane ", list[i].value, " is not in the model"));
      }
    }
    return absl::OkStatus();
  };
  VB_RETURN_IF_ERROR(check(keep, "keep"));
  VB_RETURN_IF_ERROR(check(spurs, "spurs"));
  for (size_t i = 0; i < cuts.size(); ++i) {
    if (!ids.contains(cuts[i].cane_id.value)) {
      return absl::InvalidArgumentError(absl::StrCat(CutName(i, cuts[i]), ".cane_id: cane ",
                                                     cuts[i].cane_id.value,
                                                     " is not in the model"));
    }
  }
  return absl::OkStatus();
}

json CutPlanToJson(const CutPlan& plan) {
  auto ids = [](const std::vector<CaneId>& list) {
    json out = json::array();
    for (CaneId id : list) out.push_back(id.value);
    return out;
  };
  json cuts = json::array();
  for (const Cut& cut : plan.cuts) {
    cuts.push_back({{"id", cut.id.value},
                    {"cane_id", cut.cane_id.value},
                    {"point", Vec3ToJson(cut.point)},
                    {"direction", Vec3ToJson(cut.direction)},
                    {"diameter_m", cut.diameter_m},
                    {"reason", std::string(CutReasonName(cut.reason))}});
  }
  return {{"format", kCutPlanFormat},
          {"policy", PruningPolicyToJson(plan.policy)},
          {"keep", ids(plan.keep)},
          {"spurs", ids(plan.spurs)},
          {"cuts", cuts}};
}

namespace {

absl::Status Prefix(const std::string& what, const absl::Status& s) {
  return absl::Status(s.code(), absl::StrCat(what, ".", s.message()));
}

// Rejects keys of `object` outside `allowed`, naming the first one.
absl::Status CheckKnownFields(const json& object, const std::set<std::string>& allowed,
                              const std::string& what) {
  for (const auto& [key, value] : object.items()) {
    if (!allowed.contains(key)) {
      return absl::InvalidArgumentError(absl::StrCat(what, key, ": unknown field"));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<CaneId>> ParseIds(const json& j, const std::string& field) {
  VB_ASSIGN_OR_RETURN(const json* list, Field(j, field));
  if (!list->is_array()) return absl::InvalidArgumentError(field + ": not an array");
  std::vector<CaneId> ids;
  for (size_t i = 0; i < list->size(); ++i) {
    if (!(*list)[i].is_number_integer()) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", i, "]: not an integer"));
    }
    ids.push_back(CaneId((*list)[i].get<int64_t>()));
  }
  return ids;
}

absl::StatusOr<Cut> ParseCut(const json& j, const std::string& what) {
  if (!j.is_object()) return absl::InvalidArgumentError(what + ": not an object");
  VB_RETURN_IF_ERROR(CheckKnownFields(
      j, {"id", "cane_id", "point", "direction", "diameter_m", "reason"}, what + "."));
  Cut cut;
  auto id = IntField(j, "id");
  if (!id.ok()) return Prefix(what, id.status());
  cut.id = CutId(*id);
  auto cane_id = IntField(j, "cane_id");
  if (!cane_id.ok()) return Prefix(what, cane_id.status());
  cut.cane_id = CaneId(*cane_id);
  for (const char* field : {"point", "direction"}) {
    auto value = Field(j, field);
    if (!value.ok()) return Prefix(what, value.status());
    VB_ASSIGN_OR_RETURN(Eigen::Vector3d v, ParseVec3(**value, absl::StrCat(what, ".", field)));
    (std::string_view(field) == "point" ? cut.point : cut.direction) = v;
  }
  auto diameter = NumberField(j, "diameter_m");
  if (!diameter.ok()) return Prefix(what, diameter.status());
  cut.diameter_m = *diameter;
  auto reason_name = StringField(j, "reason");
  if (!reason_name.ok()) return Prefix(what, reason_name.status());
  auto reason = ParseCutReason(*reason_name);
  if (!reason.ok()) return Prefix(what, reason.status());
  cut.reason = *reason;
  return cut;
}

}  // namespace

absl::StatusOr<CutPlan> CutPlanFromJson(const json& j) {
  VB_RETURN_IF_ERROR(CheckFormat(j, kCutPlanFormat));
  VB_RETURN_IF_ERROR(
      CheckKnownFields(j, {"format", "policy", "keep", "spurs", "cuts"}, /*what=*/""));
  CutPlan plan;
  VB_ASSIGN_OR_RETURN(const json* policy, Field(j, "policy"));
  VB_ASSIGN_OR_RETURN(plan.policy, PruningPolicyFromJson(*policy));
  VB_ASSIGN_OR_RETURN(plan.keep, ParseIds(j, "keep"));
  VB_ASSIGN_OR_RETURN(plan.spurs, ParseIds(j, "spurs"));
  VB_ASSIGN_OR_RETURN(const json* cuts, Field(j, "cuts"));
  if (!cuts->is_array()) return absl::InvalidArgumentError("cuts: not an array");
  for (size_t i = 0; i < cuts->size(); ++i) {
    VB_ASSIGN_OR_RETURN(Cut cut, ParseCut((*cuts)[i], absl::StrCat("cuts[", i, "]")));
    plan.cuts.push_back(cut);
  }
  VB_RETURN_IF_ERROR(plan.Validate());
  return plan;
}

absl::Status WriteCutPlan(const std::string& path, const CutPlan& plan) {
  return WriteJsonFile(path, CutPlanToJson(plan));
}

absl::StatusOr<CutPlan> ReadCutPlan(const std::string& path) {
  return ReadJsonFileAs<CutPlan>(path, CutPlanFromJson);
}

}  // namespace vb
