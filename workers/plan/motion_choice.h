// SPDX-License-Identifier: Apache-2.0
// The options a cut can be made with, for choosing them jointly with the order (cut_order.h
// OrderAndChoose): the cut motion, its alternatives, and their twins rolled by pi about the tool
// axis; and the move-time estimate between options, with whole-turn shifts (plan_vine.cc
// ShiftedForReach) taken into account. Pure functions; thread-safe.
#pragma once

#include <optional>
#include <vector>

#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// True when rolling the flange by pi about its axis (joint 6 + pi) leaves the arm's collision
// geometry and the cut unchanged: every capsule moved by joint 6 (the tool's, and any link in
// frame 6) maps onto one of them (either end order, 1e-9 m) under the rotation by pi about the
// flange z axis, and the TCP is on that axis with its z along it. The rolled TCP frame is then the
// cut pose sampled on the other side of the cane (cut_motion.h: y -> -y, x -> -x, z kept), an
// equally good cut. Both tools of tool.h are (the mill end is axisymmetric; the secateur's jaws
// sit at x = +-); an asymmetric tool is not.
bool RollSymmetric(const RobotModel& robot);

// The twin of a cut motion rolled by pi about the tool axis: joint 6 + pi (or - pi, whichever
// keeps the whole path within the limits; none: nullopt), and for a sweep (TCP x reversed) the
// path in reverse order. Only meaningful when RollSymmetric(robot). `cut_index` is the path's;
// *twin_cut_index receives the twin's. nullopt for an empty path or cut_index out of range.
std::optional<std::vector<Joints>> RolledTwin(const std::vector<Joints>& path, int cut_index,
                                              CutStroke stroke, const JointLimits& limits,
                                              int* twin_cut_index);

// `q` with each joint moved by a whole turn (-1, 0 or +1) to the value nearest `near` that stays
// within the limits (joints whose range is not wider than a turn keep their value).
Joints NearestTurn(const Joints& q, const Joints& near, const JointLimits& limits);

// MoveTimeS(from, NearestTurn(to, from)): the straight move to the nearest whole-turn copy of
// `to`, as the planner's shift for reach takes it (an estimate: the planner also needs the shifted
// stroke within the limits and the move free of self-collision).
double TurnAwareMoveTimeS(const Joints& from, const Joints& to, const JointLimits& limits);

// True when a and b are the same configuration up to whole turns (each joint within tol_rad).
bool SameUpToTurns(const Joints& a, const Joints& b, double tol_rad = 1e-3);

}  // namespace vb::plan
