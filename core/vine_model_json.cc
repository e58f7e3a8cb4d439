// SPDX-License-Identifier: Apache-2.0
#include "core/vine_model_json.h"

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb {

using nlohmann::json;

json VineModelToJson(const VineModel& model) {
  json canes = json::array();
  for (const Cane& c : model.canes) {
    json points = json::array();
    for (const auto& p : c.polyline.points) points.push_back(Vec3ToJson(p));
    canes.push_back({{"id", c.id.value},
                     {"parent_id", c.parent_id ? json(c.parent_id->value) : json(nullptr)},
                     {"kind", std::string(CaneKindName(c.kind))},
                     {"points", points},
                     {"radii", c.polyline.radii}});
  }
  json spheres = json::array();
  for (const Sphere& s : model.head.spheres) {
    spheres.push_back({s.center.x(), s.center.y(), s.center.z(), s.radius});
  }
  json wires = json::array();
  for (const Wire& w : model.wires) {
    json points = json::array();
    for (const auto& p : w.points) points.push_back(Vec3ToJson(p));
    wires.push_back({{"id", w.id.value}, {"points", points}, {"radius", w.radius}});
  }
  json posts = json::array();
  for (const Post& p : model.posts) {
    posts.push_back({{"id", p.id.value},
                     {"base", Vec3ToJson(p.base)},
                     {"top", Vec3ToJson(p.top)},
                     {"radius", p.radius}});
  }
  json out = {{"format", kVineModelFormat}, {"frame", "platform"}, {"units", "m"},
              {"canes", canes},            {"head", {{"spheres", spheres}}},
              {"wires", wires},            {"posts", posts}};
  // Optional: written only when there are some, so that models without (ground truth, older
  // files) read and write exactly as before.
  if (!model.obstacles.empty()) {
    json obstacles = json::array();
    for (const WoodObstacle& o : model.obstacles) {
      json points = json::array();
      for (const auto& p : o.polyline.points) points.push_back(Vec3ToJson(p));
      obstacles.push_back({{"points", points}, {"radii", o.polyline.radii}});
    }
    out["obstacles"] = obstacles;
  }
  return out;
}

namespace {

// Prefixes a status message with the element being parsed.
absl::Status Prefix(const std::string& what, const absl::Status& s) {
  return absl::Status(s.code(), absl::StrCat(what, ".", s.message()));
}

absl::StatusOr<std::vector<Eigen::Vector3d>> ParsePoints(const json& object,
                                                         const std::string& what) {
  auto field = Field(object, "points");
  if (!field.ok()) return Prefix(what, field.status());
  if (!(*field)->is_array()) return absl::InvalidArgumentError(what + ".points: not an array");
  std::vector<Eigen::Vector3d> points;
  for (size_t k = 0; k < (*field)->size(); ++k) {
    VB_ASSIGN_OR_RETURN(Eigen::Vector3d p,
                        ParseVec3((**field)[k], absl::StrCat(what, ".points[", k, "]")));
    points.push_back(p);
  }
  return points;
}

// The "points" and "radii" of a cane or an obstacle (checked by VineModel::Validate after).
absl::StatusOr<Polyline3> ParsePolyline(const json& j, const std::string& what) {
  Polyline3 polyline;
  VB_ASSIGN_OR_RETURN(polyline.points, ParsePoints(j, what));
  auto radii = Field(j, "radii");
  if (!radii.ok()) return Prefix(what, radii.status());
  if (!(*radii)->is_array()) return absl::InvalidArgumentError(what + ".radii: not an array");
  for (size_t k = 0; k < (*radii)->size(); ++k) {
    const json& r = (**radii)[k];
    if (!r.is_number()) {
      return absl::InvalidArgumentError(absl::StrCat(what, ".radii[", k, "]: not a number"));
    }
    polyline.radii.push_back(r.get<double>());
  }
  return polyline;
}

absl::StatusOr<Cane> ParseCane(const json& j, const std::string& what) {
  Cane cane;
  auto id = IntField(j, "id");
  if (!id.ok()) return Prefix(what, id.status());
  cane.id = CaneId(*id);
  auto parent = Field(j, "parent_id");
  if (!parent.ok()) return Prefix(what, parent.status());
  if (!(*parent)->is_null()) {
    if (!(*parent)->is_number_integer()) {
      return absl::InvalidArgumentError(what + ".parent_id: not an integer or null");
    }
    cane.parent_id = CaneId((*parent)->get<int64_t>());
  }
  auto kind_name = StringField(j, "kind");
  if (!kind_name.ok()) return Prefix(what, kind_name.status());
  auto kind = ParseCaneKind(*kind_name);
  if (!kind.ok()) return Prefix(what, kind.status());
  cane.kind = *kind;
  VB_ASSIGN_OR_RETURN(cane.polyline, ParsePolyline(j, what));
  return cane;
}

absl::StatusOr<const json*> ArrayField(const json& object, const std::string& field) {
  VB_ASSIGN_OR_RETURN(const json* f, Field(object, field));
  if (!f->is_array()) return absl::InvalidArgumentError(field + ": not an array");
  return f;
}

}  // namespace

absl::StatusOr<VineModel> VineModelFromJson(const json& j) {
  VB_RETURN_IF_ERROR(CheckFormat(j, kVineModelFormat));
  if (j.contains("frame") && j["frame"] != "platform") {
    return absl::InvalidArgumentError("frame: only 'platform' is supported");
  }
  if (j.contains("units") && j["units"] != "m") {
    return absl::InvalidArgumentError("units: only 'm' is supported");
  }
  VineModel model;
  VB_ASSIGN_OR_RETURN(const json* canes, ArrayField(j, "canes"));
  for (size_t i = 0; i < canes->size(); ++i) {
    VB_ASSIGN_OR_RETURN(Cane cane, ParseCane((*canes)[i], absl::StrCat("canes[", i, "]")));
    model.canes.push_back(std::move(cane));
  }
  if (j.contains("head")) {
    VB_ASSIGN_OR_RETURN(const json* spheres, ArrayField(j["head"], "spheres"));
    for (size_t i = 0; i < spheres->size(); ++i) {
      const json& s = (*spheres)[i];
      if (!s.is_array() || s.size() != 4) {
        return absl::InvalidArgumentError(absl::StrCat("head.spheres[", i, "]: expected [x,y,z,r]"));
      }
      for (int k = 0; k < 4; ++k) {
        if (!s[k].is_number()) {
          return absl::InvalidArgumentError(
              absl::StrCat("head.spheres[", i, "][", k, "]: not a number"));
        }
      }
      model.head.spheres.push_back(
          {Eigen::Vector3d(s[0].get<double>(), s[1].get<double>(), s[2].get<double>()),
           s[3].get<double>()});
    }
  }
  if (j.contains("wires")) {
    VB_ASSIGN_OR_RETURN(const json* wires, ArrayField(j, "wires"));
    for (size_t i = 0; i < wires->size(); ++i) {
      const json& w = (*wires)[i];
      const std::string what = absl::StrCat("wires[", i, "]");
      Wire wire;
      auto id = IntField(w, "id");
      if (!id.ok()) return Prefix(what, id.status());
      wire.id = WireId(*id);
      VB_ASSIGN_OR_RETURN(wire.points, ParsePoints(w, what));
      auto radius = NumberField(w, "radius");
      if (!radius.ok()) return Prefix(what, radius.status());
      wire.radius = *radius;
      model.wires.push_back(std::move(wire));
    }
  }
  if (j.contains("posts")) {
    VB_ASSIGN_OR_RETURN(const json* posts, ArrayField(j, "posts"));
    for (size_t i = 0; i < posts->size(); ++i) {
      const json& p = (*posts)[i];
      const std::string what = absl::StrCat("posts[", i, "]");
      Post post;
      auto id = IntField(p, "id");
      if (!id.ok()) return Prefix(what, id.status());
      post.id = PostId(*id);
      auto base = Field(p, "base");
      if (!base.ok()) return Prefix(what, base.status());
      VB_ASSIGN_OR_RETURN(post.base, ParseVec3(**base, what + ".base"));
      auto top = Field(p, "top");
      if (!top.ok()) return Prefix(what, top.status());
      VB_ASSIGN_OR_RETURN(post.top, ParseVec3(**top, what + ".top"));
      auto radius = NumberField(p, "radius");
      if (!radius.ok()) return Prefix(what, radius.status());
      post.radius = *radius;
      model.posts.push_back(post);
    }
  }
  if (j.contains("obstacles")) {
    VB_ASSIGN_OR_RETURN(const json* obstacles, ArrayField(j, "obstacles"));
    for (size_t i = 0; i < obstacles->size(); ++i) {
      const std::string what = absl::StrCat("obstacles[", i, "]");
      if (!(*obstacles)[i].is_object()) return absl::InvalidArgumentError(what + ": not an object");
      VB_ASSIGN_OR_RETURN(Polyline3 polyline, ParsePolyline((*obstacles)[i], what));
      model.obstacles.push_back(WoodObstacle{std::move(polyline)});
    }
  }
  VB_RETURN_IF_ERROR(model.Validate());
  return model;
}

absl::Status WriteVineModel(const std::string& path, const VineModel& model) {
  return WriteJsonFile(path, VineModelToJson(model));
}

absl::StatusOr<VineModel> ReadVineModel(const std::string& path) {
  VB_ASSIGN_OR_RETURN(json j, ReadJsonFile(path));
  auto model = VineModelFromJson(j);
  if (!model.ok()) {
    return absl::Status(model.status().code(), absl::StrCat(path, ": ", model.status().message()));
  }
  return model;
}

}  // namespace vb
