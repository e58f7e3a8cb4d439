// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/path_planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "ompl/base/MotionValidator.h"
#include "ompl/datastructures/NearestNeighbors.h"
#include "ompl/base/ProblemDefinition.h"
#include "ompl/base/SpaceInformation.h"
#include "ompl/base/StateValidityChecker.h"
#include "ompl/base/goals/GoalState.h"
#include "ompl/base/spaces/RealVectorStateSpace.h"
#include "ompl/geometric/PathGeometric.h"
#include "ompl/geometric/planners/rrt/RRTConnect.h"
#include "ompl/util/Console.h"
#include "ompl/util/Exception.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

Joints ToJoints(const ob::State* state) {
  const double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
  Joints q;
  for (int i = 0; i < 6; ++i) q[i] = v[i];
  return q;
}

void FromJoints(const Joints& q, ob::State* state) {
  double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int i = 0; i < 6; ++i) v[i] = q[i];
}

// Uniform samples from our own generator, reseeded on every query: OMPL's default samplers draw
// their seeds from one process-wide sequence, so a plan would depend on every planner created
// before it.
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint_fast32_t seed)
      : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

class Validity : public ob::StateValidityChecker {
 public:
  Validity(const ob::SpaceInformationPtr& si, CollisionChecker* checker)
      : ob::StateValidityChecker(si), checker_(checker) {}
  bool isValid(const ob::State* state) const override { return checker_->IsFree(ToJoints(state)); }

 private:
  CollisionChecker* checker_;
};

class Motion : public ob::MotionValidator {
 public:
  // *max_step_m: the resolution of the running query's edge checks.
  Motion(const ob::SpaceInformationPtr& si, CollisionChecker* checker, const double* max_step_m)
      : ob::MotionValidator(si), checker_(checker), max_step_m_(max_step_m) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    const bool ok = checker_->IsMotionFree(ToJoints(s1), ToJoints(s2), *max_step_m_);
    ok ? ++valid_ : ++invalid_;
    return ok;
  }

  // RRT-Connect does not use this form; other OMPL planners do. The segment is split into
  // kPieces straight pieces checked in order, so `lastValid` is the end of the last free piece
  // (conservative: the true last valid point may lie further).
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    constexpr int kPieces = 16;
    const Joints a = ToJoints(s1), b = ToJoints(s2);
    Joints prev = a;
    for (int k = 1; k <= kPieces; ++k) {
      const Joints next = k == kPieces ? b : Joints(a + (b - a) * (double(k) / kPieces));
      if (!checker_->IsMotionFree(prev, next, *max_step_m_)) {
        last_valid.second = double(k - 1) / kPieces;
        if (last_valid.first != nullptr) FromJoints(prev, last_valid.first);
        ++invalid_;
        return false;
      }
      prev = next;
    }
    ++valid_;
    return true;
  }

 private:
  CollisionChecker* checker_;
  const double* max_step_m_;
};

