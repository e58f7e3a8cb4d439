// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/safety_margins.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <unordered_map>
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

TwistCachedFrames::TwistCachedFrames(const DhParameters& dh) : dh_(dh) {
  for (int i = 0; i < 6; ++i) ca_[i] = std::cos(dh.alpha[i]), sa_[i] = std::sin(dh.alpha[i]);
}

// LinkFrames (ur5_kinematics.cc) with the twists' sines and cosines computed once: the same
// DhTransform and products, so the same frames bit for bit.
std::array<Eigen::Isometry3d, 7> TwistCachedFrames::operator()(const Joints& q) const {
  std::array<Eigen::Isometry3d, 7> frames;
  frames[0] = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    frames[i + 1] = frames[i] * DhTransform(std::cos(q[i]), std::sin(q[i]), ca_[i], sa_[i],
                                            dh_.a[i], dh_.d[i]);
  }
  return frames;
}

namespace {

// One arm body capsule at one configuration, in the base frame, with its axis-aligned box
// (surface included). A non-finite capsule (its distances are NaN, which never lower a minimum)
// is kept in place, marked invalid, so that capsule k of configuration c is placed[k * n + c] for
// n distinct configurations: each body capsule's configurations are contiguous, as the chunks
// below read them (one allocation: per-capsule vectors made the allocator return and fault in
// megabytes at every call).
struct PlacedCapsule {
  Eigen::Vector3d a, b;
  double radius = 0.0;
  Eigen::Vector3d lo, hi;
  bool valid = false;
};

void Place(const std::vector<LinkBody>& bodies, const TwistCachedFrames& arm, const Joints& q,
           PlacedCapsule* first, size_t stride) {
  const auto frames = arm(q);
  size_t k = 0;
  for (const LinkBody& body : bodies) {
    for (const Capsule& c : body.capsules) {
      PlacedCapsule& p = first[stride * k++];
      p.a = frames[body.frame] * c.a;
      p.b = frames[body.frame] * c.b;
      p.radius = c.radius;
      p.lo = p.a.cwiseMin(p.b).array() - c.radius;
      p.hi = p.a.cwiseMax(p.b).array() + c.radius;
      p.valid = p.lo.allFinite() && p.hi.allFinite();
    }
  }
}

// One body capsule swept over up to kChunkConfigurations consecutive distinct configurations
// held by the same protected motions: the box of its placed capsules, which bounds their
// distances from below.
struct Chunk {
  Eigen::Vector3d lo, hi;
  int motion = 0;  // the group of motions that hold its configurations (InflateMargins)
  int capsule = 0;  // placed[capsule * distinct + first + j] for j < count
  int first = 0;
  int count = 0;
  int first_block = 0;  // blocks[first_block ..]: the boxes of its runs of kBlockConfigurations
};
// Chunks are long (few grid entries and bounds per obstacle) and split into blocks with their
// own boxes (tighter bounds before the capsules). On tuning seeds 1110-1115: 8 configurations
// per chunk and no blocks took 10.5 ms per vine (CPU, vb_margins_bench), 64 and 8 take ~6 ms.
constexpr int kChunkConfigurations = 64;
constexpr int kBlockConfigurations = 8;
struct Block {
  Eigen::Vector3d lo, hi;
};

struct ConfigurationHash {
  size_t operator()(const std::array<uint64_t, 6>& key) const {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const uint64_t k : key) h = (h ^ k) * 0xff51afd7ed558ccdull, h ^= h >> 32;
    return static_cast<size_t>(h);
  }
};

// Squared Euclidean distance between two axis-aligned boxes (0 when they meet): its root is a
// lower bound of the distance between any shapes inside them. The bounds below are compared
// squared (Beyond), without a square root per pair.
double BoxDistanceSquared(const Eigen::Vector3d& lo1, const Eigen::Vector3d& hi1,
                          const Eigen::Vector3d& lo2, const Eigen::Vector3d& hi2) {
  const Eigen::Vector3d gap =
      (lo2 - hi1).cwiseMax(lo1 - hi2).cwiseMax(Eigen::Vector3d::Zero());
  return gap.squaredNorm();
}

