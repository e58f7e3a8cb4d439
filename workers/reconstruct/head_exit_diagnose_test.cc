// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: the canes of this vine near the head, and what connection
// (connect.h) hangs them on, on rendered stops as the bench renders them (fiducials included) and
// run through the pipeline's stages before connection as ReconstructFromViews runs them
// (assembly, growth, head and trunk). Per prepared cane of this vine (its majority true cane, not
// the trunk), by its true parent (the head, i.e. the trunk in the truth, or another cane):
//  - its inner end: the end nearer the model head's spheres, and how far that end lies from their
//    surface (signed; bins);
//  - what the tree hangs it on: directly on the trunk or head, on a route of the right canes
//    (its own earlier piece, its true parent), on a wrong cane or a ghost, or left out;
//  - whether its inner end points at the head (the cosine between the outward tangent there and
//    the direction to the nearest point of the head's surface) and whether the images show wood
//    along that straight line (GapSupport), i.e. what a head-exit rule would see.
// Prints one table per class of true parent, in metres of prepared cane, for the tree as
// configured and for a variant with step 6c (head exits) on, with the refined metrics of each;
// with VB_VERBOSE=1 one line per cane within VB_NEAR_M (0.3 m) of the head.
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=20 [VB_VERBOSE=1] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='HeadExit.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/connect_internal.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/join_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

enum Outcome { kRoot, kRightRoute, kWrongCane, kGhost, kLeftOut, kOutcomeCount };
const char* kOutcomeNames[kOutcomeCount] = {"on root", "right route", "wrong cane", "on ghost",
                                            "left out"};
constexpr int kBins = 6;
const double kBinUpper[kBins] = {0.0, 0.05, 0.15, 0.30, 0.50, 1e9};
const char* kBinNames[kBins] = {"inside", "0-5 cm", "5-15 cm", "15-30 cm", "30-50 cm", ">50 cm"};

int BinOf(double d) {
  for (int b = 0; b < kBins; ++b)
    if (d < kBinUpper[b]) return b;
  return kBins - 1;
}

struct Table {
  double length[kBins][kOutcomeCount] = {};
  double pointing[kBins][kOutcomeCount] = {};  // of those, inner end points at a seen head
};

void PrintTable(const char* title, const Table& t) {
  std::printf("%s (m of prepared cane; in brackets: inner end pointing at the head, cos >= 0.7, "
              "straight line to it >= 90%% wood)\n", title);
  std::printf("  %-9s", "inner end");
  for (int o = 0; o < kOutcomeCount; ++o) std::printf(" | %-18s", kOutcomeNames[o]);
  std::printf("\n");
  for (int b = 0; b < kBins; ++b) {
    std::printf("  %-9s", kBinNames[b]);
    for (int o = 0; o < kOutcomeCount; ++o)
      std::printf(" | %7.2f (%7.2f) ", t.length[b][o], t.pointing[b][o]);
    std::printf("\n");
  }
}

// One tree's account of the canes near the head (see the file comment).
struct Account {
  Table head_canes, cane_canes;
  double recall = 0, precision = 0, connectivity = 0;  // refined, means over stops
  int head_exits = 0;
};