// Linear nearest-neighbour search over a tree's joint vectors kept in one contiguous array:
// OMPL's NearestNeighborsLinear calls a std::function and the state space's virtual distance per
// element, through a pointer per state, which cost 10-15% of a path query on tuning seeds (perf).
// Same distances as RealVectorStateSpace::distance (same order of summation, then sqrt) and the
// same tie rule (the first of equal minima), so RRT-Connect grows exactly the same trees.
// T is a pointer to a motion whose `state` is a RealVectorStateSpace state of dimension 6.
template <typename T>
class JointNearest : public ompl::NearestNeighbors<T> {
 public:
  bool reportsSortedResults() const override { return true; }
  void clear() override {
    data_.clear();
    q_.clear();
  }
  void add(const T& data) override {
    data_.push_back(data);
    const double* v = data->state->template as<ob::RealVectorStateSpace::StateType>()->values;
    q_.insert(q_.end(), v, v + 6);
  }
  bool remove(const T& data) override {
    for (size_t i = data_.size(); i-- > 0;) {
      if (data_[i] != data) continue;
      data_.erase(data_.begin() + static_cast<std::ptrdiff_t>(i));
      q_.erase(q_.begin() + static_cast<std::ptrdiff_t>(6 * i),
               q_.begin() + static_cast<std::ptrdiff_t>(6 * i + 6));
      return true;
    }
    return false;
  }
  T nearest(const T& data) const override {
    if (data_.empty()) throw ompl::Exception("JointNearest: no elements");
    // Squared distances, with the square root taken only where one is smaller than the best so
    // far: the sqrt of a smaller square can round to the same distance, and then OMPL keeps the
    // earlier element, as this does.
    const double* x = Values(data);
    size_t pos = 0;
    double sq_min = SquaredDistance(0, x), d_min = std::sqrt(sq_min);
    for (size_t i = 1; i < data_.size(); ++i) {
      const double sq = SquaredDistance(i, x);
      if (sq >= sq_min) continue;
      const double d = std::sqrt(sq);
      if (d < d_min) pos = i, d_min = d;
      sq_min = sq;  // a tie keeps pos, and no later element beats d_min with sq >= this
    }
    return data_[pos];
  }
  void nearestK(const T& data, std::size_t k, std::vector<T>& nbh) const override {
    std::vector<std::pair<double, size_t>> d = Sorted(data, std::numeric_limits<double>::infinity());
    nbh.clear();
    for (size_t i = 0; i < d.size() && i < k; ++i) nbh.push_back(data_[d[i].second]);
  }
  void nearestR(const T& data, double radius, std::vector<T>& nbh) const override {
    nbh.clear();
    for (const auto& [dist, i] : Sorted(data, radius)) nbh.push_back(data_[i]);
  }
  std::size_t size() const override { return data_.size(); }
  void list(std::vector<T>& data) const override { data = data_; }

 private:
  static const double* Values(const T& data) {
    return data->state->template as<ob::RealVectorStateSpace::StateType>()->values;
  }
  double SquaredDistance(size_t i, const double* x) const {
    const double* a = &q_[6 * i];
    double sum = 0.0;
    for (int j = 0; j < 6; ++j) {
      const double diff = a[j] - x[j];
      sum += diff * diff;
    }
    return sum;
  }
  double Distance(size_t i, const double* x) const { return std::sqrt(SquaredDistance(i, x)); }
  std::vector<std::pair<double, size_t>> Sorted(const T& data, double radius) const {
    const double* x = Values(data);
    std::vector<std::pair<double, size_t>> d;
    for (size_t i = 0; i < data_.size(); ++i) {
      const double dist = Distance(i, x);
      if (dist <= radius) d.emplace_back(dist, i);
    }
    std::stable_sort(d.begin(), d.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    return d;
  }

  std::vector<T> data_;
  std::vector<double> q_;  // 6 joint values per element, in data_'s order
};

void SilenceOmpl() {
  static std::once_flag once;
  std::call_once(once, [] { ompl::msg::setLogLevel(ompl::msg::LOG_NONE); });
}

std::uint_fast32_t OmplSeed(uint64_t seed) {
  // Keep all 64 bits relevant; boost/std generators take 32-bit seeds.
  return static_cast<std::uint_fast32_t>((seed ^ (seed >> 32)) & 0xffffffffu);
}

bool NearlyEqual(const Joints& a, const Joints& b) { return (a - b).cwiseAbs().maxCoeff() < 1e-12; }

// Whether a -> b is a segment of `path` (consecutive waypoints, bit-exact): shortcutting keeps
// such segments as they are and checks every segment it makes.
bool IsTreeSegment(const std::vector<Joints>& path, const Joints& a, const Joints& b) {
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    if (path[k] == a && path[k + 1] == b) return true;
  }
  return false;
}

// Failed queries a planner remembers (PathOptions::remember_failures); later ones are not kept.
constexpr size_t kMaxRememberedFailures = 32;
// A configuration joins a remembered tree through one of its kJoinNearest nearest states within
// kJoinRange * range_rad (PathOptions::remember_failures).
constexpr int kJoinNearest = 8;
constexpr double kJoinRange = 3.0;

}  // namespace