// Squared distance from p to the segment [a, b].
double PointSegmentDistanceSquared(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

// Whether a distance whose square is d2 exceeds `limit` (always when limit < 0). A bound is
// compared with a limit kBoundSlackM above the minimum so far, far above the rounding of either
// side, so deciding on squares skips only pairs that could never lower the minimum.
bool Beyond(double d2, double limit) { return limit < 0 || d2 > limit * limit; }

// Pairs are skipped when their lower bound exceeds the minimum so far by more than this: far
// above the rounding of the bounds, so a skipped pair could never have lowered the minimum.
constexpr double kBoundSlackM = 1e-9;
constexpr double kReachSlackM = 1e-6;

// The cut cane's capsules near the cut point: the capsules the cut motions' checkers leave out
// (IsCaneNear, the rule of CollisionScene::WithoutCaneNear), which the stroke may touch.
bool Ignored(const Obstacle& o, const ProtectedMotion& m) {
  return m.ignored_cane.value != 0 &&
         IsCaneNear(o, m.ignored_cane, m.ignored_point_in_base, m.ignored_radius_m);
}

// A uniform grid over the chunks' boxes: each cell lists the chunks whose box meets it
// (compressed rows). Obstacles are few (hundreds) and chunks many (thousands), so each obstacle
// visits only the chunks in the cells its padded box meets.
class ChunkGrid {
 public:
  ChunkGrid(const std::vector<Chunk>& placed, double cell_m) {
    if (placed.empty()) return;
    lo_ = placed[0].lo;
    Eigen::Vector3d hi = placed[0].hi;
    for (const Chunk& p : placed) {
      lo_ = lo_.cwiseMin(p.lo);
      hi = hi.cwiseMax(p.hi);
    }
    // At most kMaxCells per axis: a far-flung configuration coarsens the grid, it never grows it.
    constexpr int kMaxCells = 64;
    cell_m_ = std::max(cell_m, (hi - lo_).maxCoeff() / kMaxCells);
    for (int k = 0; k < 3; ++k)
      n_[k] = std::clamp(static_cast<int>((hi[k] - lo_[k]) / cell_m_) + 1, 1, kMaxCells);
    start_.assign(static_cast<size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
    auto for_cells = [&](const Chunk& p, auto&& f) {
      const auto [c0, c1] = Cells(p.lo, p.hi);
      for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
          for (int x = c0[0]; x <= c1[0]; ++x) f(Index(x, y, z));
    };
    for (const Chunk& p : placed) for_cells(p, [&](size_t cell) { ++start_[cell + 1]; });
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    entries_.resize(start_.back());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < placed.size(); ++i)
      for_cells(placed[i], [&](size_t cell) { entries_[fill[cell]++] = static_cast<int>(i); });
  }

  // Calls visit(i) for every chunk listed in a cell the box [lo, hi] meets (a chunk in several
  // cells is visited once per cell).
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
            visit(entries_[e]);
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
  std::vector<int> entries_;  // chunk indices
};

// Grid cell edge: about an arm link's sweep over a chunk plus the margin reach, so a cane
// piece's padded box meets a few cells.
constexpr double kCellM = 0.12;

}  // namespace