// Adds one stop's tree (BuildTree with `connect`) to `account`; verbose lines within near_m.
void AccountForTree(uint64_t seed, int count, const std::vector<View2D>& views,
                    const RigCalibration& rig, const VineModel& truth,
                    const HeadAndTrunk& head, const PreparedCanes& prepared,
                    const std::vector<JoinCandidate>& joins, const ReconstructOptions& options,
                    const ConnectOptions& connect, bool verbose, double near_m,
                    Account* account) {
  const Deadline deadline = Deadline::Infinite();
  const GapSupportFn gap_support = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return GapSupport(a, b, views, rig);
  };
  ConnectSummary summary;
  const auto model = BuildTree(prepared, joins, head.head, connect, &summary, gap_support);
  ASSERT_TRUE(model.ok());
  account->head_exits += summary.head_exits;
  {
    VineModel refined = *model;
    ASSERT_TRUE(RefineModel(&refined, views, rig, options.fit, deadline).ok());
    const auto m = EvaluateReconstruction(refined, truth).value();
    account->recall += m.cane_recall / count;
    account->precision += m.cane_precision / count;
    account->connectivity += m.connectivity / count;
  }
  if (head.head.spheres.empty() || !prepared.trunk) return;
  std::vector<int> majority;
  for (const Cane& m : model->canes) majority.push_back(MajorityCane(m.polyline, truth));
  for (size_t i = 0; i < prepared.canes.size(); ++i) {
    const Polyline3& c = prepared.canes[i];
    const int g = MajorityCane(c, truth);
    if (g <= 0) continue;
    const int tp = TrueParent(truth, g);
    std::vector<int> ancestry = {g};
    for (int a = tp; a >= 0 && ancestry.size() <= truth.canes.size(); a = TrueParent(truth, a))
      ancestry.push_back(a);
    // The inner end: nearer the head's surface.
    Eigen::Vector3d at_front, at_back;
    const double d_front =
        connect_internal::DistanceToHead(c.points.front(), head.head, &at_front);
    const double d_back = connect_internal::DistanceToHead(c.points.back(), head.head, &at_back);
    const bool inner_last = d_back < d_front;
    const Eigen::Vector3d inner = inner_last ? c.points.back() : c.points.front();
    const Eigen::Vector3d at = inner_last ? at_back : at_front;
    const double d = std::min(d_front, d_back);
    const Eigen::Vector3d out = connect_internal::EndOutward(c, inner_last);
    const Eigen::Vector3d to_head = at - inner;
    const double cos = d <= 0.0 || to_head.norm() < 1e-9 ? 1.0 : out.dot(to_head.normalized());
    const double support = d <= 0.0 ? 1.0 : gap_support(inner, at);
    const bool pointing = cos >= 0.7 && support >= 0.9;
    // What the tree hangs it on.
    int owner = -1;
    for (size_t m = 1; m < model->canes.size() && owner < 0; ++m)
      if (HoldsEnds(c, model->canes[m].polyline)) owner = static_cast<int>(m);
    Outcome outcome = kLeftOut;
    if (owner >= 0) {
      const int parent = static_cast<int>(*model->IndexOf(*model->canes[owner].parent_id));
      if (parent == 0 && majority[owner] == g) {
        outcome = kRoot;
      } else {
        outcome = kRightRoute;
        for (int at_cane = owner; at_cane > 0;) {
          if (std::find(ancestry.begin(), ancestry.end(), majority[at_cane]) == ancestry.end()) {
            outcome = majority[at_cane] < 0 ? kGhost : kWrongCane;
            break;
          }
          at_cane = static_cast<int>(*model->IndexOf(*model->canes[at_cane].parent_id));
        }
      }
    }
    Table& t = tp == 0 ? account->head_canes : account->cane_canes;
    const int bin = BinOf(d);
    t.length[bin][outcome] += c.Length();
    if (pointing) t.pointing[bin][outcome] += c.Length();
    if (verbose && d < near_m) {
      // The likeliest join of all and the likeliest to the root by the inner end.
      int best = -1, best_root = -1;
      for (size_t j = 0; j < joins.size(); ++j) {
        if (joins[j].child != static_cast<int>(i)) continue;
        if (best < 0 || joins[j].probability > joins[best].probability) best = static_cast<int>(j);
        if (joins[j].parent < 0 && joins[j].base_is_last == inner_last &&
            (best_root < 0 || joins[j].probability > joins[best_root].probability))
          best_root = static_cast<int>(j);
      }
      const Polyline3& true_cane = truth.canes[g].polyline;
      const double s_inner = true_cane.Project(inner);
      const double s_outer = true_cane.Project(inner_last ? c.points.front() : c.points.back());
      std::printf("  seed %llu cane %zu: true %d (parent %d), %.2f m, inner end %.3f m from the "
                  "head (%.2f m along its true cane, %s), cos %.2f support %.2f: %s; best %.3f "
                  "to %s, root by inner end %.3f gap %.3f\n",
                  static_cast<unsigned long long>(seed), i, g, tp, c.Length(), d, s_inner,
                  s_inner <= s_outer ? "true base end" : "TIP END", cos, support,
                  kOutcomeNames[outcome], best >= 0 ? joins[best].probability : -1.0,
                  best < 0 ? "-" : joins[best].parent < 0 ? "root" : "cane",
                  best_root >= 0 ? joins[best_root].probability : -1.0,
                  best_root >= 0 ? joins[best_root].features[1] * 0.02 : -1.0);
    }
  }
}

