// SPDX-License-Identifier: Apache-2.0
#include "core/trajectory.h"

#include <cmath>
#include <limits>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb {

using nlohmann::json;

std::string_view SegmentKindName(SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kTransit:
      return "transit";
    case SegmentKind::kCut:
      return "cut";
  }
  return "transit";
}

namespace {

// A rotation written with 15+ significant digits (as nlohmann does) is orthonormal to ~1e-15;
// 1e-6 also admits poses typed by hand with six decimals.
constexpr double kOrthonormalTolerance = 1e-6;

absl::Status CheckPose(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().allFinite()) return absl::InvalidArgumentError(what + ": not finite");
  const Eigen::Matrix3d r = pose.linear();
  const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).norm();
  if (error > kOrthonormalTolerance || r.determinant() < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": rotation is not orthonormal (error ", error, ")"));
  }
  return absl::OkStatus();
}

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

absl::StatusOr<const json*> ArrayField(const json& object, const std::string& field,
                                       const std::string& what) {
  auto f = Field(object, field);
  if (!f.ok()) return Prefix(what, f.status());
  if (!(*f)->is_array())
    return absl::InvalidArgumentError(absl::StrCat(what, ".", field, ": not an array"));
  return *f;
}

absl::StatusOr<double> Number(const json& object, const std::string& field,
                              const std::string& what) {
  auto v = NumberField(object, field);
  if (!v.ok()) return Prefix(what, v.status());
  return *v;
}

absl::StatusOr<Eigen::Vector3d> Vec3(const json& object, const std::string& field,
                                     const std::string& what) {
  auto f = Field(object, field);
  if (!f.ok()) return Prefix(what, f.status());
  return ParseVec3(**f, absl::StrCat(what, ".", field));
}

}  // namespace

absl::Status Trajectory::Validate() const {
  VB_RETURN_IF_ERROR(CheckPose(platform_from_arm_base, "platform_from_arm_base"));
  VB_RETURN_IF_ERROR(CheckPose(tool.flange_from_tcp, "tool.flange_from_tcp"));
  for (size_t i = 0; i < tool.capsules.size(); ++i) {
    const Capsule& c = tool.capsules[i];
    const std::string what = absl::StrCat("tool.capsules[", i, "]");
    if (!c.a.allFinite() || !c.b.allFinite() || !std::isfinite(c.radius)) {
      return absl::InvalidArgumentError(what + ": not finite");
    }
    if (c.radius < 0) return absl::InvalidArgumentError(what + ".radius: negative");
  }
  double last_t = -std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < segments.size(); ++s) {
    const TrajectorySegment& segment = segments[s];
    const std::string what = absl::StrCat("segments[", s, "]");
    if (segment.kind == SegmentKind::kCut && segment.cut_id.value <= 0) {
      return absl::InvalidArgumentError(what + ".cut_id: a cut segment needs a positive cut id");
    }
    for (size_t p = 0; p < segment.points.size(); ++p) {
      const TrajectoryPoint& point = segment.points[p];
      const std::string point_what = absl::StrCat(what, ".points[", p, "]");
      if (!std::isfinite(point.t)) return absl::InvalidArgumentError(point_what + ".t: not finite");
      for (int j = 0; j < 6; ++j) {
        if (!std::isfinite(point.q[j])) {
          return absl::InvalidArgumentError(absl::StrCat(point_what, ".q[", j, "]: not finite"));
        }
      }
      // A segment starts where the one before it ended (same time, same configuration).
      const bool increases = p == 0 ? point.t >= last_t : point.t > last_t;
      if (!increases) {
        return absl::InvalidArgumentError(absl::StrCat(
            point_what, ".t: ", point.t, " does not increase (previous ", last_t, ")"));
      }
      last_t = point.t;
    }
  }
  if (!std::isfinite(duration_s) || duration_s < 0) {
    return absl::InvalidArgumentError("duration_s: must be finite and >= 0");
  }
  if (std::isfinite(last_t) && duration_s < last_t) {
    return absl::InvalidArgumentError(
        absl::StrCat("duration_s: ", duration_s, " is less than the last time ", last_t));
  }
  for (size_t i = 0; i < unplanned.size(); ++i) {
    if (unplanned[i].cut_id.value <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("unplanned[", i, "].cut_id: must be positive"));
    }
    if (unplanned[i].reason.empty()) {
      return absl::InvalidArgumentError(absl::StrCat("unplanned[", i, "].reason: empty"));
    }
  }
  return absl::OkStatus();
}

json PoseToJson(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  return {{"translation", Vec3ToJson(pose.translation())},
          {"rotation_xyzw", json::array({q.x(), q.y(), q.z(), q.w()})}};
}

