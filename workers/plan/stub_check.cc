// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/stub_check.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

namespace vb::plan {
namespace {

// b is a with joint 6 turned by `turn` (+pi or -pi).
bool TwinConfiguration(const Joints& a, const Joints& b, double turn) {
  for (int j = 0; j < 5; ++j)
    if (a[j] != b[j]) return false;
  return std::abs(b[5] - a[5] - turn) <= 1e-9;
}

// Whether every configuration of `path` is free and every motion between consecutive ones is;
// a mirrored path's second half (its first half reversed) is not checked again.
bool PathFree(CollisionChecker& checker, double max_step_m, const std::vector<Joints>& path) {
  if (path.empty() || !checker.IsFree(path.front())) return false;
  const size_t end = IsMirroredPath(path) ? path.size() / 2 + 1 : path.size();
  for (size_t i = 1; i < end; ++i)
    if (!checker.IsMotionFree(path[i - 1], path[i], max_step_m)) return false;
  return true;
}

}  // namespace

bool IsHalfTurnTwin(const std::vector<Joints>& a, const std::vector<Joints>& b) {
  if (a.size() != b.size() || a.empty()) return false;
  bool same_order = true, reversed = true;
  const size_t n = a.size();
  // One turn for the whole path: +pi at one configuration and -pi at the next would be a
  // different motion (an extra wrist turn between them).
  const double turn_same = b[0][5] > a[0][5] ? M_PI : -M_PI;
  const double turn_reversed = b[n - 1][5] > a[0][5] ? M_PI : -M_PI;
  for (size_t i = 0; i < n && (same_order || reversed); ++i) {
    same_order = same_order && TwinConfiguration(a[i], b[i], turn_same);
    reversed = reversed && TwinConfiguration(a[i], b[n - 1 - i], turn_reversed);
  }
  return same_order || reversed;
}

bool IsMirroredPath(const std::vector<Joints>& path) {
  if (path.size() < 3 || path.size() % 2 == 0) return false;
  const size_t c = path.size() / 2;
  for (size_t j = 1; j <= c; ++j)
    if (path[c + j] != path[c - j]) return false;
  return true;
}

bool KeepMotionsFreeOfStubs(CollisionChecker& checker, double max_step_m, bool share_twins,
                            CutMotion* motion) {
  std::vector<const std::vector<Joints>*> motions = {&motion->path};
  for (const std::vector<Joints>& alternative : motion->alternatives)
    motions.push_back(&alternative);
  std::vector<bool> free(motions.size());
  for (size_t m = 0; m < motions.size(); ++m) {
    size_t twin = m;
    if (share_twins) {
      for (size_t e = 0; e < m && twin == m; ++e)
        if (IsHalfTurnTwin(*motions[e], *motions[m])) twin = e;
    }
    free[m] = twin < m ? free[twin] : PathFree(checker, max_step_m, *motions[m]);
  }
  if (std::all_of(free.begin(), free.end(), [](bool f) { return f; })) return true;
  std::vector<std::vector<Joints>> kept;
  if (free[0]) kept.push_back(std::move(motion->path));
  for (size_t a = 0; a < motion->alternatives.size(); ++a)
    if (free[a + 1]) kept.push_back(std::move(motion->alternatives[a]));
  if (kept.empty()) return false;  // nothing was moved: `motion` is unchanged
  motion->path = std::move(kept.front());
  motion->alternatives.assign(std::make_move_iterator(kept.begin() + 1),
                              std::make_move_iterator(kept.end()));
  return true;
}

}  // namespace vb::plan