absl::Status PathOptions::Validate() const {
  if (!(max_step_m > 0.0) || !std::isfinite(max_step_m)) {
    return absl::InvalidArgumentError("path options: max_step_m: must be finite and > 0");
  }
  if (!(tree_max_step_m >= 0.0) || !std::isfinite(tree_max_step_m)) {
    return absl::InvalidArgumentError("path options: tree_max_step_m: must be finite and >= 0");
  }
  if (!(range_rad >= 0.0) || !std::isfinite(range_rad)) {
    return absl::InvalidArgumentError("path options: range_rad: must be finite and >= 0");
  }
  if (!(time_limit_s > 0.0)) {
    return absl::InvalidArgumentError("path options: time_limit_s: must be > 0");
  }
  if (max_tree_states < 0) {
    return absl::InvalidArgumentError("path options: max_tree_states: must be >= 0");
  }
  if (flip_max_tree_states < 0) {
    return absl::InvalidArgumentError("path options: flip_max_tree_states: must be >= 0");
  }
  if (walled_in_after_states < 0) {
    return absl::InvalidArgumentError("path options: walled_in_after_states: must be >= 0");
  }
  if (!(walled_in_goal_fraction >= 0.0) || !(walled_in_goal_fraction < 1.0)) {
    return absl::InvalidArgumentError("path options: walled_in_goal_fraction: must be in [0, 1)");
  }
  if (shortcut_rounds < 0) {
    return absl::InvalidArgumentError("path options: shortcut_rounds: must be >= 0");
  }
  return absl::OkStatus();
}

