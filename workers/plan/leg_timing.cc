// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/leg_timing.h"

#include <utility>
#include <vector>

#include "core/status_macros.h"
#include "workers/plan/blend.h"
#include "workers/plan/time_parameterization.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

// Appends timed samples to the trajectory as one segment.
void AppendSegment(SegmentKind kind, CutId cut_id, const std::vector<TimedJoints>& timed,
                   Trajectory* out) {
  TrajectorySegment segment;
  segment.kind = kind;
  segment.cut_id = cut_id;
  for (const TimedJoints& p : timed) {
    TrajectoryPoint point;
    point.t = p.t;
    for (int j = 0; j < 6; ++j) point.q[j] = p.q[j];
    segment.points.push_back(point);
  }
  if (!segment.points.empty()) out->duration_s = segment.points.back().t;
  out->segments.push_back(std::move(segment));
}

}  // namespace

// A transit from rest to rest, blended through its waypoints where the blends are free in
// `checker` (the scene it was planned in) and the blended trajectory is proven free in `proof`
// (the scene without margins; MotionProver between its samples through the blends, as it is
// re-checked; the other chords are on the proven waypoint segments), or
// stopping at each of them (on the waypoints' segments, which were proven free).
absl::Status AppendTransit(std::span<const Joints> waypoints, CollisionChecker* checker,
                           MotionProver* proof, const PlanOptions& options,
                           const JointLimits& limits, PlanStats& stats, Trajectory* out) {
  auto stop_at_each = [&]() -> absl::Status {
    VB_ASSIGN_OR_RETURN(const std::vector<TimedJoints> timed,
                        TimeParameterize(waypoints, limits, out->duration_s, options.sample_dt_s));
    AppendSegment(SegmentKind::kTransit, CutId{0}, timed, out);
    return absl::OkStatus();
  };
  if (!options.blend_transits) return stop_at_each();
  BlendOptions blend = options.blend;
  blend.max_step_m = options.path.max_step_m;
  VB_ASSIGN_OR_RETURN(const BlendedPath path,
                      TimeParameterizeBlended(waypoints, limits, checker, blend, out->duration_s,
                                              options.sample_dt_s));
  stats.blend_vias += path.vias;
  stats.blend_stops += path.stops;
  stats.blend_shrinks += path.shrinks;
  stats.checks += path.checks;
  if (path.vias > path.stops) {
    // Only the chords through the blends: the others lie on the waypoints' segments, which were
    // proven free of the same scene when the path was accepted (Planning::Prove).
    const int64_t checks = proof->checks();
    bool proven = true;
    for (size_t c = 0; c < path.blend_chords.size() && proven; ++c) {
      const int i = path.blend_chords[c];
      proven = proof->IsMotionFree(path.samples[i].q, path.samples[i + 1].q);
    }
    stats.checks += proof->checks() - checks;
    if (!proven) {
      ++stats.unproven_blends;
      return stop_at_each();
    }
  }
  AppendSegment(SegmentKind::kTransit, CutId{0}, path.samples, out);
  return absl::OkStatus();
}

// A cut stroke, at rest at its ends. Mill end: the part of the sweep whose TCP is within the
// cane's radius plus cut_feed_margin_m of the cut point is in wood and moves at the feed rate
// (cut_speed_fraction of the velocity limits), the rest in free air at the full limits. Secateur:
// the jaws close with the arm at rest at the cut; approach and retract move at the full limits.
absl::Status AppendStroke(const CutMotion& motion, const Cut& cut, const RobotModel& robot,
                          const PlanOptions& options, Trajectory* out) {
  const std::vector<Joints>& path = motion.path;
  std::vector<double> fraction(path.empty() ? 0 : path.size() - 1, 1.0);
  std::vector<int> stops;
  const bool at_cut = motion.cut_index >= 0 && static_cast<size_t>(motion.cut_index) < path.size();
  if (StrokeOf(robot.tool) == CutStroke::kApproachCloseRetract) {
    if (at_cut) stops.push_back(motion.cut_index);
  } else {
    auto tcp = [&](const Joints& q) {
      return Eigen::Vector3d((ForwardKinematics(q) * robot.tool.flange_from_tcp).translation());
    };
    const double contact_m = 0.5 * cut.diameter_m + options.cut_feed_margin_m;
    const Eigen::Vector3d cut_point = tcp(path[at_cut ? motion.cut_index : 0]);
    std::vector<bool> in_wood(path.size());
    for (size_t k = 0; k < path.size(); ++k)
      in_wood[k] = !at_cut || (tcp(path[k]) - cut_point).norm() <= contact_m;
    for (size_t k = 0; k < fraction.size(); ++k)
      if (in_wood[k] || in_wood[k + 1]) fraction[k] = options.cut_speed_fraction;
  }
  VB_ASSIGN_OR_RETURN(const std::vector<TimedJoints> timed,
                      TimeParameterizeAlongPath(path, robot.limits, fraction, stops,
                                                out->duration_s, options.sample_dt_s));
  AppendSegment(SegmentKind::kCut, cut.id, timed, out);
  return absl::OkStatus();
}

}  // namespace vb::plan
