// SPDX-License-Identifier: Apache-2.0
// The stubs check of a pass (plan_vine.cc, docs/plan.md "The plan stage" step 6): a cut motion
// (path and alternatives) must not touch the stub chord that another cut of the same pass leaves
// (CollisionScene::StubChords). Each motion is checked with a checker built on those stubs
// (IsFree at its first configuration, IsMotionFree between consecutive ones), as before s13, but
// what the cut-motion search showed to be the same geometry is checked once:
//  - a mirrored stroke (the secateur's: path[c + j] == path[c - j] for every j, c the middle)
//    retraces its approach: the motions of its second half are those of its first, reversed
//    (the same configurations; IsMotionFree samples them from the other end, which differs by
//    rounding only);
//  - with `share_twins` (a robot whose flange bodies are symmetric under a half turn about the
//    flange axis, motion_choice.h RollSymmetric, and a capsule checker), a motion that is the
//    half-turn twin of an earlier one (joints 1-5 equal bit for bit, joint 6 turned by pi, in the
//    same or reversed order) places the same capsules in space: it gets that motion's verdict.
//    The cut-motion search relies on the same identity (cut_motion.h share_rolled_twins).
// Pure functions; thread-compatible (the checker is the caller's).
#pragma once

#include <vector>

#include "workers/plan/collision_checker.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// Drops the motions of `motion` (its path and alternatives) that `checker` (built on the stubs)
// finds in collision along their configurations (IsMotionFree at `max_step_m`); the first free
// alternative replaces a path that touches. False (and `motion` unchanged) if every one does.
bool KeepMotionsFreeOfStubs(CollisionChecker& checker, double max_step_m, bool share_twins,
                            CutMotion* motion);

// True when `b` is the half-turn twin of `a`: the same length, joints 1-5 equal bit for bit and
// joint 6 turned by the same +pi or -pi throughout (within 1e-9 rad), configuration by
// configuration in the same order or in reverse order (a sweep's twin runs the other way).
bool IsHalfTurnTwin(const std::vector<Joints>& a, const std::vector<Joints>& b);

// True when path[c + j] == path[c - j] bit for bit for every j, with c = size / 2 and an odd size
// of at least 3 (a stroke that returns the way it came).
bool IsMirroredPath(const std::vector<Joints>& path);

}  // namespace vb::plan