absl::StatusOr<Eigen::Isometry3d> PoseFromJson(const json& j, const std::string& what) {
  if (!j.is_object()) return absl::InvalidArgumentError(what + ": not an object");
  VB_RETURN_IF_ERROR(CheckKnownFields(j, {"translation", "rotation_xyzw"}, what + "."));
  VB_ASSIGN_OR_RETURN(Eigen::Vector3d t, Vec3(j, "translation", what));
  VB_ASSIGN_OR_RETURN(const json* r, ArrayField(j, "rotation_xyzw", what));
  const std::string r_what = what + ".rotation_xyzw";
  if (r->size() != 4) return absl::InvalidArgumentError(r_what + ": expected [qx, qy, qz, qw]");
  double xyzw[4];
  for (int i = 0; i < 4; ++i) {
    if (!(*r)[i].is_number()) {
      return absl::InvalidArgumentError(absl::StrCat(r_what, "[", i, "]: not a number"));
    }
    xyzw[i] = (*r)[i].get<double>();
    if (!std::isfinite(xyzw[i])) {
      return absl::InvalidArgumentError(absl::StrCat(r_what, "[", i, "]: not finite"));
    }
  }
  Eigen::Quaterniond q(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
  const double norm = q.norm();
  if (norm < 0.5 || norm > 2.0) {
    return absl::InvalidArgumentError(
        absl::StrCat(r_what, ": quaternion norm ", norm, " is not near 1"));
  }
  q.normalize();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.toRotationMatrix();
  pose.translation() = t;
  return pose;
}

json TrajectoryToJson(const Trajectory& trajectory) {
  json capsules = json::array();
  for (const Capsule& c : trajectory.tool.capsules) {
    capsules.push_back({{"a", Vec3ToJson(c.a)}, {"b", Vec3ToJson(c.b)}, {"radius", c.radius}});
  }
  json segments = json::array();
  for (const TrajectorySegment& segment : trajectory.segments) {
    json points = json::array();
    for (const TrajectoryPoint& p : segment.points) {
      points.push_back({{"t", p.t}, {"q", p.q}});
    }
    json s = {{"kind", std::string(SegmentKindName(segment.kind))}, {"points", points}};
    if (segment.kind == SegmentKind::kCut) s["cut_id"] = segment.cut_id.value;
    segments.push_back(s);
  }
  json unplanned = json::array();
  for (const UnplannedCut& u : trajectory.unplanned) {
    unplanned.push_back({{"cut_id", u.cut_id.value}, {"reason", u.reason}});
  }
  return {{"format", kTrajectoryFormat},
          {"robot", trajectory.robot},
          {"platform_from_arm_base", PoseToJson(trajectory.platform_from_arm_base)},
          {"tool",
           {{"name", trajectory.tool.name},
            {"flange_from_tcp", PoseToJson(trajectory.tool.flange_from_tcp)},
            {"capsules", capsules}}},
          {"segments", segments},
          {"duration_s", trajectory.duration_s},
          {"unplanned", unplanned}};
}

namespace {

absl::StatusOr<ToolGeometry> ParseTool(const json& j) {
  if (!j.is_object()) return absl::InvalidArgumentError("tool: not an object");
  VB_RETURN_IF_ERROR(CheckKnownFields(j, {"name", "flange_from_tcp", "capsules"}, "tool."));
  ToolGeometry tool;
  auto name = StringField(j, "name");
  if (!name.ok()) return Prefix("tool", name.status());
  tool.name = *name;
  auto pose = Field(j, "flange_from_tcp");
  if (!pose.ok()) return Prefix("tool", pose.status());
  VB_ASSIGN_OR_RETURN(tool.flange_from_tcp, PoseFromJson(**pose, "tool.flange_from_tcp"));
  VB_ASSIGN_OR_RETURN(const json* capsules, ArrayField(j, "capsules", "tool"));
  for (size_t i = 0; i < capsules->size(); ++i) {
    const json& c = (*capsules)[i];
    const std::string what = absl::StrCat("tool.capsules[", i, "]");
    if (!c.is_object()) return absl::InvalidArgumentError(what + ": not an object");
    VB_RETURN_IF_ERROR(CheckKnownFields(c, {"a", "b", "radius"}, what + "."));
    Capsule capsule;
    VB_ASSIGN_OR_RETURN(capsule.a, Vec3(c, "a", what));
    VB_ASSIGN_OR_RETURN(capsule.b, Vec3(c, "b", what));
    VB_ASSIGN_OR_RETURN(capsule.radius, Number(c, "radius", what));
    tool.capsules.push_back(capsule);
  }
  return tool;
}

absl::StatusOr<TrajectorySegment> ParseSegment(const json& j, const std::string& what) {
  if (!j.is_object()) return absl::InvalidArgumentError(what + ": not an object");
  VB_RETURN_IF_ERROR(CheckKnownFields(j, {"kind", "cut_id", "points"}, what + "."));
  TrajectorySegment segment;
  auto kind = StringField(j, "kind");
  if (!kind.ok()) return Prefix(what, kind.status());
  if (*kind == "transit") {
    segment.kind = SegmentKind::kTransit;
  } else if (*kind == "cut") {
    segment.kind = SegmentKind::kCut;
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ".kind: unknown segment kind '", *kind, "' (expected transit or cut)"));
  }
  if (segment.kind == SegmentKind::kCut) {
    auto id = IntField(j, "cut_id");
    if (!id.ok()) return Prefix(what, id.status());
    segment.cut_id = CutId(*id);
  } else if (j.contains("cut_id")) {
    return absl::InvalidArgumentError(what + ".cut_id: only cut segments carry a cut id");
  }
  VB_ASSIGN_OR_RETURN(const json* points, ArrayField(j, "points", what));
  for (size_t p = 0; p < points->size(); ++p) {
    const json& pj = (*points)[p];
    const std::string p_what = absl::StrCat(what, ".points[", p, "]");
    if (!pj.is_object()) return absl::InvalidArgumentError(p_what + ": not an object");
    VB_RETURN_IF_ERROR(CheckKnownFields(pj, {"t", "q"}, p_what + "."));
    TrajectoryPoint point;
    VB_ASSIGN_OR_RETURN(point.t, Number(pj, "t", p_what));
    VB_ASSIGN_OR_RETURN(const json* q, ArrayField(pj, "q", p_what));
    if (q->size() != 6) return absl::InvalidArgumentError(p_what + ".q: expected 6 joint angles");
    for (int i = 0; i < 6; ++i) {
      if (!(*q)[i].is_number()) {
        return absl::InvalidArgumentError(absl::StrCat(p_what, ".q[", i, "]: not a number"));
      }
      point.q[i] = (*q)[i].get<double>();
    }
    segment.points.push_back(point);
  }
  return segment;
}

}  // namespace

