// SPDX-License-Identifier: Apache-2.0
// RRT-Connect through OMPL for PathPlanner (rrt_connect.h): the adapters between OMPL's states
// and our joints and checker, a nearest-neighbour search over contiguous joint vectors, and one
// run rooted at every goal.
#include "workers/plan/rrt_connect.h"

#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "ompl/base/MotionValidator.h"
#include "ompl/base/ProblemDefinition.h"
#include "ompl/base/SpaceInformation.h"
#include "ompl/base/StateValidityChecker.h"
#include "ompl/base/goals/GoalState.h"
#include "ompl/base/spaces/RealVectorStateSpace.h"
#include "ompl/datastructures/NearestNeighbors.h"
#include "ompl/geometric/PathGeometric.h"
#include "ompl/geometric/planners/rrt/RRTConnect.h"
#include "ompl/util/Console.h"
#include "ompl/util/Exception.h"

namespace vb::plan {

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

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

}  // namespace

struct RrtConnect::Ompl {
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

RrtConnect::RrtConnect(std::unique_ptr<Ompl> ompl) : ompl_(std::move(ompl)) {}
RrtConnect::~RrtConnect() = default;

absl::StatusOr<std::unique_ptr<RrtConnect>> RrtConnect::Create(CollisionChecker& checker,
                                                               const JointLimits& limits,
                                                               double range_rad) {
  SilenceOmpl();
  try {
    auto ompl = std::make_unique<Ompl>();
    ompl->space = std::make_shared<ob::RealVectorStateSpace>(6);
    ob::RealVectorBounds bounds(6);
    for (int i = 0; i < 6; ++i) {
      bounds.setLow(i, limits.lower[i]);
      bounds.setHigh(i, limits.upper[i]);
    }
    ompl->space->setBounds(bounds);
    Ompl* raw = ompl.get();
    ompl->space->setStateSamplerAllocator([raw](const ob::StateSpace* space) -> ob::StateSamplerPtr {
      return std::make_shared<SeededSampler>(space, raw->seed);
    });
    ompl->si = std::make_shared<ob::SpaceInformation>(ompl->space);
    ompl->si->setStateValidityChecker(std::make_shared<Validity>(ompl->si, &checker));
    ompl->si->setMotionValidator(std::make_shared<Motion>(ompl->si, &checker, &raw->edge_step_m));
    ompl->si->setup();
    ompl->pdef = std::make_shared<ob::ProblemDefinition>(ompl->si);
    ompl->start = ompl->si->allocState();
    ompl->goal = ompl->si->allocState();
    ompl->planner = std::make_shared<TreeSizeRRTConnect>(ompl->si);
    if (range_rad > 0.0) ompl->planner->setRange(range_rad);
    ompl->planner->setProblemDefinition(ompl->pdef);
    ompl->planner->setNearestNeighbors<JointNearest>();  // also runs setup()
    return std::unique_ptr<RrtConnect>(new RrtConnect(std::move(ompl)));
  } catch (const std::exception& e) {
    return absl::InternalError(absl::StrCat("path planner: OMPL setup failed: ", e.what()));
  }
}

absl::StatusOr<RrtRun> RrtConnect::Run(
    const Joints& start, std::span<const Joints> goals, uint64_t seed, double edge_step_m,
    absl::FunctionRef<bool(size_t start_tree, size_t goal_tree)> stop) {
  Ompl& o = *ompl_;
  o.edge_step_m = edge_step_m;
  RrtRun run;
  try {
    o.planner->clear();  // drops both trees and the sampler (re-allocated, seeded, in solve)
    o.pdef->clearSolutionPaths();
    o.pdef->clearStartStates();
    // Reversed roles (rrt_connect.h): OMPL's start states are our goals.
    for (const Joints& goal : goals) {
      FromJoints(goal, o.goal);
      o.pdef->addStartState(o.goal);  // copied
    }
    FromJoints(start, o.start);
    auto goal_region = std::make_shared<ob::GoalState>(o.si);
    goal_region->setState(o.start);
    goal_region->setThreshold(1e-9);
    o.pdef->setGoal(goal_region);
    o.seed = OmplSeed(seed);
    const TreeSizeRRTConnect& rrt = *o.planner;
    const ob::PlannerTerminationCondition ptc(
        [&rrt, stop] { return stop(rrt.GoalTreeSize(), rrt.StartTreeSize()); });
    const ob::PlannerStatus status = o.planner->solve(ptc);
    run.status = status.asString();
    // Roles are reversed: OMPL's start tree is rooted at our goals.
    run.start_tree_states = rrt.GoalTreeSize();
    run.goal_tree_states = rrt.StartTreeSize();
    run.exact = status == ob::PlannerStatus::EXACT_SOLUTION && o.pdef->hasExactSolution();
    if (!run.exact) return run;
    const auto* path = o.pdef->getSolutionPath()->as<og::PathGeometric>();
    run.path.reserve(path->getStateCount());
    for (std::size_t k = path->getStateCount(); k-- > 0;) run.path.push_back(ToJoints(path->getState(k)));
  } catch (const std::exception& e) {  // ompl::Exception and allocation failures
    return absl::InternalError(absl::StrCat("OMPL: ", e.what()));
  }
  return run;
}

std::vector<Joints> RrtConnect::TreeStates(bool start_side) const {
  // Roles are reversed: OMPL's goal tree is rooted at our start.
  return ompl_->planner->TreeStates(/*start_tree=*/!start_side);
}

}  // namespace vb::plan
