// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/tool.h"

#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb::plan {
namespace {

absl::Status CheckPositive(double value, const char* what, const char* field) {
  if (!std::isfinite(value) || value <= 0.0) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ".", field, ": must be finite and > 0, is ", value));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status MillEndOptions::Validate() const {
  const std::pair<double, const char*> fields[] = {
      {body_length_m, "body_length_m"},     {body_radius_m, "body_radius_m"},
      {collet_length_m, "collet_length_m"}, {collet_radius_m, "collet_radius_m"},
      {bit_length_m, "bit_length_m"},       {bit_radius_m, "bit_radius_m"},
      {flute_length_m, "flute_length_m"}};
  for (const auto& [value, name] : fields) {
    if (auto s = CheckPositive(value, "mill_end", name); !s.ok()) return s;
  }
  if (flute_length_m > bit_length_m) {
    return absl::InvalidArgumentError("mill_end.flute_length_m: longer than bit_length_m");
  }
  if (bit_radius_m > collet_radius_m) {
    return absl::InvalidArgumentError("mill_end.bit_radius_m: wider than collet_radius_m");
  }
  return absl::OkStatus();
}

absl::Status SecateurOptions::Validate() const {
  const std::pair<double, const char*> fields[] = {
      {body_length_m, "body_length_m"}, {body_radius_m, "body_radius_m"},
      {jaw_length_m, "jaw_length_m"},   {jaw_opening_m, "jaw_opening_m"},
      {jaw_radius_m, "jaw_radius_m"},   {tcp_depth_m, "tcp_depth_m"}};
  for (const auto& [value, name] : fields) {
    if (auto s = CheckPositive(value, "secateur", name); !s.ok()) return s;
  }
  if (tcp_depth_m >= jaw_length_m) {
    return absl::InvalidArgumentError("secateur.tcp_depth_m: must be less than jaw_length_m");
  }
  return absl::OkStatus();
}

ToolGeometry MillEndTool(const MillEndOptions& o) {
  ToolGeometry tool;
  tool.name = kMillEndToolName;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  // The housing's nose is rounded by the capsule cap; its flange end reaches into the flange
  // (frame 6 and the tool move together, so that overlap is never checked).
  const double body_end = std::max(o.body_length_m - o.body_radius_m, 0.0);
  tool.capsules.push_back({Eigen::Vector3d::Zero(), body_end * z, o.body_radius_m});
  const double collet_end = o.body_length_m + o.collet_length_m;
  tool.capsules.push_back(
      {o.body_length_m * z, (collet_end - o.collet_radius_m) * z, o.collet_radius_m});
  const double tip = collet_end + o.bit_length_m;
  tool.capsules.push_back({collet_end * z, (tip - o.bit_radius_m) * z, o.bit_radius_m});
  tool.flange_from_tcp = Eigen::Isometry3d::Identity();
  tool.flange_from_tcp.translation() = (tip - 0.5 * o.flute_length_m) * z;
  return tool;
}

ToolGeometry SecateurTool(const SecateurOptions& o) {
  ToolGeometry tool;
  tool.name = kSecateurToolName;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  tool.capsules.push_back(
      {Eigen::Vector3d::Zero(), (o.body_length_m - o.body_radius_m) * z, o.body_radius_m});
  // Jaw capsules: their surfaces leave jaw_opening_m clear between them, root to tip.
  const double offset = 0.5 * o.jaw_opening_m + o.jaw_radius_m;
  for (double side : {-1.0, 1.0}) {
    const Eigen::Vector3d x = side * offset * Eigen::Vector3d::UnitX();
    tool.capsules.push_back({x + o.body_length_m * z,
                             x + (o.body_length_m + o.jaw_length_m - o.jaw_radius_m) * z,
                             o.jaw_radius_m});
  }
  tool.flange_from_tcp = Eigen::Isometry3d::Identity();
  tool.flange_from_tcp.translation() = (o.body_length_m + o.tcp_depth_m) * z;
  return tool;
}

CutStroke StrokeOf(const ToolGeometry& tool) {
  return tool.name == kSecateurToolName ? CutStroke::kApproachCloseRetract : CutStroke::kSweep;
}

}  // namespace vb::plan