absl::StatusOr<Trajectory> TrajectoryFromJson(const json& j) {
  VB_RETURN_IF_ERROR(CheckFormat(j, kTrajectoryFormat));
  VB_RETURN_IF_ERROR(CheckKnownFields(
      j,
      {"format", "robot", "platform_from_arm_base", "tool", "segments", "duration_s", "unplanned"},
      /*what=*/""));
  Trajectory trajectory;
  VB_ASSIGN_OR_RETURN(trajectory.robot, StringField(j, "robot"));
  VB_ASSIGN_OR_RETURN(const json* mount, Field(j, "platform_from_arm_base"));
  VB_ASSIGN_OR_RETURN(trajectory.platform_from_arm_base,
                      PoseFromJson(*mount, "platform_from_arm_base"));
  VB_ASSIGN_OR_RETURN(const json* tool, Field(j, "tool"));
  VB_ASSIGN_OR_RETURN(trajectory.tool, ParseTool(*tool));
  VB_ASSIGN_OR_RETURN(const json* segments, Field(j, "segments"));
  if (!segments->is_array()) return absl::InvalidArgumentError("segments: not an array");
  for (size_t s = 0; s < segments->size(); ++s) {
    VB_ASSIGN_OR_RETURN(TrajectorySegment segment,
                        ParseSegment((*segments)[s], absl::StrCat("segments[", s, "]")));
    trajectory.segments.push_back(std::move(segment));
  }
  VB_ASSIGN_OR_RETURN(trajectory.duration_s, NumberField(j, "duration_s"));
  VB_ASSIGN_OR_RETURN(const json* unplanned, Field(j, "unplanned"));
  if (!unplanned->is_array()) return absl::InvalidArgumentError("unplanned: not an array");
  for (size_t i = 0; i < unplanned->size(); ++i) {
    const json& u = (*unplanned)[i];
    const std::string what = absl::StrCat("unplanned[", i, "]");
    if (!u.is_object()) return absl::InvalidArgumentError(what + ": not an object");
    VB_RETURN_IF_ERROR(CheckKnownFields(u, {"cut_id", "reason"}, what + "."));
    UnplannedCut cut;
    auto id = IntField(u, "cut_id");
    if (!id.ok()) return Prefix(what, id.status());
    cut.cut_id = CutId(*id);
    auto reason = StringField(u, "reason");
    if (!reason.ok()) return Prefix(what, reason.status());
    cut.reason = *reason;
    trajectory.unplanned.push_back(cut);
  }
  VB_RETURN_IF_ERROR(trajectory.Validate());
  return trajectory;
}

absl::Status WriteTrajectory(const std::string& path, const Trajectory& trajectory) {
  return WriteJsonFile(path, TrajectoryToJson(trajectory));
}

absl::StatusOr<Trajectory> ReadTrajectory(const std::string& path) {
  return ReadJsonFileAs<Trajectory>(path, TrajectoryFromJson);
}

}  // namespace vb
