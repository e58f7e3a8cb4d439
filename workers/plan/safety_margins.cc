// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/safety_margins.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "workers/plan/collision_checker.h"

namespace vb::plan {

absl::Status MarginOptions::Validate() const {
  auto bad = [](const char* field) {
    return absl::InvalidArgumentError(
        absl::StrCat("margin options: ", field, " must be finite and >= 0"));
  };
  if (!std::isfinite(max_margin_m) || max_margin_m < 0) return bad("max_margin_m");
  if (!std::isfinite(slack_m) || slack_m < 0) return bad("slack_m");
  if (!std::isfinite(max_step_m) || !(max_step_m > 0))
    return absl::InvalidArgumentError("margin options: max_step_m must be finite and > 0");
  return absl::OkStatus();
}

namespace {

// One arm body capsule at one configuration, in the base frame, with its axis-aligned box
// (surface included) and the protected motion it belongs to.
struct PlacedCapsule {
  Eigen::Vector3d a, b;
  double radius = 0.0;
  Eigen::Vector3d lo, hi;
  int motion = 0;
};

void Place(const std::vector<LinkBody>& bodies, const Joints& q, int motion,
           std::vector<PlacedCapsule>* placed) {
  const auto frames = LinkFrames(q);
  for (const LinkBody& body : bodies) {
    for (const Capsule& c : body.capsules) {
      PlacedCapsule p;
      p.a = frames[body.frame] * c.a;
      p.b = frames[body.frame] * c.b;
      p.radius = c.radius;
      p.lo = p.a.cwiseMin(p.b).array() - c.radius;
      p.hi = p.a.cwiseMax(p.b).array() + c.radius;
      p.motion = motion;
      // A non-finite capsule's distances are NaN, which never lowers a minimum: drop it.
      if (p.lo.allFinite() && p.hi.allFinite()) placed->push_back(p);
    }
  }
}

// The same rule as CollisionScene::WithoutCaneNear: the cut cane's capsules near the cut point.
bool Ignored(const Obstacle& o, const ProtectedMotion& m) {
  return m.ignored_cane.value != 0 && o.kind == ObstacleKind::kCane &&
         o.owner_id == m.ignored_cane.value &&
         PointSegmentDistance(m.ignored_point_in_base, o.capsule.a, o.capsule.b) <=
             m.ignored_radius_m;
}

// A uniform grid over the placed capsules' boxes: each cell lists the capsules whose box meets
// it (compressed rows). Obstacles are few (hundreds) and placed capsules many (tens of
// thousands), so each obstacle visits only the capsules in the cells its padded box meets.
class CapsuleGrid {
 public:
  CapsuleGrid(const std::vector<PlacedCapsule>& placed, double cell_m) {
    if (placed.empty()) return;
    lo_ = placed[0].lo;
    Eigen::Vector3d hi = placed[0].hi;
    for (const PlacedCapsule& p : placed) {
      lo_ = lo_.cwiseMin(p.lo);
      hi = hi.cwiseMax(p.hi);
    }
    // At most kMaxCells per axis: a far-flung configuration coarsens the grid, it never grows it.
    constexpr int kMaxCells = 64;
    cell_m_ = std::max(cell_m, (hi - lo_).maxCoeff() / kMaxCells);
    for (int k = 0; k < 3; ++k)
      n_[k] = std::clamp(static_cast<int>((hi[k] - lo_[k]) / cell_m_) + 1, 1, kMaxCells);
    start_.assign(static_cast<size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
    auto for_cells = [&](const PlacedCapsule& p, auto&& f) {
      const auto [c0, c1] = Cells(p.lo, p.hi);
      for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
          for (int x = c0[0]; x <= c1[0]; ++x) f(Index(x, y, z));
    };
    for (const PlacedCapsule& p : placed) for_cells(p, [&](size_t cell) { ++start_[cell + 1]; });
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    entries_.resize(start_.back());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < placed.size(); ++i)
      for_cells(placed[i], [&](size_t cell) { entries_[fill[cell]++] = static_cast<int>(i); });
  }

  // Calls visit(i) for every capsule listed in a cell the box [lo, hi] meets (a capsule in
  // several cells is visited once per cell); stops when visit returns false.
  template <typename Visit>
  void ForEachNear(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit&& visit) const {
    if (entries_.empty()) return;
    for (int k = 0; k < 3; ++k) {
      if (hi[k] < lo_[k] || lo[k] > lo_[k] + n_[k] * cell_m_) return;
    }
    const auto [c0, c1] = Cells(lo, hi);
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) {
          const size_t cell = Index(x, y, z);
          for (int e = start_[cell]; e < start_[cell + 1]; ++e)
            if (!visit(entries_[e])) return;
        }
  }

