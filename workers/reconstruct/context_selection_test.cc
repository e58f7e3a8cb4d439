// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/context_selection.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/gibbs.h"

namespace vb::reconstruct {
namespace {

using Curve = std::vector<Eigen::Vector3d>;

// A straight curve from a to b with a vertex every ~5 cm.
Curve Line(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.05)));
  Curve c;
  for (int k = 0; k <= n; ++k) c.push_back(a + (b - a) * (static_cast<double>(k) / n));
  return c;
}

ContextSelectionOptions On() {
  ContextSelectionOptions options;
  options.enabled = true;
  options.alpha = 9.0;  // lower threshold 0.1 (the scene's selection alpha 3.5: 0.222)
  return options;
}

// The scene: kept cane piece 0 along x from 0 to 0.3 m, and below-threshold candidates (P 0.15,
// between 1 / (1 + 9) and 1 / (1 + 3.5)) around it.
struct Scene {
  std::vector<Curve> curves;
  std::vector<double> marginals;
  std::vector<std::vector<int>> conflicts;
  std::vector<int> kept;
  int Add(const Curve& c, double p) {
    curves.push_back(c);
    marginals.push_back(p);
    conflicts.emplace_back();
    return static_cast<int>(curves.size()) - 1;
  }
  void Conflict(int i, int j) {
    conflicts[i].push_back(j);
    conflicts[j].push_back(i);
  }
};

Scene KeptCane() {
  Scene s;
  s.Add(Line({0, 0, 0}, {0.3, 0, 0}), 0.9);
  s.kept = SelectMinimumExpectedLoss(s.marginals, 3.5);
  return s;
}

TEST(SelectInContext, AddsACandidateContinuingAKeptPieceButNotAFloatingOne) {
  Scene s = KeptCane();
  // Continues the kept piece past its end, 8 mm off its line, bending by ~11 degrees.
  const int continuing = s.Add(Line({0.305, 0.008, 0}, {0.5, 0.045, 0}), 0.15);
  // The same shape 10 cm away: nothing kept near it.
  const int floating = s.Add(Line({0.305, 0.1, 0}, {0.5, 0.137, 0}), 0.15);
  ASSERT_EQ(s.kept, std::vector<int>({0}));
  EXPECT_EQ(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, On()),
            std::vector<int>({continuing}));
  (void)floating;
  // Off: nothing is added.
  EXPECT_TRUE(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, {}).empty());
}

TEST(SelectInContext, AttachesAtEitherEndInEitherSense) {
  Scene s = KeptCane();
  // Ends at the kept piece's start, running toward it (its back end attaches).
  const int before = s.Add(Line({-0.2, 0, 0.01}, {-0.004, 0, 0.004}), 0.15);
  // Starts inside the kept piece's span (overlapping its last 2 cm) and runs on.
  const int overlapping = s.Add(Line({0.28, 0, -0.005}, {0.45, 0, -0.01}), 0.15);
  EXPECT_EQ(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, On()),
            std::vector<int>({before, overlapping}));
}

TEST(SelectInContext, RejectsCrossingDoublingConflictingAndTooUnlikelyCandidates) {
  Scene s = KeptCane();
  // Starts on the kept piece but leaves it at right angles (a crossing ghost).
  s.Add(Line({0.15, 0.005, 0}, {0.15, 0.2, 0}), 0.15);
  // Lies along the kept piece 5 mm from it: it adds no cane.
  s.Add(Line({0.02, 0, 0.005}, {0.29, 0, 0.005}), 0.15);
  // Continues it but conflicts with it (one-to-one).
  const int conflicting = s.Add(Line({0.305, 0, 0}, {0.5, 0, 0}), 0.15);
  s.Conflict(0, conflicting);
  // Continues it but below the lower threshold 0.1.
  s.Add(Line({-0.2, 0, 0}, {-0.005, 0, 0}), 0.08);
  // Ends 3 cm from it, in line: beyond max_gap_m.
  s.Add(Line({0.33, 0, 0}, {0.5, 0, 0}), 0.15);
  EXPECT_TRUE(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, On()).empty());
  // A looser rule takes the crossing (min_cos 0) and the one 3 cm off (max_gap_m 4 cm).
  ContextSelectionOptions loose = On();
  loose.min_cos = 0.0;
  EXPECT_EQ(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, loose),
            std::vector<int>({1}));
  loose = On();
  loose.max_gap_m = 0.04;
  EXPECT_EQ(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, loose),
            std::vector<int>({5}));
}

TEST(SelectInContext, TwoConflictingContinuationsKeepTheLikelierAndAddedOnesAttachNothing) {
  Scene s = KeptCane();
  const int weaker = s.Add(Line({0.305, 0, 0}, {0.5, 0.01, 0}), 0.12);
  const int stronger = s.Add(Line({0.305, 0, 0.003}, {0.5, 0, 0.02}), 0.2);
  s.Conflict(weaker, stronger);
  // Would continue `stronger` only: added candidates do not attach others.
  s.Add(Line({0.505, 0, 0.02}, {0.7, 0, 0.04}), 0.15);
  EXPECT_EQ(SelectInContext(s.curves, s.marginals, s.conflicts, s.kept, On()),
            std::vector<int>({stronger}));
}

TEST(ContextSelectionOptions, RejectsBadValuesNamingTheField) {
  EXPECT_TRUE(ContextSelectionOptions{}.Validate().ok());
  auto message = [](auto edit) {
    ContextSelectionOptions o;
    edit(o);
    const absl::Status s = o.Validate();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    return std::string(s.message());
  };
  EXPECT_NE(message([](auto& o) { o.alpha = 0; }).find("context.alpha"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.alpha = NAN; }).find("context.alpha"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.max_gap_m = -1; }).find("context.max_gap_m"),
            std::string::npos);
  EXPECT_NE(message([](auto& o) { o.min_cos = 1.5; }).find("context.min_cos"), std::string::npos);
  EXPECT_NE(message([](auto& o) { o.min_new_fraction = NAN; }).find("context.min_new_fraction"),
            std::string::npos);
  // In the correspondence options: the context's alpha below the selection's, when enabled.
  CorrespondenceOptions options;
  options.volume.box = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 2));
  ASSERT_TRUE(options.Validate().ok()) << options.Validate();
  options.context.alpha = 3.0;
  EXPECT_TRUE(options.Validate().ok());  // off: not checked
  options.context.enabled = true;
  EXPECT_NE(options.Validate().message().find("context.alpha"), std::string::npos);
  options.context.alpha = 9.0;
  options.context.min_cos = -0.1;
  EXPECT_NE(options.Validate().message().find("context.min_cos"), std::string::npos);
}

}  // namespace
}  // namespace vb::reconstruct
