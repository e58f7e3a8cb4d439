// SPDX-License-Identifier: Apache-2.0
// CutLoss.DISABLED_Report: why the cuts decided on reconstructed vines miss the cuts decided on
// the ground truth (docs/decide.md "Why reconstructed cuts miss"). A diagnosis tool, not a test:
// each stop is rendered and reconstructed as `vinebot bench reconstruct` does it (vine 1 of each
// seed, Bayer images, fiducials, 1 px calibration error), decided on the truth and on the model
// under the default policy and weights, and paired as core/cut_metrics.h MatchCuts pairs them.
// Prints:
//  - every unpaired truth cut by the first cause that applies: A no model cane within 10 mm of
//    the cut (split by the distance from the true head); B the model's trunk covers it; C the
//    model cane's cut paired with another truth cut; D a model cut within 30 mm not on the cane;
//    E the model cane's cut lies on another true cane; F on the same cane but > 30 mm away (truth
//    reason vs model reason, which way along the cane); G the model keeps the cane; H the model
//    leaves it an uncut spur; I it falls with its model parent's cut (parent right or wrong);
//  - every unpaired model cut: a not within 10 mm of true wood; b on the true trunk or an old
//    spur; c its true cane's cut paired with another model cut; d on the same true cane > 30 mm
//    from its cut; e the truth keeps the cane; f truth spur left uncut; g the true cane falls with
//    its parent's cut ("[on kept]": counted in cuts_on_kept_canes);
//  - for A, how far along the true cane its first recalled sample lies, and whether it is inside
//    the model's head; for d toward the tip, the model cut's slide out of the head and where the
//    model cane's base lies;
//  - the kept canes of either plan against the other's;
//  - oracles (missed and spurious): the truth's scheme carried over to the model (each truth
//    kept cane / spur to the model candidate covering most of its first 0.3 m); the truth
//    decided with the model's head spheres, with the truth's scheme, and also without the slide;
//    the model without the head slide; the model with the true head spheres;
//  - where the model's scheme and the carried-over one differ, the weighted feature difference.
//
// The stop and the look-ups are in cut_loss_stop.h.
//
// Knobs: VB_SEED (1300), VB_STOPS (10), VB_INPUT (images | labels | truth: perfect 2D views),
// VB_MODEL_DIAMETER_WEIGHT (the keep diameter weight of the model's decision only; spurs get a
// third), VB_CACHE (a directory: reconstructed models and truths are stored there by seed and
// input and read back on the next run), VB_VERBOSE (one line per missed truth cut), VB_HEAD_BASES
// (0 or 1: the cane bases at the head, workers/reconstruct/head_bases.h; a cache of its own),
// VB_HEAD_BASES_CURVE (their curve_gain), VB_HEAD_BASES_SKELETON (their max_skeleton_px; each
// variant with a cache of its own).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/cut_metrics.h"
#include "gtest/gtest.h"
#include "tests/cut_loss_stop.h"
#include "workers/decide/cut_points.h"
#include "workers/decide/decide.h"