 private:
  std::pair<std::array<int, 3>, std::array<int, 3>> Cells(const Eigen::Vector3d& lo,
                                                          const Eigen::Vector3d& hi) const {
    std::array<int, 3> c0, c1;
    for (int k = 0; k < 3; ++k) {
      // Clamped in double before the cast: boxes may reach far outside the grid.
      c0[k] = static_cast<int>(std::clamp((lo[k] - lo_[k]) / cell_m_, 0.0, n_[k] - 1.0));
      c1[k] = static_cast<int>(std::clamp((hi[k] - lo_[k]) / cell_m_, 0.0, n_[k] - 1.0));
    }
    return {c0, c1};
  }
  size_t Index(int x, int y, int z) const {
    return (static_cast<size_t>(z) * n_[1] + y) * n_[0] + x;
  }

  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  double cell_m_ = 1.0;
  std::array<int, 3> n_ = {0, 0, 0};
  std::vector<int> start_;    // cell c lists entries_[start_[c] .. start_[c + 1])
  std::vector<int> entries_;  // capsule indices
};

// Grid cell edge: about an arm link's thickness plus the margin reach, so a cane piece's padded
// box meets a few cells.
constexpr double kCellM = 0.12;

}  // namespace

MarginSummary InflateMargins(const RobotModel& robot, std::span<const ProtectedMotion> motions,
                             const MarginOptions& options, CollisionScene* scene) {
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  // The checkers' own interpolation (CollisionChecker::IsMotionFree), so the poses are theirs.
  const JointLevers lever_m = JointLeverArms(robot);
  size_t capsules = 0;
  for (const LinkBody& body : bodies) capsules += body.capsules.size();
  size_t expected = 0;
  for (const ProtectedMotion& motion : motions) {
    expected += motion.path.size();
    for (size_t i = 0; i + 1 < motion.path.size(); ++i)
      expected += MotionSteps(motion.path[i], motion.path[i + 1], options.max_step_m, lever_m) - 1;
  }
  std::vector<PlacedCapsule> placed;
  placed.reserve(expected * capsules);
  int configurations = 0;
  for (size_t m = 0; m < motions.size(); ++m) {
    const ProtectedMotion& motion = motions[m];
    const int id = static_cast<int>(m);
    for (size_t i = 0; i < motion.path.size(); ++i) {
      Place(bodies, motion.path[i], id, &placed);
      ++configurations;
      if (i + 1 == motion.path.size()) break;
      const Joints& a = motion.path[i];
      const Joints& b = motion.path[i + 1];
      const int steps = MotionSteps(a, b, options.max_step_m, lever_m);
      for (int s = 1; s < steps; ++s) {
        Place(bodies, a + (b - a) * (double(s) / steps), id, &placed);
        ++configurations;
      }
    }
  }

  // Only pairs closer than `reach` can limit a margin: farther ones clamp to max_margin_m. So
  // pairs whose boxes are farther apart than that are skipped without changing any margin, and an
  // obstacle's search ends once its margin is 0.
  const double reach = options.max_margin_m + options.slack_m;
  const CapsuleGrid grid(placed, kCellM);
  std::vector<int> visited(placed.size(), -1);      // obstacle index that last measured it
  std::vector<char> ignored(motions.size(), 0);
  std::vector<int> ignored_list;
  std::vector<double> vine_margins;
  for (size_t oi = 0; oi < scene->obstacles.size(); ++oi) {
    Obstacle& o = scene->obstacles[oi];
    for (int m : ignored_list) ignored[m] = 0;
    ignored_list.clear();
    if (o.kind == ObstacleKind::kCane) {
      for (size_t m = 0; m < motions.size(); ++m) {
        if (Ignored(o, motions[m])) {
          ignored[m] = 1;
          ignored_list.push_back(static_cast<int>(m));
        }
      }
    }
    const double pad = o.capsule.radius + reach;
    const Eigen::Vector3d lo = o.capsule.a.cwiseMin(o.capsule.b).array() - pad;
    const Eigen::Vector3d hi = o.capsule.a.cwiseMax(o.capsule.b).array() + pad;
    const int stamp = static_cast<int>(oi);
    double clearance = std::numeric_limits<double>::infinity();
    grid.ForEachNear(lo, hi, [&](int i) {
      if (visited[i] == stamp) return true;
      visited[i] = stamp;
      const PlacedCapsule& p = placed[i];
      if (ignored[p.motion]) return true;
      if ((p.lo.array() > hi.array()).any() || (p.hi.array() < lo.array()).any()) return true;
      const double d = SegmentSegmentDistance(p.a, p.b, o.capsule.a, o.capsule.b) - p.radius -
                       o.capsule.radius;
      clearance = std::min(clearance, d);
      return clearance > options.slack_m;  // margin 0 already: nothing can lower it
    });
    o.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
    if (o.kind != ObstacleKind::kPlatform) vine_margins.push_back(o.margin_m);
  }
  for (HalfSpace& plane : scene->planes) {
    double clearance = std::numeric_limits<double>::infinity();
    for (const PlacedCapsule& p : placed) {
      const double d = plane.offset - std::max(plane.normal.dot(p.a), plane.normal.dot(p.b)) -
                       p.radius;
      clearance = std::min(clearance, d);
    }
    plane.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
  }

  MarginSummary summary;
  summary.configurations = configurations;
  if (!vine_margins.empty()) {
    std::sort(vine_margins.begin(), vine_margins.end());
    summary.min_margin_m = vine_margins.front();
    summary.median_margin_m = vine_margins[vine_margins.size() / 2];
  }
  return summary;
}

}  // namespace vb::plan
