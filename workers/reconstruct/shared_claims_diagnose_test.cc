// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: what tells apart two right candidates of one view pair that
// conflict because they claim the same stretch of one 2D segment (two canes lying along each
// other in that view) from a right candidate conflicting with a ghost. The second pass's
// candidates (ScoreCandidates with the refined rig, those at or above min_probability) are
// labelled against the drawn canes (vine and neighbours): right when >= 80% of the fitted points
// lie within 10 mm of one drawn cane (that cane is its identity), wrong when < 50% lie within
// 10 mm of any. Each conflicting pair (CandidateConflicts) is classed as right/right on different
// canes, right/right on one cane, right/wrong, wrong/wrong, or other (a partial candidate), and
// for each class the report prints the median (and quartiles) of:
//   max/min share: per pair the larger / smaller of the two candidates' shared fraction of their
//     claim on the shared segment; sides: 2 when they also share a segment on the pair's other
//     side;
//   sep: median 3D distance from one candidate's points over the shared stretch to the other's
//     polyline (mm); third: the lower of the two candidates' third-view support over the shared
//     stretch (CheckInView: inside x aligned, a view outside the pair), and own: the same over
//     the unshared part (0 when one of them has none, as nearly always); p: the lower
//     probability; kept: how many of the two Gibbs kept.
// Then, for each setting of the shared-claim relaxation (SharedClaimOptions), how many pairs of
// each class it would relax; and the true length of the vine inside two or more images, split by
// whether it lies along another cane of the vine in two or more views (LyingAlongAnother, as
// OverlapLoss.DISABLED_Report), near (10 mm) any fitted candidate, one above the threshold, one
// kept strictly, one kept with the relaxation (VB_RELAX), and, where none above the threshold is
// near, whether one below it is right, partial or wrong; and the match classifier's mean terms
// (weight x feature, match_classifier.h) of right candidates above / below the threshold whose
// points lie mostly along another cane of the vine (within a 1 cm cell of such true length) or
// not, and of wrong candidates above it. Run with
//   VB_INPUT=labels|images VB_SEED=1300 VB_STOPS=20 [VB_FIDUCIALS=0] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='SharedClaims.DISABLED_Report'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/match_classifier.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

enum PairClass { kRightRightOther, kRightRightSame, kRightWrong, kWrongWrong, kPartial, kClasses };
const char* kClassNames[kClasses] = {"right/right, 2 canes", "right/right, 1 cane",
                                     "right/wrong", "wrong/wrong", "partial"};

// -1: wrong; -2: partial; else the index of the drawn cane it lies on.
int Label(const ScoredCandidate& c, const std::vector<Cane>& canes) {
  std::map<int, int> votes;
  int near = 0;
  for (const Eigen::Vector3d& p : c.fit.points) {
    int best = -1;
    double best_d = 0.01;
    for (size_t k = 0; k < canes.size(); ++k) {
      const double d = DistanceToPolyline(p, canes[k].polyline);
      if (d <= best_d) {
        best_d = d;
        best = static_cast<int>(k);
      }
    }
    if (best >= 0) {
      ++near;
      ++votes[best];
    }
  }
  const double n = std::max<size_t>(1, c.fit.points.size());
  if (near < 0.5 * n) return -1;
  if (near < 0.8 * n) return -2;
  int cane = -1, most = 0;
  for (const auto& [k, v] : votes) {
    if (v > most) {
      most = v;
      cane = k;
    }
  }
  return cane;
}

std::array<int, 3> CellOf(const Eigen::Vector3d& p) {
  return {static_cast<int>(std::floor(p.x() / 0.01)), static_cast<int>(std::floor(p.y() / 0.01)),
          static_cast<int>(std::floor(p.z() / 0.01))};
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1) + 0.5)];
}