std::string_view PathOutcomeName(PathOutcome outcome) {
  switch (outcome) {
    case PathOutcome::kSolved: return "solved";
    case PathOutcome::kStartInCollision: return "start_in_collision";
    case PathOutcome::kGoalInCollision: return "goal_in_collision";
    case PathOutcome::kOutsideLimits: return "outside_limits";
    case PathOutcome::kNoPathWithinDeadline: return "no_path_within_deadline";
    case PathOutcome::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

// RRT-Connect with its trees' sizes visible.
class TreeSizeRRTConnect : public og::RRTConnect {
 public:
  using og::RRTConnect::RRTConnect;
  size_t StartTreeSize() const { return tStart_ ? tStart_->size() : 0; }
  size_t GoalTreeSize() const { return tGoal_ ? tGoal_->size() : 0; }
  // The joint vectors of the start tree (start_tree) or the goal tree.
  std::vector<Joints> TreeStates(bool start_tree) const {
    std::vector<Joints> out;
    const TreeData& tree = start_tree ? tStart_ : tGoal_;
    if (!tree) return out;
    std::vector<Motion*> motions;
    tree->list(motions);
    out.reserve(motions.size());
    for (const Motion* m : motions) out.push_back(ToJoints(m->state));
    return out;
  }
};

struct PathPlanner::Ompl {
  std::shared_ptr<ob::RealVectorStateSpace> space;
  ob::SpaceInformationPtr si;
  ob::ProblemDefinitionPtr pdef;
  std::shared_ptr<TreeSizeRRTConnect> planner;
  std::uint_fast32_t seed = 1;  // read by the sampler allocator at every solve
  ob::State* start = nullptr;
  ob::State* goal = nullptr;
  double edge_step_m = 0.01;  // RRT-Connect's edge-check resolution in the running query

  ~Ompl() {
    if (si != nullptr) {
      if (start != nullptr) si->freeState(start);
      if (goal != nullptr) si->freeState(goal);
    }
  }
};

PathPlanner::PathPlanner(CollisionChecker& checker, const JointLimits& limits,
                         const PathOptions& options)
    : checker_(checker), limits_(limits), options_(options) {
  SilenceOmpl();
  setup_status_ = limits_.Validate();
  if (setup_status_.ok()) setup_status_ = options_.Validate();
  if (!setup_status_.ok()) return;
  try {
    auto ompl = std::make_unique<Ompl>();
    ompl->space = std::make_shared<ob::RealVectorStateSpace>(6);
    ob::RealVectorBounds bounds(6);
    for (int i = 0; i < 6; ++i) {
      bounds.setLow(i, limits_.lower[i]);
      bounds.setHigh(i, limits_.upper[i]);
    }
    ompl->space->setBounds(bounds);
    Ompl* raw = ompl.get();
    ompl->space->setStateSamplerAllocator([raw](const ob::StateSpace* space) -> ob::StateSamplerPtr {
      return std::make_shared<SeededSampler>(space, raw->seed);
    });
    ompl->si = std::make_shared<ob::SpaceInformation>(ompl->space);
    ompl->si->setStateValidityChecker(std::make_shared<Validity>(ompl->si, &checker_));
    ompl->edge_step_m = options_.max_step_m;
    ompl->si->setMotionValidator(std::make_shared<Motion>(ompl->si, &checker_, &raw->edge_step_m));
    ompl->si->setup();
    ompl->pdef = std::make_shared<ob::ProblemDefinition>(ompl->si);
    ompl->start = ompl->si->allocState();
    ompl->goal = ompl->si->allocState();
    ompl->planner = std::make_shared<TreeSizeRRTConnect>(ompl->si);
    if (options_.range_rad > 0.0) ompl->planner->setRange(options_.range_rad);
    ompl->planner->setProblemDefinition(ompl->pdef);
    ompl->planner->setNearestNeighbors<JointNearest>();  // also runs setup()
    ompl_ = std::move(ompl);
  } catch (const std::exception& e) {
    setup_status_ = absl::InternalError(absl::StrCat("path planner: OMPL setup failed: ", e.what()));
  }
}

PathPlanner::~PathPlanner() = default;

PathResult PathPlanner::Plan(const Joints& start, const Joints& goal, const Deadline& deadline) {
  return PlanToAny(start, std::span<const Joints>(&goal, 1), deadline);
}

PathResult PathPlanner::PlanToAny(const Joints& start, std::span<const Joints> goals,
                                  const Deadline& deadline, bool only_way) {
  const Clock::time_point t0 = Clock::now();
  const int64_t checks0 = checker_.checks();
  PathResult result;
  auto finish = [&](PathOutcome outcome, std::string message) {
    result.outcome = outcome;
    result.message = std::move(message);
    if (outcome != PathOutcome::kSolved) {
      result.waypoints.clear();
      result.goal_index = -1;
    }
    result.checks = checker_.checks() - checks0;
    result.planning_s = SecondsSince(t0);
    return result;
  };

  if (!setup_status_.ok()) return finish(PathOutcome::kInvalidInput, std::string(setup_status_.message()));
  if (goals.empty()) return finish(PathOutcome::kInvalidInput, "goals: empty");
  if (!start.allFinite()) return finish(PathOutcome::kInvalidInput, "start: non-finite joint value");
  for (size_t g = 0; g < goals.size(); ++g) {
    if (!goals[g].allFinite()) {
      return finish(PathOutcome::kInvalidInput,
                    goals.size() == 1 ? std::string("goal: non-finite joint value")
                                      : absl::StrCat("goals[", g, "]: non-finite joint value"));
    }
  }
  if (!limits_.Contains(start)) return finish(PathOutcome::kOutsideLimits, "start: outside the joint limits");
  // The goals that can be reached at all; the first goal's reason when none can.
  std::vector<int> usable;
  PathOutcome first_outcome = PathOutcome::kSolved;
  std::string first_message;
  for (size_t g = 0; g < goals.size(); ++g) {
    const std::string name = goals.size() == 1 ? "goal" : absl::StrCat("goals[", g, "]");
    if (!limits_.Contains(goals[g])) {
      if (g == 0) first_outcome = PathOutcome::kOutsideLimits, first_message = name + ": outside the joint limits";
      continue;
    }
    if (g == 0 && !checker_.IsFree(start)) {
      return finish(PathOutcome::kStartInCollision, "start: in collision");
    }
    if (!checker_.IsFree(goals[g])) {
      if (g == 0) first_outcome = PathOutcome::kGoalInCollision, first_message = name + ": in collision";
      continue;
    }
    usable.push_back(static_cast<int>(g));
  }
  if (usable.empty()) return finish(first_outcome, first_message);
  if (usable.front() != 0 && !checker_.IsFree(start)) {
    return finish(PathOutcome::kStartInCollision, "start: in collision");
  }

  for (int g : usable) {
    if (NearlyEqual(start, goals[g]) ||
        (options_.try_direct_first && checker_.IsMotionFree(start, goals[g], options_.max_step_m))) {
      result.waypoints = {start, goals[g]};
      result.direct = true;
      result.goal_index = g;
      return finish(PathOutcome::kSolved, "");
    }
  }
  if (deadline.Expired()) {
    return finish(PathOutcome::kNoPathWithinDeadline, "deadline expired before RRT-Connect");
  }
  // Elbow flips give up sooner (PathOptions::flip_max_tree_states) unless they are the only way.
  bool flip = !only_way && options_.flip_max_tree_states > 0 &&
              (options_.max_tree_states == 0 ||
               options_.flip_max_tree_states < options_.max_tree_states);
  for (int g : usable) flip = flip && (goals[g][2] > 0.0) != (start[2] > 0.0);
  const int bound = flip ? options_.flip_max_tree_states : options_.max_tree_states;
  const size_t max_states = bound > 0 ? static_cast<size_t>(bound) : SIZE_MAX;
  if (options_.remember_failures) {
    if (const int f = RepeatsFailure(start, goals, usable, max_states); f >= 0) {
      result.repeated_failure = true;
      return finish(PathOutcome::kNoPathWithinDeadline,
                    absl::StrCat("like failed query ", f, " of this planner: the start joins its "
                                 "start's tree and every goal its goals' tree (",
                                 failures_[f].start_side.size(), " and ",
                                 failures_[f].goal_side.size(), " states)"));
    }
  }

  const double budget_s = std::min(options_.time_limit_s, deadline.RemainingS());
  const Clock::time_point end =
      budget_s >= 1e9 ? Clock::time_point::max()
                      : Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(budget_s));
  // RRT-Connect checks its edges at tree_max_step_m; the path it returns is then checked at
  // max_step_m, and if that finds a collision the query runs again with the edges checked at
  // max_step_m (same seed, same bounds, within what is left of the time limit).
  Ompl& o = *ompl_;
  const double coarse_m = std::max(options_.tree_max_step_m, options_.max_step_m);
  for (const double edge_step_m : {coarse_m, options_.max_step_m}) {
    result.waypoints.clear();
    o.edge_step_m = edge_step_m;
    try {
      o.planner->clear();  // drops both trees and the sampler (re-allocated, seeded, in solve)
      o.pdef->clearSolutionPaths();
      o.pdef->clearStartStates();
      // Reversed roles: RRT-Connect roots its start tree at every start state before the first
      // iteration, but adds goal states one at a time as its goal tree grows, so a walled-in
      // first goal would hide the others. The path is reversed below.
      for (int g : usable) {
        FromJoints(goals[g], o.goal);
        o.pdef->addStartState(o.goal);  // copied
      }
      FromJoints(start, o.start);
      auto goal_region = std::make_shared<ob::GoalState>(o.si);
      goal_region->setState(o.start);
      goal_region->setThreshold(1e-9);
      o.pdef->setGoal(goal_region);
      o.seed = OmplSeed(options_.seed);
      const TreeSizeRRTConnect& rrt = *o.planner;
      // Goals walled in (PathOptions::walled_in_after_states). OMPL's start tree is rooted at our
      // goals.
      const size_t wall_after = options_.walled_in_after_states > 0
                                    ? static_cast<size_t>(options_.walled_in_after_states)
                                    : SIZE_MAX;
      const double wall_fraction = options_.walled_in_goal_fraction;
      bool walled_in = false;
      const ob::PlannerTerminationCondition ptc(
          [&end, &deadline, &rrt, max_states, wall_after, wall_fraction, &walled_in] {
            const size_t goal_side = rrt.StartTreeSize(), total = goal_side + rrt.GoalTreeSize();
            if (total >= wall_after && static_cast<double>(goal_side) <= wall_fraction * total) {
              walled_in = true;
            }
            return walled_in || total >= max_states || Clock::now() >= end ||
                   deadline.Cancelled();
          });
      const ob::PlannerStatus status = o.planner->solve(ptc);
      // Roles are reversed: OMPL's start tree is rooted at our goals.
      result.start_tree_states = static_cast<int>(rrt.GoalTreeSize());
      result.goal_tree_states = static_cast<int>(rrt.StartTreeSize());
      if (status != ob::PlannerStatus::EXACT_SOLUTION || !o.pdef->hasExactSolution()) {
        // Only a query stopped by the bound on states is remembered: one stopped by time says
        // nothing reproducible. Roles are reversed: OMPL's start tree is rooted at our goals.
        if (options_.remember_failures && failures_.size() < kMaxRememberedFailures &&
            (walled_in || rrt.StartTreeSize() + rrt.GoalTreeSize() >= max_states)) {
          // A walled-in query ends whatever its bound; one stopped by the bound refuses only
          // queries allowed no more states (a flip's failure does not refuse the way home).
          failures_.push_back(
              {rrt.TreeStates(false), rrt.TreeStates(true), walled_in ? SIZE_MAX : max_states});
        }
        result.flip_bound = flip && !walled_in && rrt.StartTreeSize() + rrt.GoalTreeSize() >= max_states;
        if (walled_in) {
          result.walled_in = true;
          return finish(PathOutcome::kNoPathWithinDeadline,
                        absl::StrCat("goals walled in: their tree holds ", rrt.StartTreeSize(),
                                     " of the ", rrt.StartTreeSize() + rrt.GoalTreeSize(),
                                     " states of both (walled_in_goal_fraction ", wall_fraction,
                                     ")"));
        }
        return finish(PathOutcome::kNoPathWithinDeadline,
                      absl::StrCat("RRT-Connect found no exact path within ", budget_s,
                                   " s (", status.asString(), ")"));
      }
      const auto* path = o.pdef->getSolutionPath()->as<og::PathGeometric>();
      for (std::size_t k = path->getStateCount(); k-- > 0;) {
        const Joints q = ToJoints(path->getState(k));
        if (result.waypoints.empty() || !NearlyEqual(result.waypoints.back(), q)) {
          result.waypoints.push_back(q);
        }
      }
    } catch (const std::exception& e) {  // ompl::Exception and allocation failures
      return finish(PathOutcome::kNoPathWithinDeadline, absl::StrCat("OMPL: ", e.what()));
    }
    if (result.waypoints.size() < 2) {
      return finish(PathOutcome::kNoPathWithinDeadline, "RRT-Connect returned a degenerate path");
    }
    // The path ends at a copy of one of the goals: find which (the nearest; copies are exact),
    // and make the ends bit-exact so callers can chain paths.
    double best = std::numeric_limits<double>::infinity();
    for (int g : usable) {
      const double d = (goals[g] - result.waypoints.back()).cwiseAbs().maxCoeff();
      if (d < best) best = d, result.goal_index = g;
    }
    if (best > 1e-9) {
      return finish(PathOutcome::kNoPathWithinDeadline, "RRT-Connect's path ends at no goal");
    }
    result.waypoints.front() = start;
    result.waypoints.back() = goals[result.goal_index];
    // Shortcut first: every segment shortcutting makes is checked at max_step_m, so only the
    // tree's own segments that remain need the check at max_step_m (most are shortcut away).
    const std::vector<Joints> tree_path =
        edge_step_m > options_.max_step_m ? result.waypoints : std::vector<Joints>();
    ShortcutPath(checker_, limits_, options_.max_step_m, options_.shortcut_rounds, options_.seed,
                 deadline, result.waypoints);
    if (edge_step_m <= options_.max_step_m) break;  // every edge was checked at max_step_m
    bool fine = true;
    for (size_t k = 0; fine && k + 1 < result.waypoints.size(); ++k) {
      if (IsTreeSegment(tree_path, result.waypoints[k], result.waypoints[k + 1])) {
        fine = checker_.IsMotionFree(result.waypoints[k], result.waypoints[k + 1],
                                     options_.max_step_m);
      }
    }
    if (fine) break;
    ++result.coarse_rejections;
    if (deadline.Expired() || Clock::now() >= end) {
      return finish(PathOutcome::kNoPathWithinDeadline,
                    "RRT-Connect's path collided at max_step_m and no time was left to replan");
    }
  }
  return finish(PathOutcome::kSolved, "");
}

bool PathPlanner::Joins(const Joints& q, const std::vector<Joints>& tree) {
  // The kJoinNearest nearest states (squared distances); a state equal to q (up to rounding:
  // a goal shifted by whole turns again) joins at once.
  constexpr int kNearest = kJoinNearest;
  std::pair<double, int> best[kNearest];
  for (auto& b : best) b = {std::numeric_limits<double>::infinity(), -1};
  for (size_t i = 0; i < tree.size(); ++i) {
    const double d = (tree[i] - q).squaredNorm();
    if (d < 1e-18) return true;
    if (d < best[kNearest - 1].first) {
      best[kNearest - 1] = {d, static_cast<int>(i)};
      for (int k = kNearest - 1; k > 0 && best[k].first < best[k - 1].first; --k)
        std::swap(best[k], best[k - 1]);
    }
  }
  const double range = options_.range_rad > 0.0 ? options_.range_rad
                                                : std::numeric_limits<double>::infinity();
  const double step_m = std::max(options_.tree_max_step_m, options_.max_step_m);
  for (const auto& [d, i] : best) {
    if (i < 0 || std::sqrt(d) > kJoinRange * range) continue;
    if (checker_.IsMotionFree(q, tree[i], step_m)) return true;
  }
  return false;
}

int PathPlanner::RepeatsFailure(const Joints& start, std::span<const Joints> goals,
                                const std::vector<int>& usable, size_t max_states) {
  for (size_t f = 0; f < failures_.size(); ++f) {
    const FailedQuery& failed = failures_[f];
    if (failed.max_states < max_states) continue;  // this query may grow larger trees
    // Goals first: they repeat exactly when a cut is tried again from another start.
    bool all = true;
    for (int g : usable) {
      if (!Joins(goals[g], failed.goal_side)) {
        all = false;
        break;
      }
    }
    if (all && Joins(start, failed.start_side)) return static_cast<int>(f);
  }
  return -1;
}

PathResult PlanPath(CollisionChecker& checker, const JointLimits& limits, const Joints& start,
                    const Joints& goal, const PathOptions& options, const Deadline& deadline) {
  const Clock::time_point t0 = Clock::now();
  PathPlanner planner(checker, limits, options);
  PathResult result = planner.Plan(start, goal, deadline);
  result.planning_s = SecondsSince(t0);
  return result;
}

namespace {

// Removes waypoints greedily: from each kept waypoint, jump to the farthest later one whose
// straight segment is free and faster than the waypoints it skips. Returns shortcuts taken.
int GreedySkip(CollisionChecker& checker, const JointLimits& limits, double max_step_m,
               const Deadline& deadline, std::vector<Joints>& w) {
  int taken = 0;
  for (size_t i = 0; i + 2 < w.size(); ++i) {
    for (size_t j = w.size() - 1; j >= i + 2; --j) {
      if (deadline.Expired()) return taken;
      const double via = PathTimeS(std::span<const Joints>(w).subspan(i, j - i + 1), limits);
      if (MoveTimeS(w[i], w[j], limits) >= via) continue;
      if (checker.IsMotionFree(w[i], w[j], max_step_m)) {
        w.erase(w.begin() + static_cast<std::ptrdiff_t>(i) + 1, w.begin() + static_cast<std::ptrdiff_t>(j));
        ++taken;
        break;
      }
    }
  }
  return taken;
}

}  // namespace

int ShortcutPath(CollisionChecker& checker, const JointLimits& limits, double max_step_m,
                 int rounds, uint64_t seed, const Deadline& deadline,
                 std::vector<Joints>& waypoints) {
  std::vector<Joints>& w = waypoints;
  if (w.size() < 3) return 0;
  int taken = GreedySkip(checker, limits, max_step_m, deadline, w);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Per path: cumulative joint-space length at each waypoint and the time of each segment;
  // recomputed only when a shortcut is taken, so a rejected round costs a few MoveTimeS.
  std::vector<double> cumulative, seg_time;
  double path_time = 0.0;
  auto measure = [&] {
    cumulative.assign(w.size(), 0.0);
    seg_time.assign(w.size() - 1, 0.0);
    path_time = 0.0;
    for (size_t k = 1; k < w.size(); ++k) {
      cumulative[k] = cumulative[k - 1] + (w[k] - w[k - 1]).norm();
      seg_time[k - 1] = MoveTimeS(w[k - 1], w[k], limits);
      path_time += seg_time[k - 1];
    }
  };
  measure();
  std::vector<Joints> candidate;
  for (int round = 0; round < rounds && w.size() >= 3; ++round) {
    if (deadline.Expired()) break;
    // Two points drawn uniformly by joint-space length along the path; the segment between
    // them replaces what lies between (OMPL's PathSimplifier::shortcutPath does the same).
    const double length = cumulative.back();
    double u = unit(rng) * length, v = unit(rng) * length;
    if (u > v) std::swap(u, v);
    auto locate = [&](double s, size_t& seg, Joints& q) {
      seg = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), s) -
                                cumulative.begin());
      seg = std::clamp<size_t>(seg, 1, w.size() - 1) - 1;  // segment seg: w[seg] -> w[seg + 1]
      const double len = cumulative[seg + 1] - cumulative[seg];
      const double f = len > 0 ? std::clamp((s - cumulative[seg]) / len, 0.0, 1.0) : 0.0;
      q = w[seg] + f * (w[seg + 1] - w[seg]);
    };
    size_t i = 0, j = 0;
    Joints qu, qv;
    locate(u, i, qu);
    locate(v, j, qv);
    if (i == j) continue;  // both on one straight segment: nothing to gain
    // Time of w[0..i], qu, qv, w[j+1..]: the segments i..j are replaced by three.
    double replaced = 0.0;
    for (size_t k = i; k <= j; ++k) replaced += seg_time[k];
    const double joined = MoveTimeS(w[i], qu, limits) + MoveTimeS(qu, qv, limits) +
                          MoveTimeS(qv, w[j + 1], limits);
    if (joined >= replaced - 1e-9) continue;
    // The new joining segment first (it is the one likely to fail), then the two remnants of
    // old segments: sub-segments of checked segments, but sampled at other points, so they are
    // checked again to keep the contract that every output segment passed IsMotionFree.
    if (!checker.IsMotionFree(qu, qv, max_step_m)) continue;
    if (!checker.IsMotionFree(w[i], qu, max_step_m)) continue;
    if (!checker.IsMotionFree(qv, w[j + 1], max_step_m)) continue;
    candidate.assign(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(i) + 1);
    for (const Joints* q : {&qu, &qv}) {
      if (!NearlyEqual(candidate.back(), *q)) candidate.push_back(*q);
    }
    for (size_t k = j + 1; k < w.size(); ++k) {
      if (!NearlyEqual(candidate.back(), w[k])) candidate.push_back(w[k]);
    }
    w.swap(candidate);
    measure();
    ++taken;
  }
  taken += GreedySkip(checker, limits, max_step_m, deadline, w);
  return taken;
}

}  // namespace vb::plan
