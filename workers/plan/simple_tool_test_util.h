// SPDX-License-Identifier: Apache-2.0
// A fixed, simple cutter for tests and benchmarks of the checker and the planner, independent of
// the tool options (tool.h) so that their figures do not move when a tool's defaults do: a
// 0.035 m spindle on the flange axis to 0.12 m, then a 0.006 m bit to the TCP at 0.17 m.
#pragma once

#include "core/trajectory.h"

namespace vb::plan {

inline ToolGeometry SimpleMillEnd() {
  ToolGeometry tool;
  tool.name = "mill_end";
  tool.flange_from_tcp.translation() = Eigen::Vector3d(0, 0, 0.17);
  tool.capsules = {{Eigen::Vector3d(0, 0, 0.0), Eigen::Vector3d(0, 0, 0.12), 0.035},
                   {Eigen::Vector3d(0, 0, 0.12), Eigen::Vector3d(0, 0, 0.17), 0.006}};
  return tool;
}

}  // namespace vb::plan