TEST(SharedClaims, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10, true);
  const ReconstructOptions options;
  const CorrespondenceOptions& co = options.correspondence;
  const double threshold = 1.0 / (1.0 + co.alpha);
  struct Described {
    SharedClaimPair pair;
    int kept = 0;  // how many of the two Gibbs kept
  };
  std::vector<std::vector<Described>> pairs_by_class(kClasses);
  int candidates_total = 0, right_total = 0, right_above = 0, right_kept = 0;
  int right_above_dropped_by_other = 0, right_above_dropped_by_wrong = 0;
  // The relaxation the length line uses (VB_RELAX: min_separation_m, min_other_view_support).
  const std::vector<double> relax_list = ListFromEnv("VB_RELAX", {0.01, 0.5});
  SharedClaimOptions relax_setting;
  relax_setting.enabled = true;
  if (relax_list.size() == 2) {
    relax_setting.min_separation_m = relax_list[0];
    relax_setting.min_other_view_support = relax_list[1];
  }
  double length_total[2] = {}, length_any[2] = {}, length_above[2] = {}, length_strict[2] = {},
         length_relaxed[2] = {};
  // Not near a candidate above the threshold, but near one below it that is right / partial /
  // wrong (the first that applies).
  double length_below[2][3] = {};
  // Classifier terms (weight x feature) summed by group: right above the threshold along another
  // cane of the vine (in 2+ views) / not, right below it along / not, wrong above it.
  constexpr int kGroups = 5;
  double term_sum[kGroups][kMatchFeatureCount] = {}, logit_sum[kGroups] = {};
  int group_count[kGroups] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const auto run = RenderAndMatch(seed, images, fiducials, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const SimulatedStop& stop = run->stop;
    const RigCalibration& rig = run->matched.rig;
    std::vector<ViewSamples> samples;
    auto scored = ScoreCandidates(stop.views, rig, co, Deadline::Infinite(), &samples);
    ASSERT_TRUE(scored.ok()) << scored.status();
    std::set<std::array<int, 3>> along_cells;  // 1 cm cells holding true length along another
    std::vector<Polyline3> any_lines;  // every fitted candidate, whatever its probability
    // Those at or below the threshold, by label: right, partial, wrong.
    std::vector<Polyline3> below_lines[3];
    for (const ScoredCandidate& c : *scored) {
      Polyline3 line;
      line.points = c.fit.control_points;
      if (c.probability <= threshold) {
        const int l = Label(c, stop.drawn.canes);
        below_lines[l >= 0 ? 0 : l == -2 ? 1 : 2].push_back(line);
      }
      any_lines.push_back(std::move(line));
    }
    std::vector<ScoredCandidate> cands;
    for (ScoredCandidate& c : *scored)
      if (c.probability >= co.min_probability) cands.push_back(std::move(c));
    const std::vector<std::vector<int>> conflicts =
        CandidateConflicts(cands, co.min_conflict_overlap_px);
    std::vector<double> probabilities;
    for (const ScoredCandidate& c : cands) probabilities.push_back(c.probability);
    const std::vector<double> marginals = GibbsMarginals(probabilities, conflicts, co.gibbs);
    std::vector<int> label(cands.size());
    for (size_t i = 0; i < cands.size(); ++i) label[i] = Label(cands[i], stop.drawn.canes);
    candidates_total += static_cast<int>(cands.size());
    for (size_t i = 0; i < cands.size(); ++i) {
      if (label[i] < 0) continue;
      ++right_total;
      const bool kept = marginals[i] > threshold;
      right_kept += kept;
      if (cands[i].probability <= threshold) continue;
      ++right_above;
      if (kept) continue;
      bool by_other = false, by_wrong = false;
      for (int j : conflicts[i]) {
        if (marginals[j] <= threshold) continue;
        if (label[j] >= 0 && label[j] != label[i]) by_other = true;
        if (label[j] == -1) by_wrong = true;
      }
      right_above_dropped_by_other += by_other;
      right_above_dropped_by_wrong += by_wrong;
    }
    // True length near the candidates kept strictly, kept with the relaxation, and above the
    // threshold (what no conflict rule can exceed).
    {
      CorrespondenceOptions relaxed_options = co;
      relaxed_options.shared_claims = relax_setting;
      const auto relaxed_conflicts =
          CandidateConflicts(cands, relaxed_options, stop.views, samples, rig);
      const std::vector<double> relaxed_marginals =
          GibbsMarginals(probabilities, relaxed_conflicts, co.gibbs);
      std::vector<Polyline3> strict_lines, relaxed_lines, above_lines;
      for (size_t i = 0; i < cands.size(); ++i) {
        Polyline3 line;
        line.points = cands[i].fit.control_points;
        if (marginals[i] > threshold) strict_lines.push_back(line);
        if (relaxed_marginals[i] > threshold) relaxed_lines.push_back(line);
        if (cands[i].probability > threshold) above_lines.push_back(line);
      }
      auto near = [](const Eigen::Vector3d& p, const std::vector<Polyline3>& lines) {
        for (const Polyline3& l : lines)
          if (DistanceToPolyline(p, l) <= 0.01) return true;
        return false;
      };
      // Row 1: lying along another cane of the vine in 2+ views (LyingAlongAnother, as
      // OverlapLoss.DISABLED_Report); row 0: the rest.
      for (const LengthSample& ls : SampleTrueLength(stop, 0.005, false)) {
        const Eigen::Vector3d& p = ls.p;
        const double step = ls.step_m;
        if (ls.in_image < 2) continue;
        const int row = ls.along_own >= 2 ? 1 : 0;
        length_total[row] += step;
        length_any[row] += step * near(p, any_lines);
        length_above[row] += step * near(p, above_lines);
        length_strict[row] += step * near(p, strict_lines);
        length_relaxed[row] += step * near(p, relaxed_lines);
        if (!near(p, above_lines)) {
          for (int l = 0; l < 3; ++l) {
            if (near(p, below_lines[l])) {
              length_below[row][l] += step;
              break;
            }
          }
        }
        if (row == 1) along_cells.insert(CellOf(p));
      }
    }
    // The classifier's terms by group (right candidates above / below the threshold, mostly along
    // another cane of the vine or not; wrong ones above it).
    for (size_t i = 0; i < cands.size(); ++i) {
      const ScoredCandidate& c = cands[i];
      const bool above = c.probability > threshold;
      int group;
      if (label[i] == -1) {
        if (!above) continue;
        group = 4;
      } else if (label[i] >= 0) {
        int on = 0;
        for (const Eigen::Vector3d& q : c.fit.points) {
          const std::array<int, 3> cell = CellOf(q);
          bool hit = false;
          for (int dx = -1; dx <= 1 && !hit; ++dx)
            for (int dy = -1; dy <= 1 && !hit; ++dy)
              for (int dz = -1; dz <= 1 && !hit; ++dz)
                hit = along_cells.count({cell[0] + dx, cell[1] + dy, cell[2] + dz}) > 0;
          on += hit;
        }
        const bool along_cane = 2 * on >= static_cast<int>(c.fit.points.size());
        group = (above ? 0 : 2) + (along_cane ? 0 : 1);
      } else {
        continue;
      }
      const MatchFeatures& w = c.multi_view ? co.classifier.multi_view : co.classifier.two_view;
      double logit = 0.0;
      for (int f = 0; f < kMatchFeatureCount; ++f) {
        term_sum[group][f] += w[f] * c.features[f];
        logit += w[f] * c.features[f];
      }
      logit_sum[group] += logit;
      ++group_count[group];
    }
    for (size_t i = 0; i < cands.size(); ++i) {
      for (int j : conflicts[i]) {
        if (j <= static_cast<int>(i)) continue;
        Described pair;
        pair.pair = DescribeSharedClaim(cands, static_cast<int>(i), j, stop.views, samples, rig,
                                        co.min_conflict_overlap_px);
        pair.kept = (marginals[i] > threshold) + (marginals[j] > threshold);
        const int li = label[i], lj = label[j];
        PairClass cls;
        if (li == -2 || lj == -2) cls = kPartial;
        else if (li >= 0 && lj >= 0) cls = li == lj ? kRightRightSame : kRightRightOther;
        else if (li >= 0 || lj >= 0) cls = kRightWrong;
        else cls = kWrongWrong;
        pairs_by_class[cls].push_back(pair);
      }
    }
  }
  std::printf("SharedClaims %s, seeds %llu-%llu: %d candidates (p >= %.2f), %d right; right "
              "above threshold %d, of which kept %d; right above threshold dropped with a kept "
              "conflicting right candidate of another cane %d, with a kept wrong one %d\n",
              images ? "images" : "labels", static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), candidates_total,
              co.min_probability, right_total, right_above, right_kept,
              right_above_dropped_by_other, right_above_dropped_by_wrong);
  std::printf("  true length of the vine inside 2+ images within 10 mm of: any fitted candidate / "
              "one above threshold (no conflicts) / one kept strictly / one kept relaxed (D %.0f mm"
              " T %.2f), as shares of the row's length\n",
              1000 * relax_setting.min_separation_m, relax_setting.min_other_view_support);
  const char* rows[2] = {"not along another cane of the vine in 2+ views",
                         "along another cane of the vine in 2+ views"};
  for (int r = 0; r < 2; ++r) {
    const double t = std::max(length_total[r], 1e-9);
    std::printf("    %-48s %6.1f m: %.3f / %.3f / %.3f / %.3f\n", rows[r], length_total[r],
                length_any[r] / t, length_above[r] / t, length_strict[r] / t,
                length_relaxed[r] / t);
    std::printf("    %-48s %8s  none above threshold, one below it: right %.3f, partial %.3f, "
                "wrong only %.3f\n", "", "", length_below[r][0] / t, length_below[r][1] / t,
                length_below[r][2] / t);
  }
  std::printf("  classifier terms (weight x feature, mean) of right candidates above the threshold "
              "along another cane / not, below it along / not, and of wrong ones above it:\n");
  std::printf("    %-8s %8d %8d %8d %8d %8d  (candidates)\n", "n", group_count[0],
              group_count[1], group_count[2], group_count[3], group_count[4]);
  auto mean = [](double sum, int n) { return n > 0 ? sum / n : 0.0; };
  std::printf("    %-8s", "logit");
  for (int g = 0; g < kGroups; ++g) std::printf(" %8.2f", mean(logit_sum[g], group_count[g]));
  std::printf("\n");
  for (int f = 0; f < kMatchFeatureCount; ++f) {
    std::printf("    f%-7d", f);
    for (int g = 0; g < kGroups; ++g) std::printf(" %8.2f", mean(term_sum[g][f], group_count[g]));
    std::printf("\n");
  }
  std::printf("  %-22s %6s | %-17s %-17s %-6s %-17s %-17s %-17s %-17s kept(0/1/2)\n", "class",
              "pairs", "max share q25/50/75", "min share", "sides2", "sep mm", "third",
              "own third", "min p");
  for (int c = 0; c < kClasses; ++c) {
    const auto& v = pairs_by_class[c];
    std::vector<double> share, min_share, sep, third, own, p;
    int two_sides = 0, kept[3] = {};
    for (const Described& d : v) {
      const SharedClaimPair& s = d.pair;
      share.push_back(s.max_share);
      min_share.push_back(s.min_share);
      two_sides += s.sides == 2;
      sep.push_back(1000 * s.separation_m);
      third.push_back(s.min_shared_support);
      own.push_back(s.min_own_support);
      p.push_back(s.min_probability);
      ++kept[std::clamp(d.kept, 0, 2)];
    }
    auto q3 = [](const std::vector<double>& x) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.2f/%.2f/%.2f", Quantile(x, 0.25), Quantile(x, 0.5),
                    Quantile(x, 0.75));
      return std::string(buf);
    };
    std::printf("  %-22s %6zu | %-17s %-17s %-6.2f %-17s %-17s %-17s %-17s %d/%d/%d\n",
                kClassNames[c], v.size(), q3(share).c_str(), q3(min_share).c_str(),
                v.empty() ? 0.0 : double(two_sides) / v.size(),
                q3(sep).c_str(), q3(third).c_str(), q3(own).c_str(), q3(p).c_str(), kept[0],
                kept[1], kept[2]);
  }
  // What the relaxation would let through, per setting (VB_SEP_MM, VB_THIRD lists).
  const std::vector<double> seps = ListFromEnv("VB_SEP_MM", {5, 10, 20});
  const std::vector<double> thirds = ListFromEnv("VB_THIRD", {0.3, 0.5, 0.7});
  std::printf("  relaxed pairs (one side, sep >= D, both third >= T): "
              "RR2 / RR1 / RW / WW / partial, each (of which only one of the two kept)\n");
  {
    for (double d : seps) {
      for (double t : thirds) {
        SharedClaimOptions relax;
        relax.enabled = true;
        relax.min_separation_m = d / 1000;
        relax.min_other_view_support = t;
        std::printf("    D %4.0f T %.2f:", d, t);
        for (int c = 0; c < kClasses; ++c) {
          int n = 0, n_split = 0;  // relaxed; of those, with only one of the two kept
          for (const Described& d : pairs_by_class[c]) {
            const bool r = RelaxesConflict(d.pair, relax);
            n += r;
            n_split += r && d.kept < 2;
          }
          std::printf(" %5d (%4d)", n, n_split);
        }
        std::printf("\n");
      }
    }
  }
  EXPECT_GT(candidates_total, 0);
}

}  // namespace
}  // namespace vb::reconstruct