MarginSummary InflateMargins(const RobotModel& robot, std::span<const ProtectedMotion> motions,
                             const MarginOptions& options, CollisionScene* scene) {
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  const TwistCachedFrames arm(Ur5Dh());
  // The checkers' own interpolation (CollisionChecker::IsMotionFree), so the poses are theirs.
  const JointLevers lever_m = JointLeverArms(robot);
  size_t capsules = 0;
  for (const LinkBody& body : bodies) capsules += body.capsules.size();
  size_t expected = 0;
  std::vector<int> segment_steps;  // MotionSteps of every segment, motion after motion
  for (const ProtectedMotion& motion : motions) {
    expected += motion.path.size();
    for (size_t i = 0; i + 1 < motion.path.size(); ++i) {
      segment_steps.push_back(
          MotionSteps(motion.path[i], motion.path[i + 1], options.max_step_m, lever_m));
      expected += segment_steps.back() - 1;
    }
  }
  // Each distinct configuration (bitwise: the same joints place the same capsules, hence the same
  // distances) is placed once; a configuration several motions share is ignored by an obstacle
  // only if every one of them ignores it. Alternatives share most of their configurations, and
  // every stroke's ends are also protected alone.
  std::vector<Joints> distinct_q;  // placed once all are known
  distinct_q.reserve(expected);
  const int stride = static_cast<int>(capsules);
  std::unordered_map<std::array<uint64_t, 6>, int, ConfigurationHash> index;
  index.reserve(expected);
  std::vector<int> first_motion;                  // per distinct configuration
  std::vector<std::vector<int>> more_motions;     // other motions that hold it (few)
  std::vector<int> more_of;                       // index into more_motions, or -1
  int configurations = 0;
  auto add = [&](const Joints& q, int motion) {
    ++configurations;
    std::array<uint64_t, 6> key;
    std::memcpy(key.data(), q.data(), sizeof(key));
    const auto [it, inserted] = index.try_emplace(key, static_cast<int>(first_motion.size()));
    if (inserted) {
      distinct_q.push_back(q);
      first_motion.push_back(motion);
      more_of.push_back(-1);
      return;
    }
    const int u = it->second;
    if (first_motion[u] == motion) return;
    if (more_of[u] < 0) {
      more_of[u] = static_cast<int>(more_motions.size());
      more_motions.emplace_back();
    }
    more_motions[more_of[u]].push_back(motion);
  };
  size_t segment = 0;
  for (size_t m = 0; m < motions.size(); ++m) {
    const ProtectedMotion& motion = motions[m];
    const int id = static_cast<int>(m);
    for (size_t i = 0; i < motion.path.size(); ++i) {
      add(motion.path[i], id);
      if (i + 1 == motion.path.size()) break;
      const Joints& a = motion.path[i];
      const Joints& b = motion.path[i + 1];
      const int steps = segment_steps[segment++];
      for (int s = 1; s < steps; ++s) add(a + (b - a) * (double(s) / steps), id);
    }
  }
  // Groups: the set of motions that ignore something and hold a configuration; group 0 (no
  // motion) for a configuration some motion that ignores nothing holds: never ignored.
  std::map<std::vector<int>, int> group_of;
  std::vector<std::vector<int>> groups = {{}};
  group_of[{}] = 0;
  const int distinct = static_cast<int>(first_motion.size());
  std::vector<PlacedCapsule> placed(static_cast<size_t>(distinct) * capsules);
  for (int u = 0; u < distinct; ++u) Place(bodies, arm, distinct_q[u], &placed[u], distinct);
  std::vector<int> group(distinct, 0);
  // Most configurations belong to one motion: its group is looked up once (the same ids, in
  // the same order of first appearance, as the lookup below gives).
  std::vector<int> single_group(motions.size(), -1);
  for (int u = 0; u < distinct; ++u) {
    if (more_of[u] < 0 && single_group[first_motion[u]] >= 0) {
      group[u] = single_group[first_motion[u]];
      continue;
    }
    std::vector<int> holders = {first_motion[u]};
    if (more_of[u] >= 0)
      holders.insert(holders.end(), more_motions[more_of[u]].begin(),
                     more_motions[more_of[u]].end());
    std::sort(holders.begin(), holders.end());
    holders.erase(std::unique(holders.begin(), holders.end()), holders.end());
    bool never = false;
    for (int m : holders) never |= motions[m].ignored_cane.value == 0;
    if (never) holders.clear();
    const auto [it, inserted] = group_of.try_emplace(holders, static_cast<int>(groups.size()));
    if (inserted) groups.push_back(holders);
    group[u] = it->second;
    if (more_of[u] < 0) single_group[first_motion[u]] = group[u];
  }
  // Chunks: each body capsule over runs of consecutive distinct configurations of one group.
  std::vector<Chunk> chunks;
  std::vector<Block> blocks;
  for (int u0 = 0; u0 < distinct;) {
    int n = 1;
    while (n < kChunkConfigurations && u0 + n < distinct && group[u0 + n] == group[u0]) ++n;
    for (int k = 0; k < stride; ++k) {
      Chunk chunk;
      chunk.motion = group[u0];
      chunk.capsule = k;
      chunk.first = u0;
      chunk.count = n;
      chunk.first_block = static_cast<int>(blocks.size());
      chunk.lo.setConstant(std::numeric_limits<double>::infinity());
      chunk.hi.setConstant(-std::numeric_limits<double>::infinity());
      for (int j0 = 0; j0 < n; j0 += kBlockConfigurations) {
        Block& block = blocks.emplace_back();
        block.lo.setConstant(std::numeric_limits<double>::infinity());
        block.hi.setConstant(-std::numeric_limits<double>::infinity());
        for (int j = j0; j < n && j < j0 + kBlockConfigurations; ++j) {
          const PlacedCapsule& p = placed[static_cast<size_t>(k) * distinct + chunk.first + j];
          if (!p.valid) continue;
          block.lo = block.lo.cwiseMin(p.lo);
          block.hi = block.hi.cwiseMax(p.hi);
        }
        chunk.lo = chunk.lo.cwiseMin(block.lo);
        chunk.hi = chunk.hi.cwiseMax(block.hi);
      }
      if (chunk.lo.allFinite() && chunk.hi.allFinite()) chunks.push_back(chunk);
      else blocks.resize(chunk.first_block);
    }
    u0 += n;
  }

  // Only pairs closer than `reach` can limit a margin: farther ones clamp to max_margin_m. So
  // pairs whose boxes are farther apart than that are skipped without changing any margin; the
  // others are measured nearest box first, and skipped once their box is farther than the
  // smallest distance so far (a chunk's box bounds its capsules', which bound the capsules). An
  // obstacle's search ends once its margin is 0.
  const double reach = options.max_margin_m + options.slack_m;
  const ChunkGrid grid(chunks, kCellM);
  std::vector<int> visited(chunks.size(), -1);      // obstacle index that last listed it
  std::vector<char> ignored(motions.size(), 0);
  std::vector<int> ignored_list;
  std::vector<char> group_ignored(groups.size(), 0);
  std::vector<std::pair<double, int>> near;  // (squared box distance, chunk) of one obstacle
  std::vector<double> vine_margins;
  // The motions that ignore each cane, and the groups that hold each motion: an obstacle visits
  // only those (the same flags as testing every motion and group).
  std::unordered_map<int64_t, std::vector<int>> motions_ignoring;
  for (size_t m = 0; m < motions.size(); ++m)
    if (motions[m].ignored_cane.value != 0)
      motions_ignoring[motions[m].ignored_cane.value].push_back(static_cast<int>(m));
  std::vector<std::vector<int>> groups_of(motions.size());
  for (size_t g = 1; g < groups.size(); ++g)
    for (int m : groups[g]) groups_of[m].push_back(static_cast<int>(g));
  std::vector<int> groups_set;  // groups whose group_ignored is 1
  for (size_t oi = 0; oi < scene->obstacles.size(); ++oi) {
    Obstacle& o = scene->obstacles[oi];
    for (int m : ignored_list) ignored[m] = 0;
    ignored_list.clear();
    for (int g : groups_set) group_ignored[g] = 0;
    groups_set.clear();
    if (o.kind == ObstacleKind::kCane) {
      const auto it = motions_ignoring.find(o.owner_id);
      if (it != motions_ignoring.end()) {
        for (int m : it->second) {
          if (Ignored(o, motions[m])) {
            ignored[m] = 1;
            ignored_list.push_back(m);
          }
        }
      }
    }
    // A group is ignored when every motion in it is; only groups of an ignoring motion can be.
    for (int m : ignored_list) {
      for (int g : groups_of[m]) {
        if (group_ignored[g]) continue;
        bool all = true;
        for (int other : groups[g]) all = all && ignored[other];
        if (!all) continue;
        group_ignored[g] = 1;
        groups_set.push_back(g);
      }
    }
    const Eigen::Vector3d o_lo = o.capsule.a.cwiseMin(o.capsule.b).array() - o.capsule.radius;
    const Eigen::Vector3d o_hi = o.capsule.a.cwiseMax(o.capsule.b).array() + o.capsule.radius;
    const Eigen::Vector3d o_mid = 0.5 * (o.capsule.a + o.capsule.b);
    const double o_half = 0.5 * (o.capsule.b - o.capsule.a).norm();
    const Eigen::Vector3d lo = o_lo.array() - reach;
    const Eigen::Vector3d hi = o_hi.array() + reach;
    const int stamp = static_cast<int>(oi);
    near.clear();
    grid.ForEachNear(lo, hi, [&](int i) {
      if (visited[i] == stamp) return;
      visited[i] = stamp;
      const Chunk& c = chunks[i];
      if (group_ignored[c.motion]) return;
      if ((c.lo.array() > hi.array()).any() || (c.hi.array() < lo.array()).any()) return;
      near.emplace_back(BoxDistanceSquared(c.lo, c.hi, o_lo, o_hi), i);
    });
    std::sort(near.begin(), near.end());
    double clearance = std::numeric_limits<double>::infinity();
    // A pair farther than `reach` leaves the margin at its maximum: the search is capped there
    // (a micrometre beyond, so that the rounding of clearance - slack_m cannot matter).
    double cap = reach + kReachSlackM;
    for (const auto& [bound, i] : near) {
      if (Beyond(bound, cap + kBoundSlackM)) break;
      const Chunk& c = chunks[i];
      for (int j = 0; j < c.count; ++j) {
        if (j % kBlockConfigurations == 0) {
          // A block whose box is beyond the cap holds no nearer capsule (invalid capsules left
          // its box empty, so it is skipped).
          const Block& b = blocks[c.first_block + j / kBlockConfigurations];
          if ((b.lo.array() > hi.array()).any() || (b.hi.array() < lo.array()).any() ||
              Beyond(BoxDistanceSquared(b.lo, b.hi, o_lo, o_hi), cap + kBoundSlackM)) {
            j += kBlockConfigurations - 1;
            continue;
          }
        }
        const PlacedCapsule& p = placed[static_cast<size_t>(c.capsule) * distinct + c.first + j];
        if (!p.valid) continue;
        if ((p.lo.array() > hi.array()).any() || (p.hi.array() < lo.array()).any()) continue;
        if (Beyond(BoxDistanceSquared(p.lo, p.hi, o_lo, o_hi), cap + kBoundSlackM)) continue;
        // Distance is 1-Lipschitz: no point of the obstacle's axis is nearer the capsule's
        // than its midpoint's distance less half its length (tight for the short chords of
        // canes, which are most obstacles).
        if (Beyond(PointSegmentDistanceSquared(o_mid, p.a, p.b),
                   cap + kBoundSlackM + o_half + p.radius + o.capsule.radius))
          continue;
        const double d = SegmentSegmentDistance(p.a, p.b, o.capsule.a, o.capsule.b) - p.radius -
                         o.capsule.radius;
        clearance = std::min(clearance, d);
        cap = std::min(cap, clearance);
      }
      if (clearance <= options.slack_m) break;  // margin 0 already: nothing can lower it
    }
    o.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
    if (o.kind != ObstacleKind::kPlatform) vine_margins.push_back(o.margin_m);
  }
  // Planes: a chunk's box bounds its capsules' distances from below (offset less the box's
  // support along the unit normal, which contains a + r n and b + r n), so a chunk whose bound
  // exceeds the smallest distance so far, or the reach, holds none that could lower the margin.
  for (HalfSpace& plane : scene->planes) {
    double clearance = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d& n = plane.normal;
    for (const Chunk& c : chunks) {
      double support = 0.0;
      for (int k = 0; k < 3; ++k) support += std::max(n[k] * c.lo[k], n[k] * c.hi[k]);
      if (plane.offset - support > std::min(clearance, reach + kReachSlackM) + kBoundSlackM)
        continue;
      for (int j = 0; j < c.count; ++j) {
        const PlacedCapsule& p = placed[static_cast<size_t>(c.capsule) * distinct + c.first + j];
        if (!p.valid) continue;
        const double d =
            plane.offset - std::max(n.dot(p.a), n.dot(p.b)) - p.radius;
        clearance = std::min(clearance, d);
      }
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