namespace vb {
namespace {

using cutloss::CarryOver;
using cutloss::Correspondence;
using cutloss::HeadSurfaceDistance;
using cutloss::MakeStop;
using cutloss::Nearest;

// The whole number in `name`, or `fallback` when it is not set; a value that is not one
// (EnvNumber's errors, or a fraction) fails the calling test, naming the variable.
int EnvInt(const char* name, int fallback) {
  const auto x = cutloss::EnvNumber(name);
  if (!x.ok()) {
    ADD_FAILURE() << x.status();
    return fallback;
  }
  if (!x->has_value()) return fallback;
  if (**x != std::floor(**x) || std::fabs(**x) > 1e9) {
    ADD_FAILURE() << name << " must be a whole number, is " << **x;
    return fallback;
  }
  return static_cast<int>(**x);
}
std::string EnvString(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? v : fallback;
}

// Role of each cane under a plan: 'k' kept, 's' spur, 'c' has a cut, 'f' no cut (falls with an
// ancestor's cut or left uncut), 't' trunk or old spur.
std::vector<char> Roles(const VineModel& m, const CutPlan& plan) {
  std::vector<char> role(m.canes.size(), 'f');
  for (size_t i = 0; i < m.canes.size(); ++i)
    if (m.canes[i].kind != CaneKind::kCane) role[i] = 't';
  for (const Cut& c : plan.cuts) role[*m.IndexOf(c.cane_id)] = 'c';
  for (CaneId id : plan.keep) role[*m.IndexOf(id)] = 'k';
  for (CaneId id : plan.spurs) role[*m.IndexOf(id)] = 's';
  return role;
}

struct Tally {
  std::map<std::string, int> counts;
  int total = 0;
  void Add(const std::string& what) {
    ++counts[what];
    ++total;
  }
  void Print(const char* title, int denominator) const {
    std::printf("%s (%d; fraction of %d)\n", title, total, denominator);
    for (const auto& [what, n] : counts)
      std::printf("  %-72s %5d  %.3f\n", what.c_str(), n,
                  denominator ? double(n) / denominator : 0.0);
  }
};

std::string ArcBin(double ds) {
  if (ds < -0.03) return "model cut > 30 mm nearer the base";
  if (ds < 0.0) return "model cut <= 30 mm nearer the base (but > 30 mm in 3D)";
  if (ds <= 0.03) return "model cut <= 30 mm nearer the tip (but > 30 mm in 3D)";
  if (ds <= 0.06) return "model cut 30-60 mm nearer the tip";
  return "model cut > 60 mm nearer the tip";
}

TEST(CutLossEnv, NumbersAreParsedWholeOrRejectedByName) {
  unsetenv("VB_CUT_LOSS_ENV_TEST");
  auto x = cutloss::EnvNumber("VB_CUT_LOSS_ENV_TEST");
  ASSERT_TRUE(x.ok());
  EXPECT_FALSE(x->has_value());
  setenv("VB_CUT_LOSS_ENV_TEST", "-2.5", 1);
  x = cutloss::EnvNumber("VB_CUT_LOSS_ENV_TEST");
  ASSERT_TRUE(x.ok());
  EXPECT_EQ(x->value_or(0.0), -2.5);
  for (const char* bad : {"", "abc", "0.5x", "nan", "inf"}) {
    setenv("VB_CUT_LOSS_ENV_TEST", bad, 1);
    x = cutloss::EnvNumber("VB_CUT_LOSS_ENV_TEST");
    EXPECT_EQ(x.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(x.status().message().find("VB_CUT_LOSS_ENV_TEST"), std::string::npos) << bad;
  }
  // MakeStop rejects a bad variable by name before it renders anything.
  unsetenv("VB_CUT_LOSS_ENV_TEST");
  setenv("VB_HEAD_BASES", "2", 1);
  const auto stop = MakeStop(1300, "images", "");
  unsetenv("VB_HEAD_BASES");
  EXPECT_EQ(stop.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(stop.status().message().find("VB_HEAD_BASES"), std::string::npos);
}

TEST(CutLoss, DISABLED_Report) {
  const int seed0 = EnvInt("VB_SEED", 1300);
  const int stops = EnvInt("VB_STOPS", 10);
  const std::string input = EnvString("VB_INPUT", "images");
  const std::string cache = EnvString("VB_CACHE", "");
  const bool verbose = EnvInt("VB_VERBOSE", 0) != 0;
  const PruningPolicy policy;
  const decide::DecideOptions options;

  Tally missed, spurious, kept_cmp, gap_tally, slide_tally;
  int truth_cuts = 0, model_cuts = 0, matched = 0, truth_kept = 0, model_kept = 0;
  // Oracles: matched truth cuts and model cuts.
  int carry_matched = 0, carry_cuts = 0, carry_vines = 0;
  int head_matched = 0, head_cuts = 0;
  int head_scheme_matched = 0, head_scheme_cuts = 0;
  int head_noslide_matched = 0, head_noslide_cuts = 0;
  int noslide_matched = 0, noslide_cuts = 0;
  int truehead_matched = 0, truehead_cuts = 0;
  int choice_vines = 0, choice_near_ties = 0;
  decide::FeatureVector choice_diff = decide::FeatureVector::Zero();
  std::vector<double> errors;
  for (int k = 0; k < stops; ++k) {
    const uint64_t seed = static_cast<uint64_t>(seed0 + k);
    auto stop = MakeStop(seed, input, cache);
    ASSERT_TRUE(stop.ok()) << seed << ": " << stop.status();
    const VineModel& truth = stop->truth;
    const VineModel& model = stop->model;
    auto td = decide::Decide(truth, policy, options);
    ASSERT_TRUE(td.ok()) << td.status();
    // VB_MODEL_DIAMETER_WEIGHT: the diameter weights (kept canes and spurs) of the decision on the
    // model only, to see what the reconstructed diameters cost the choice.
    decide::DecideOptions model_options = options;
    const auto w = cutloss::EnvNumber("VB_MODEL_DIAMETER_WEIGHT");
    ASSERT_TRUE(w.ok()) << w.status();
    if (w->has_value()) {
      model_options.weights.w[decide::kKeepDiameterOutsideMm] = **w;
      model_options.weights.w[decide::kSpurDiameterOutsideMm] = **w / 3.0;
    }
    auto md = decide::Decide(model, policy, model_options);
    if (!md.ok()) {
      std::printf("seed %d: no model plan: %s\n", int(seed),
                  std::string(md.status().message()).c_str());
      truth_cuts += td->plan.cuts.size();
      for (size_t i = 0; i < td->plan.cuts.size(); ++i) missed.Add("no model plan");
      continue;
    }
    const CutPlan& tp = td->plan;
    const CutPlan& mp = md->plan;
    auto match = MatchCuts(truth, tp, model, &mp);
    ASSERT_TRUE(match.ok()) << match.status();
    truth_cuts += tp.cuts.size();
    model_cuts += mp.cuts.size();
    truth_kept += tp.keep.size();
    model_kept += mp.keep.size();
    const std::vector<int> corr = Correspondence(model, truth);
    // Per cane id: how far its cut slid out of the head (plan with slide minus plan without).
    auto slides = [&](const VineModel& v, const CutPlan& with) {
      std::map<int64_t, double> out;
      decide::DecideOptions o = options;
      o.max_head_slide_m = 0.0;
      auto without = decide::Decide(v, policy, o);
      if (!without.ok()) return out;
      for (const Cut& a : with.cuts) {
        for (const Cut& b : without->plan.cuts) {
          if (a.cane_id != b.cane_id) continue;
          const Polyline3& line = v.canes[*v.IndexOf(a.cane_id)].polyline;
          out[a.cane_id.value] = line.Project(a.point) - line.Project(b.point);
        }
      }
      return out;
    };
    const std::map<int64_t, double> truth_slides = slides(truth, tp);
    const std::map<int64_t, double> model_slides = slides(model, mp);
    const std::vector<char> trole = Roles(truth, tp);
    const std::vector<char> mrole = Roles(model, mp);
    std::map<int64_t, int> model_cut_of;  // model cane id -> cut index
    for (size_t j = 0; j < mp.cuts.size(); ++j) model_cut_of[mp.cuts[j].cane_id.value] = int(j);
    std::map<int64_t, int> truth_cut_of;
    for (size_t i = 0; i < tp.cuts.size(); ++i) truth_cut_of[tp.cuts[i].cane_id.value] = int(i);

    for (size_t i = 0; i < tp.cuts.size(); ++i) {
      const Cut& c = tp.cuts[i];
      const size_t T = *truth.IndexOf(c.cane_id);
      const double head_d = HeadSurfaceDistance(truth.head, c.point);
      const std::string where = head_d < 0.05 ? " [<5 cm from head]" : " [>=5 cm from head]";
      if (match->truth_partner[i] >= 0) {
        ++matched;
        errors.push_back((c.point - mp.cuts[match->truth_partner[i]].point).norm());
        continue;
      }
      std::string why;
      double d = 0.0, arc = 0.0;
      const int M = Nearest(model, c.point, &d, &arc);
      if (M < 0 || d > 0.010) {
        bool elsewhere = false;
        for (int m = 0; m < int(model.canes.size()); ++m)
          elsewhere = elsewhere || corr[m] == int(T);
        why = std::string("A not recalled at the cut") +
              (elsewhere ? ", cane recalled elsewhere" : ", cane not recalled") + where;
        // How far along the true cane its first recalled sample lies beyond the cut, and
        // whether that sample lies inside the model's head.
        const Polyline3& line = truth.canes[T].polyline;
        const double s0 = line.Project(c.point);
        for (double s = s0; s <= line.Length(); s += 0.005) {
          double d2 = 0.0, a2 = 0.0;
          const int m2 = Nearest(model, line.PointAt(s), &d2, &a2);
          if (m2 >= 0 && d2 <= 0.010) {
            const double inside = HeadSurfaceDistance(model.head, line.PointAt(s));
            gap_tally.Add(std::string(s - s0 < 0.03 ? "<30 mm" : s - s0 < 0.06 ? "30-60 mm" :
                                      s - s0 < 0.10 ? "60-100 mm" : ">100 mm") +
                          (inside < 0 ? ", inside the model head" :
                           inside < 0.01 ? ", within 10 mm outside the model head" :
                                           ", farther out of the model head"));
            break;
          }
        }
      } else if (mrole[M] == 't') {
        why = "B model trunk/old spur covers the cut" + where;
      } else if (model_cut_of.contains(model.canes[M].id.value)) {
        const int j = model_cut_of[model.canes[M].id.value];
        const Cut& mc = mp.cuts[j];
        const double dist = (mc.point - c.point).norm();
        const size_t L = match->model_truth_cane[j];
        const std::string mreason(CutReasonName(mc.reason));
        if (match->model_partner[j] >= 0) {
          why = "C model cut on this cane paired with another truth cut";
        } else if (L != T && dist <= 0.030) {
          why = "D model cut within 30 mm but assigned to another true cane" + where;
        } else if (L != T) {
          why = "E model cane's cut lies on another true cane (" + mreason + ")" + where;
        } else {
          const double ds = truth.canes[T].polyline.Project(mc.point) -
                            truth.canes[T].polyline.Project(c.point);
          why = "F same cane, " + std::string(CutReasonName(c.reason)) + " vs " + mreason + ": " +
                ArcBin(ds);
        }
      } else {
        const char r = mrole[M];
        const std::string truth_reason(CutReasonName(c.reason));
        if (r == 'k') {
          why = "G model keeps the cane (truth " + truth_reason + ")";
          if (corr[M] != int(T)) why += ", model cane mostly another true cane";
        } else if (r == 's') {
          why = "H model spur left uncut (truth " + truth_reason + ")";
        } else {
          why = "I model cane falls with its model parent's cut (or left uncut)";
          const auto& parent = model.canes[M].parent_id;
          if (parent) {
            const int p = int(*model.IndexOf(*parent));
            why += corr[p] >= 0 && truth.canes[T].parent_id &&
                           truth.canes[corr[p]].id == *truth.canes[T].parent_id
                       ? ", parent right"
                       : ", parent wrong";
          }
        }
      }
      missed.Add(why);
      if (verbose)
        std::printf("MISS seed %d truth cane %lld (%s) at %.3f %.3f %.3f: %s\n", int(seed),
                    (long long)c.cane_id.value, std::string(CutReasonName(c.reason)).c_str(),
                    c.point.x(), c.point.y(), c.point.z(), why.c_str());
    }

    for (size_t j = 0; j < mp.cuts.size(); ++j) {
      if (match->model_partner[j] >= 0) continue;
      const Cut& mc = mp.cuts[j];
      const size_t T = match->model_truth_cane[j];
      std::string why;
      const std::string kept_flag = match->model_on_kept_cane[j] ? " [on kept]" : "";
      if (match->model_truth_distance_m[j] > 0.010) {
        why = "a not within 10 mm of true wood";
      } else if (trole[T] == 't') {
        why = "b on the true trunk or an old spur";
      } else if (truth_cut_of.contains(truth.canes[T].id.value)) {
        const int i = truth_cut_of[truth.canes[T].id.value];
        if (match->truth_partner[i] >= 0) {
          why = "c true cane's cut already paired with another model cut";
        } else {
          const double ds = truth.canes[T].polyline.Project(mc.point) -
                            truth.canes[T].polyline.Project(tp.cuts[i].point);
          why = "d same true cane, no partner: " + ArcBin(ds);
          if (ds > 0.03) {
            // The model cut's slide out of the model head, and the truth cut's.
            const auto truth_slide = truth_slides.find(tp.cuts[i].cane_id.value);
            const auto model_slide = model_slides.find(mc.cane_id.value);
            const double ts = truth_slide != truth_slides.end() ? truth_slide->second : 0.0;
            const double ms = model_slide != model_slides.end() ? model_slide->second : 0.0;
            const Polyline3& mline = model.canes[*model.IndexOf(mc.cane_id)].polyline;
            const double base_ds = truth.canes[T].polyline.Project(mline.points.front()) -
                                   truth.canes[T].polyline.Project(tp.cuts[i].point);
            slide_tally.Add(std::string("model slide ") + (ms < 0.01 ? "<10 mm" : ms < 0.03 ?
                            "10-30 mm" : ">=30 mm") + ", model base beyond truth cut " +
                            (base_ds < 0.0 ? "<0" : base_ds < 0.03 ? "0-30 mm" : base_ds < 0.06 ?
                            "30-60 mm" : ">=60 mm") + (ts > 0.01 ? ", truth slid >10 mm" : ""));
          }
        }
      } else if (trole[T] == 'k') {
        why = "e truth keeps the cane (no truth cut)";
      } else if (trole[T] == 's') {
        why = "f truth spur, uncut";
      } else {
        why = "g true cane falls with its parent's truth cut";
      }
      spurious.Add(why + kept_flag);
    }

    // The kept canes: does the model keep the true kept canes?
    for (CaneId id : tp.keep) {
      const size_t T = *truth.IndexOf(id);
      std::string what = "truth kept cane: no model cane mostly on it";
      for (size_t m = 0; m < model.canes.size(); ++m) {
        if (corr[m] != int(T)) continue;
        if (mrole[m] == 'k') {
          what = "truth kept cane: kept by the model";
          break;
        }
        what = std::string("truth kept cane: model cane ") +
               (mrole[m] == 's' ? "spurred" : mrole[m] == 'c' ? "cut" : "falls/uncut");
      }
      kept_cmp.Add(what);
    }
    for (CaneId id : mp.keep) {
      const int T = corr[*model.IndexOf(id)];
      kept_cmp.Add(T < 0 ? "model kept cane: on no true cane"
                         : std::string("model kept cane: true cane is ") +
                               (trole[T] == 'k' ? "kept" : trole[T] == 's' ? "a spur"
                                : trole[T] == 'c' ? "cut" : trole[T] == 't' ? "trunk" : "falling"));
    }

    // Oracle 1: the truth's scheme carried over to the model.
    auto candidates = decide::FindCandidates(model, policy);
    if (candidates.ok()) {
      auto scheme = CarryOver(truth, tp, model, *candidates);
      // What makes the model's own scheme cheaper than the carried-over one, feature by feature
      // (only where the carried-over scheme is feasible, so that both are of one size).
      if (*scheme != md->scheme && decide::IsFeasible(*candidates, policy, *scheme)) {
        const decide::FeatureVector diff =
            options.weights.w.cwiseProduct(decide::SchemeFeatures(*candidates, policy, md->scheme) -
                                           decide::SchemeFeatures(*candidates, policy, *scheme));
        ++choice_vines;
        choice_diff += diff;
        if (diff.sum() > -0.1) ++choice_near_ties;
      }
      auto placed =
          decide::PlaceCuts(model, *candidates, policy, *scheme, options.max_head_slide_m);
      if (placed.ok()) {
        CutPlan plan = mp;
        plan.keep = scheme->keep;
        plan.spurs = scheme->spurs;
        plan.cuts = placed->cuts;
        auto m = EvaluateCuts(truth, tp, model, &plan);
        if (m.ok()) {
          carry_matched += m->matched_cuts;
          carry_cuts += m->model_cuts;
          ++carry_vines;
        }
      }
    }
    // Oracle 2: the truth with the model's head spheres.
    {
      VineModel t2 = truth;
      t2.head = model.head;
      auto d2 = decide::Decide(t2, policy, options);
      if (d2.ok()) {
        auto m = EvaluateCuts(truth, tp, t2, &d2->plan);
        if (m.ok()) {
          head_matched += m->matched_cuts;
          head_cuts += m->model_cuts;
        }
      }
    }
    // Oracle 2b: the truth with the model's head spheres and the truth's scheme (the slide
    // alone); 2c: the same without the slide.
    {
      VineModel t2 = truth;
      t2.head = model.head;
      auto cands = decide::FindCandidates(t2, policy);
      for (double slide : {options.max_head_slide_m, 0.0}) {
        if (!cands.ok()) break;
        auto placed = decide::PlaceCuts(t2, *cands, policy, td->scheme, slide);
        if (!placed.ok()) continue;
        CutPlan plan = tp;
        plan.cuts = placed->cuts;
        auto m = EvaluateCuts(truth, tp, t2, &plan);
        if (!m.ok()) continue;
        (slide > 0 ? head_scheme_matched : head_noslide_matched) += m->matched_cuts;
        (slide > 0 ? head_scheme_cuts : head_noslide_cuts) += m->model_cuts;
      }
    }
    // Oracle 4: the model with the true head spheres (the head's whole share on this model).
    {
      VineModel m4 = model;
      m4.head = truth.head;
      auto d4 = decide::Decide(m4, policy, options);
      if (d4.ok()) {
        auto m = EvaluateCuts(truth, tp, m4, &d4->plan);
        if (m.ok()) {
          truehead_matched += m->matched_cuts;
          truehead_cuts += m->model_cuts;
        }
      }
    }
    // Oracle 3: the model without the head slide.
    {
      decide::DecideOptions o3 = options;
      o3.max_head_slide_m = 0.0;
      auto d3 = decide::Decide(model, policy, o3);
      if (d3.ok()) {
        auto m = EvaluateCuts(truth, tp, model, &d3->plan);
        if (m.ok()) {
          noslide_matched += m->matched_cuts;
          noslide_cuts += m->model_cuts;
        }
      }
    }
  }
  std::sort(errors.begin(), errors.end());
  std::printf("CutLoss %s seeds %d-%d: truth cuts %d, model cuts %d, matched %d: missed %.3f, "
              "spurious %.3f, matched error median %.1f mm\n",
              input.c_str(), seed0, seed0 + stops - 1, truth_cuts, model_cuts, matched,
              truth_cuts ? 1.0 - double(matched) / truth_cuts : 0.0,
              model_cuts ? 1.0 - double(matched) / model_cuts : 0.0,
              errors.empty() ? 0.0 : 1000 * errors[errors.size() / 2]);
  missed.Print("missed truth cuts by first cause", truth_cuts);
  spurious.Print("spurious model cuts by first cause", model_cuts);
  gap_tally.Print("not recalled at the cut: first recalled sample beyond the cut", truth_cuts);
  slide_tally.Print("spurious cuts > 30 mm toward the tip", model_cuts);
  kept_cmp.Print("kept canes (truth kept, then model kept)", truth_kept + model_kept);
  auto oracle = [&](const char* name, int m, int n) {
    std::printf("oracle %-58s matched %4d: missed %.3f, spurious %.3f\n", name, m,
                truth_cuts ? 1.0 - double(m) / truth_cuts : 0.0, n ? 1.0 - double(m) / n : 0.0);
  };
  oracle("truth's scheme carried over to the model", carry_matched, carry_cuts);
  std::printf("  (carried over on %d of %d stops)\n", carry_vines, stops);
  std::printf("model's scheme against the carried-over one, where that is feasible and differs: "
              "%d stops, %d within 0.1 of cost; weighted feature difference (model - carried, "
              "summed; negative: why the model's is cheaper):\n", choice_vines, choice_near_ties);
  for (int f = 0; f < decide::kSchemeFeatureCount; ++f)
    std::printf("  %-28s %+8.3f\n", std::string(decide::SchemeFeatureName(f)).c_str(),
                choice_diff[f]);
  oracle("truth decided with the model's head spheres", head_matched, head_cuts);
  oracle("truth, model's head, truth's scheme", head_scheme_matched, head_scheme_cuts);
  oracle("truth, model's head, truth's scheme, no slide", head_noslide_matched, head_noslide_cuts);
  oracle("model decided without the head slide", noslide_matched, noslide_cuts);
  oracle("model decided with the true head spheres", truehead_matched, truehead_cuts);
}

}  // namespace
}  // namespace vb