void PrintAccount(const char* title, const Account& a) {
  std::printf("== %s: final (refined) recall %.4f precision %.4f connectivity %.4f; head exits "
              "%d\n", title, a.recall, a.precision, a.connectivity, a.head_exits);
  PrintTable("canes of the head (true parent the trunk/head)", a.head_canes);
  PrintTable("canes of canes (true parent another cane)", a.cane_canes);
}

// Knobs: VB_NEAR_M (verbose lines within this of the head, 0.3); the variant's head exit
// (ConnectOptions): VB_EXIT_REACH (0.3 while the default is off), VB_EXIT_COS,
// VB_EXIT_SUPPORT, VB_EXIT_LEFT_OUT.
TEST(HeadExit, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 20, true);
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  double near_m = 0.3;
  OverrideFromEnv("VB_NEAR_M", &near_m);
  ReconstructOptions options;
  ConnectOptions variant = options.connect;
  if (variant.head_exit_reach_m <= 0.0) variant.head_exit_reach_m = 0.3;
  OverrideFromEnv("VB_EXIT_REACH", &variant.head_exit_reach_m);
  OverrideFromEnv("VB_EXIT_COS", &variant.head_exit_min_cos);
  OverrideFromEnv("VB_EXIT_SUPPORT", &variant.head_exit_min_support);
  OverrideFromEnv("VB_EXIT_LEFT_OUT", &variant.head_exit_left_out);
  Account base, with;
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const auto rendered = RenderAndMatch(seed, images, fiducials, options);
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    const std::vector<View2D>& views = rendered->stop.views;
    const RigCalibration& rig = rendered->matched.rig;
    const VineModel& truth = rendered->stop.scene.vine;
    const auto grown = AssembleAndGrow(views, rig, rendered->matched.pieces, options);
    ASSERT_TRUE(grown.ok()) << grown.status();
    const auto head = ReconstructHeadAndTrunk(views, rig, options.volume, options.head,
                                              Deadline::Infinite(), grown->hints);
    ASSERT_TRUE(head.ok());
    const auto prepared = PrepareCanes(grown->canes, head->trunk, head->head, options.connect);
    ASSERT_TRUE(prepared.ok());
    const std::vector<JoinCandidate> joins = FindJoins(*prepared, head->head, options.connect);
    ConnectOptions off = options.connect;
    off.head_exit_reach_m = 0.0;
    AccountForTree(seed, count, views, rig, truth, *head, *prepared, joins, options, off,
                   verbose, near_m, &base);
    AccountForTree(seed, count, views, rig, truth, *head, *prepared, joins, options, variant,
                   false, near_m, &with);
  }
  std::printf("%d stops from %llu (%s)\n", count, static_cast<unsigned long long>(first),
              images ? "images" : "labels");
  PrintAccount("head exit off", base);
  std::printf("variant: head_exit_reach_m %.3f, min_cos %.2f, min_support %.2f, left out %d\n",
              variant.head_exit_reach_m, variant.head_exit_min_cos,
              variant.head_exit_min_support, variant.head_exit_left_out ? 1 : 0);
  PrintAccount("head exit on", with);
}

}  // namespace
}  // namespace vb::reconstruct
