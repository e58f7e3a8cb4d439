// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: what the connection step (connect.h) does to true cane length
// that assembly recovered, on rendered stops as the bench renders them (fiducials included).
//  - Lost in connection: true samples within 10 mm of an assembled cane (or the silhouette trunk)
//    but of no connected cane, by why the assembled cane nearest them is not in the model.
//  - Recalled but not connected: true samples whose nearest model cane's route to the trunk is
//    not the true one (core/model_metrics.h), by the first wrong cane on that route: a ghost, a
//    descendant of the true cane (hung upside down), or another true cane; and whether a
//    reconstruction of the true parent existed in the model.
//  - With VB_CROSSING=1: per child of this vine, its likeliest join to a cane, right or wrong
//    (LabelJoins), with its crossing evidence (MeasureCrossing: wood past the parent, miss).
// Variants of the connect options (diagnosis only): VB_INSIDE, VB_KEEP_WITHIN,
// VB_KEEP_MIN_LENGTH, VB_KEEP_TAPER, VB_MIN_JOIN, VB_MAX_ATTACH, VB_NO_MERGE, VB_RESCUE,
// VB_RESCUE_TAPER, VB_REPEAT, VB_CROSS_FACTOR, VB_CROSS_SUPPORT, VB_CROSS_REACH, VB_CROSS_MISS.
// Run with
//   VB_INPUT=images VB_SEED=1300 VB_STOPS=12 [VB_VERBOSE=1] vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='ConnectLoss.DISABLED_*'
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/connect_internal.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/join_images.h"
#include "workers/reconstruct/join_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

// Index of the polyline nearest p within `radius` (-1 if none).
int NearestLine(const Eigen::Vector3d& p, const std::vector<const Polyline3*>& lines,
                double radius = 0.01) {
  int best = -1;
  double best_d = radius;
  for (size_t i = 0; i < lines.size(); ++i) {
    const double d = DistanceToPolyline(p, *lines[i]);
    if (d <= best_d) best_d = d, best = static_cast<int>(i);
  }
  return best;
}

std::vector<int> Ancestry(const VineModel& truth, int g) {
  std::vector<int> out = {g};
  for (int at = TrueParent(truth, g); at >= 0 && out.size() <= truth.canes.size();
       at = TrueParent(truth, at))
    out.push_back(at);
  return out;
}

TEST(ConnectLoss, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 12, true);
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  ReconstructOptions options;
  // Variants to try (diagnosis only).
  if (const char* v = std::getenv("VB_INSIDE")) options.connect.inside_fraction = std::atof(v);
  if (const char* v = std::getenv("VB_KEEP_WITHIN")) options.connect.keep_within_m = std::atof(v);
  if (const char* v = std::getenv("VB_KEEP_MIN_LENGTH"))
    options.connect.keep_min_length_m = std::atof(v);
  if (const char* v = std::getenv("VB_KEEP_TAPER"))
    options.connect.keep_taper_ratio = std::atof(v);
  if (const char* v = std::getenv("VB_MIN_JOIN"))
    options.connect.min_join_probability = std::atof(v);
  if (const char* v = std::getenv("VB_MAX_ATTACH")) options.connect.max_attach_m = std::atof(v);
  if (std::getenv("VB_NO_MERGE")) options.connect.merge_continuations = false;
  if (const char* v = std::getenv("VB_RESCUE"))
    options.connect.rescue_min_probability = std::atof(v);
  if (std::getenv("VB_REPEAT")) options.connect.repeat_rescue = true;
  if (const char* v = std::getenv("VB_RESCUE_TAPER"))
    options.connect.rescue_min_taper = std::atof(v);
  if (const char* v = std::getenv("VB_CROSS_FACTOR")) options.connect.crossing_factor = std::atof(v);
  if (const char* v = std::getenv("VB_CROSS_SUPPORT"))
    options.connect.crossing_min_support = std::atof(v);
  if (const char* v = std::getenv("VB_CROSS_REACH")) options.connect.crossing_reach_m = std::atof(v);
  if (const char* v = std::getenv("VB_CROSS_MISS")) options.connect.crossing_min_miss_m = std::atof(v);
  double final_recall = 0, final_precision = 0, final_connectivity = 0;
  // Lost in connection, by the reason of the assembled cane nearest the sample.
  enum Lost { kInside, kNoJoin, kFar, kShort, kOtherLeftOut, kInModel, kLostCount };
  const char* lost_names[kLostCount] = {
      "dropped inside trunk/head", "left out: no candidate join", "left out: beyond keep_within",
      "left out: shorter than keep_min_length", "left out: other", "in model (merged elsewhere)"};
  double lost[kLostCount] = {};
  // Recalled but not connected, by the first wrong cane on the route.
  enum Wrong { kGhost, kInverted, kOtherCane, kWrongCount };
  const char* wrong_names[kWrongCount] = {"first wrong ancestor a ghost",
                                          "first wrong ancestor a descendant (upside down)",
                                          "first wrong ancestor another true cane"};
  double wrong[kWrongCount] = {}, wrong_parent_present[kWrongCount] = {};
  double total = 0, recalled = 0, connected = 0, on_root_not_true = 0;
  // Length of this vine's prepared canes (trunk excluded): all; likeliest join wrong though a
  // right one was a candidate; likeliest join wrong and no right candidate.
  double join_length[3] = {};
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const VineModel& truth = stop.scene.vine;
    const Deadline deadline = Deadline::Infinite();
    const auto matched = MatchWithRigRefinement(stop.views, stop.rig, options, deadline);
    ASSERT_TRUE(matched.ok()) << matched.status();
    const RigCalibration& rig = matched->rig;
    auto canes = AssembleCanes(matched->pieces, options.assembly, deadline);
    ASSERT_TRUE(canes.ok());
    std::erase_if(*canes,
                  [&](const Polyline3& cane) { return options.volume.MostlyOutside(cane); });
    std::vector<Eigen::Vector3d> hints;
    for (const Polyline3& c : *canes) hints.insert(hints.end(), c.points.begin(), c.points.end());
    const auto head = ReconstructHeadAndTrunk(stop.views, rig, options.volume, options.head,
                                              deadline, hints);
    ASSERT_TRUE(head.ok());
    const auto prepared = PrepareCanes(*canes, head->trunk, head->head, options.connect);
    ASSERT_TRUE(prepared.ok());
    const GapSupportFn gap_support = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return GapSupport(a, b, stop.views, rig);
    };
    const JoinImageFn join_images = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return MeasureJoinImages(a, b, stop.views, rig);
    };
    const std::vector<JoinCandidate> joins =
        FindJoins(*prepared, head->head, options.connect, join_images);
    ConnectSummary summary;
    const auto model =
        BuildTree(*prepared, joins, head->head, options.connect, &summary, gap_support);
    ASSERT_TRUE(model.ok());
    {
      VineModel refined = *model;
      ASSERT_TRUE(RefineModel(&refined, stop.views, rig, options.fit, deadline).ok());
      const auto m = EvaluateReconstruction(refined, truth).value();
      final_recall += m.cane_recall / count;
      final_precision += m.cane_precision / count;
      final_connectivity += m.connectivity / count;
    }

    const double centre_x = prepared->trunk ? prepared->trunk->points.back().x() : 0.0;
    // Canes that connect.h's step 3b (rescue_min_probability) brings into the tree (VB_VERBOSE).
    if (verbose && options.connect.rescue_min_probability > 0.0) {
      ConnectOptions no_rescue = options.connect;
      no_rescue.rescue_min_probability = 0.0;
      const auto without = BuildTree(*prepared, joins, head->head, no_rescue, nullptr, gap_support);
      ASSERT_TRUE(without.ok());
      for (const Cane& m : model->canes) {
        bool before = false;
        for (const Cane& w : without->canes) before = before || HoldsEnds(w.polyline, m.polyline);
        if (before || m.kind == CaneKind::kTrunk) continue;
        const Polyline3& c = m.polyline;
        const int parent_index = static_cast<int>(*model->IndexOf(*m.parent_id));
        std::printf("  rescued seed %llu: %.3f m, true %d, x %.2f..%.2f, taper %.2f, on %s (true %d)\n",
                    static_cast<unsigned long long>(seed), c.Length(), MajorityCane(c, truth),
                    c.points.front().x(), c.points.back().x(), TaperTowardCentre(c, centre_x),
                    parent_index == 0 ? "root" : "cane",
                    MajorityCane(model->canes[parent_index].polyline, truth));
      }
    }
    // Reason per assembled cane.
    std::vector<const Polyline3*> assembled;
    if (head->trunk) assembled.push_back(&*head->trunk);
    for (const Polyline3& c : *canes) assembled.push_back(&c);
    std::vector<int> reason(assembled.size(), kInModel);
    std::vector<double> best_p(prepared->canes.size(), 0.0);
    std::vector<char> has_join(prepared->canes.size(), 0);
    for (const JoinCandidate& j : joins) {
      has_join[j.child] = 1;
      best_p[j.child] = std::max(best_p[j.child], j.probability);
    }
    for (size_t a = head->trunk ? 1 : 0; a < assembled.size(); ++a) {
      int p = -1;
      for (size_t i = 0; i < prepared->canes.size() && p < 0; ++i)
        if (HoldsEnds(*assembled[a], prepared->canes[i])) p = static_cast<int>(i);
      if (p < 0) {
        reason[a] = kInside;
        if (verbose) {
          const Polyline3& c = *assembled[a];
          double r = 0;
          for (double x : c.radii) r += x / c.radii.size();
          const double trunk_r = *std::max_element(prepared->trunk->radii.begin(),
                                                   prepared->trunk->radii.end());
          std::printf("  inside seed %llu: %.3f m, true %d, mean radius %.4f (trunk %.4f), z %.2f..%.2f\n",
                      static_cast<unsigned long long>(seed), c.Length(), MajorityCane(c, truth), r,
                      trunk_r, c.points.front().z(), c.points.back().z());
        }
        continue;
      }
      bool in_model = false;
      for (const Cane& m : model->canes)
        in_model = in_model || HoldsEnds(prepared->canes[p], m.polyline);
      if (in_model) continue;
      const Polyline3& c = prepared->canes[p];
      bool near = true;
      for (const Eigen::Vector3d& q : c.points)
        near = near && std::abs(q.x() - centre_x) <= options.connect.keep_within_m;
      reason[a] = !has_join[p] ? kNoJoin
                  : !near      ? kFar
                  : c.Length() < options.connect.keep_min_length_m ? kShort
                                                                     : kOtherLeftOut;
      if (verbose) {
        const int g = MajorityCane(c, truth);
        // Radii near the end nearer the vine's centre and the far end (3 cm in): canes taper.
        const bool front_inner =
            std::abs(c.points.front().x() - centre_x) < std::abs(c.points.back().x() - centre_x);
        const double len = c.Length();
        const double r_inner = c.RadiusAt(front_inner ? std::min(0.03, len) : len - std::min(0.03, len));
        const double r_outer = c.RadiusAt(front_inner ? len - std::min(0.03, len) : std::min(0.03, len));
        std::printf("  left out seed %llu: %.3f m, true %d, best join %.3f, x %.2f..%.2f, r in %.4f out %.4f, %s\n",
                    static_cast<unsigned long long>(seed), c.Length(), g, best_p[p],
                    c.points.front().x(), c.points.back().x(), r_inner, r_outer, lost_names[reason[a]]);
        // Its likeliest join to the tree (a cane in the model, the trunk or head), and by which
        // end (the one nearer the vine's centre or the other).
        int tree_best = -1;
        for (size_t k = 0; k < joins.size(); ++k) {
          const JoinCandidate& jc = joins[k];
          if (jc.child != p) continue;
          bool to_tree = jc.parent < 0;
          for (const Cane& m : model->canes)
            to_tree = to_tree ||
                      (jc.parent >= 0 && HoldsEnds(prepared->canes[jc.parent], m.polyline));
          if (to_tree && (tree_best < 0 || jc.probability > joins[tree_best].probability))
            tree_best = static_cast<int>(k);
        }
        if (tree_best >= 0) {
          const JoinCandidate& jc = joins[tree_best];
          std::printf("    to the tree: %.3f to %s (true %d) by the %s end, gap %.3f, taper %.2f\n",
                      jc.probability, jc.parent < 0 ? "root" : "cane",
                      jc.parent < 0 ? 0 : MajorityCane(prepared->canes[jc.parent], truth),
                      jc.base_is_last == !front_inner ? "inner" : "outer", jc.features[1] * 0.02,
                      TaperTowardCentre(c, centre_x));
        } else {
          std::printf("    to the tree: none, taper %.2f\n", TaperTowardCentre(c, centre_x));
        }
      }
    }
    std::vector<const Polyline3*> model_lines;
    for (const Cane& m : model->canes) model_lines.push_back(&m.polyline);
    std::vector<int> majority;
    for (const Cane& m : model->canes) majority.push_back(MajorityCane(m.polyline, truth));

    for (size_t g = 0; g < truth.canes.size(); ++g) {
      const Cane& cane = truth.canes[g];
      if (cane.kind == CaneKind::kSpur) continue;
      const std::vector<int> ancestry = Ancestry(truth, static_cast<int>(g));
      const int true_parent = TrueParent(truth, static_cast<int>(g));
      bool parent_present = false;
      for (int m : majority) parent_present = parent_present || (m == true_parent && m >= 0);
      for (const Eigen::Vector3d& p : cane.polyline.Sample(0.005)) {
        total += 1;
        const int owner = NearestLine(p, model_lines);
        if (owner < 0) {
          const int a = NearestLine(p, assembled);
          if (a >= 0) lost[reason[a]] += 1;
          continue;
        }
        recalled += 1;
        // The route, as the metric walks it.
        int at = owner, first_wrong = -1;
        for (size_t hops = 0; hops <= model->canes.size(); ++hops) {
          const Cane& c = model->canes[at];
          if (!c.parent_id) break;
          at = static_cast<int>(*model->IndexOf(*c.parent_id));
          if (model->canes[at].kind == CaneKind::kTrunk) break;
          if (std::find(ancestry.begin(), ancestry.end(), majority[at]) == ancestry.end()) {
            first_wrong = at;
            break;
          }
        }
        if (first_wrong < 0) {
          connected += 1;
          // Counted connected by the metric's reading (a cane on the trunk or head is), though
          // its true parent is another cane.
          const Cane& o = model->canes[owner];
          if (o.parent_id && model->canes[*model->IndexOf(*o.parent_id)].kind == CaneKind::kTrunk &&
              true_parent > 0)
            on_root_not_true += 1;
          continue;
        }
        const int h = majority[first_wrong];
        bool descendant = false;
        for (int x = h; x >= 0 && !descendant; x = TrueParent(truth, x)) descendant = x == int(g);
        const Wrong w = h < 0 ? kGhost : descendant ? kInverted : kOtherCane;
        wrong[w] += 1;
        if (parent_present || true_parent == 0) wrong_parent_present[w] += 1;
      }
    }
    // Per prepared cane of this vine: is its likeliest join right (LabelJoins)? If not, was a
    // right one among the candidates, and what kind of join beat it?
    const std::vector<LabelledJoin> labels = LabelJoins(*prepared, joins, truth);
    std::vector<int> majority_prepared;
    for (const Polyline3& c : prepared->canes) majority_prepared.push_back(MajorityCane(c, truth));
    for (size_t i = 0; i < prepared->canes.size(); ++i) {
      const int g = MajorityCane(prepared->canes[i], truth);
      if (g <= 0) continue;
      int best = -1, best_right = -1;
      for (size_t j = 0; j < joins.size(); ++j) {
        if (joins[j].child != int(i)) continue;
        if (best < 0 || joins[j].probability > joins[best].probability) best = int(j);
        if (labels[j].right &&
            (best_right < 0 || joins[j].probability > joins[best_right].probability))
          best_right = int(j);
      }
      const double length = prepared->canes[i].Length();
      join_length[0] += length;
      if (best >= 0 && labels[best].right) continue;
      join_length[best_right >= 0 ? 1 : 2] += length;
      if (best < 0) continue;
      const JoinCandidate& b = joins[best];
      const int h = b.parent >= 0 ? MajorityCane(prepared->canes[b.parent], truth) : 0;
      const bool flipped = h == g || (b.parent < 0 && TrueParent(truth, g) == 0);  // wrong end
      if (verbose) {
        std::printf("  wrong join seed %llu cane %zu (true %d, %.2f m): best %.3f to %s %d "
                    "(true %d%s) gap %.3f, inside %.2f; best right %.3f%s\n",
                    static_cast<unsigned long long>(seed), i, g, length, b.probability,
                    b.parent < 0 ? (b.target == JoinTarget::kHead ? "head" : "trunk") : "cane",
                    b.parent, h, flipped ? ", wrong end" : "", b.features[1] * 0.02,
                    b.features[7], best_right >= 0 ? joins[best_right].probability : -1.0,
                    best_right >= 0 && joins[best_right].parent < 0 ? " (root)" : "");
        // Without a right candidate: how far the child's true base end lies from the true
        // parent's reconstruction (the head's surface for a cane of the head or trunk).
        if (best_right < 0) {
          const int tp = TrueParent(truth, g);
          const Polyline3& c = prepared->canes[i];
          const Polyline3& tc = truth.canes[g].polyline;
          const Eigen::Vector3d base = tc.Project(c.points.front()) <= tc.Project(c.points.back())
                                           ? c.points.front()
                                           : c.points.back();
          double d = 1e9;
          if (tp == 0) {
            d = std::max(0.0, connect_internal::DistanceToHead(base, head->head, nullptr));
            d = std::min(d, DistanceToPolyline(base, *prepared->trunk));
          }
          for (size_t m = 0; m < prepared->canes.size(); ++m)
            if (tp > 0 && majority_prepared[m] == tp)
              d = std::min(d, DistanceToPolyline(base, prepared->canes[m]));
          std::printf("    no right candidate: true parent %d, base %.3f m from it%s\n", tp, d,
                      d > 1e8 ? " (not reconstructed)" : "");
        }
        // What ranked the wrong join above the right one, both to a cane (VB_FEATURES=1): each
        // feature's weighted difference, wrong minus right.
        if (std::getenv("VB_FEATURES") && best_right >= 0 && b.parent >= 0 &&
            joins[best_right].parent >= 0) {
          const JoinWeights w = options.connect.join_weights;
          std::printf("    features wrong-right:");
          for (int f = 1; f < kJoinFeatureCount; ++f)
            std::printf(" %d:%+.2f", f,
                        w.cane[f] * (b.features[f] - joins[best_right].features[f]));
          std::printf("\n");
        }
      }
    }
    // Crossings (VB_CROSSING=1): per child, its likeliest join to a cane, labelled; how much
    // wood the images show along the child's line continued past the parent (a crossing cane
    // goes on, a fork ends), and how near that line passes the parent's axis (skew).
    if (std::getenv("VB_CROSSING")) {
      for (size_t i = 0; i < prepared->canes.size(); ++i) {
        const int g = MajorityCane(prepared->canes[i], truth);
        if (g <= 0) continue;
        int best = -1;
        for (size_t j = 0; j < joins.size(); ++j) {
          if (joins[j].child != int(i)) continue;
          if (best < 0 || joins[j].probability > joins[best].probability) best = int(j);
        }
        if (best < 0 || joins[best].parent < 0) continue;
        const JoinCandidate& b = joins[best];
        const Polyline3& c = prepared->canes[i];
        const Polyline3& par = prepared->canes[b.parent];
        const double len = c.Length();
        const double r_par = par.RadiusAt(par.Project(b.point));
        const CrossingEvidence e =
            MeasureCrossing(c, b.base_is_last, par, b.point, options.connect, gap_support);
        const double beyond = e.past_support, skew = e.miss_m;
        const int h = MajorityCane(par, truth);
        std::printf("  crossing seed %llu child %zu true %d len %.3f -> cane %d true %d: %s p %.3f "
                    "gap %.3f beyond %.2f skew %.4f r_par %.4f r_child %.4f\n",
                    static_cast<unsigned long long>(seed), i, g, len, b.parent, h,
                    labels[best].right ? "RIGHT" : "WRONG", b.probability, b.features[1] * 0.02,
                    beyond, skew, r_par, b.base_is_last ? c.radii.back() : c.radii.front());
      }
    }
    // Canes reaching beyond keep_within that thin away from the centre (kept by their taper):
    // what they hang on, and how far their inner end is from the rest of their true cane or its
    // true parent in the model.
    if (verbose) {
      for (size_t i = 0; i < prepared->canes.size(); ++i) {
        const Polyline3& c = prepared->canes[i];
        bool near = true;
        for (const Eigen::Vector3d& q : c.points)
          near = near && std::abs(q.x() - centre_x) <= options.connect.keep_within_m;
        if (near || c.Length() < options.connect.keep_min_length_m ||
            TaperTowardCentre(c, centre_x) < 1.1)
          continue;
        int in_model = -1;
        for (size_t m = 0; m < model->canes.size(); ++m)
          if (HoldsEnds(c, model->canes[m].polyline)) in_model = static_cast<int>(m);
        const int g = MajorityCane(c, truth);
        const bool inner_last =
            std::abs(c.points.back().x() - centre_x) < std::abs(c.points.front().x() - centre_x);
        const Eigen::Vector3d inner = inner_last ? c.points.back() : c.points.front();
        double to_self = 1e9, to_parent = 1e9;
        const int tp = g >= 0 ? TrueParent(truth, g) : -2;
        for (size_t m = 0; m < model->canes.size(); ++m) {
          if (static_cast<int>(m) == in_model) continue;
          const double d = DistanceToPolyline(inner, model->canes[m].polyline);
          if (majority[m] == g && g >= 0) to_self = std::min(to_self, d);
          if (majority[m] == tp && tp >= 0) to_parent = std::min(to_parent, d);
        }
        int parent_true = -9;
        if (in_model >= 0 && model->canes[in_model].parent_id)
          parent_true = majority[*model->IndexOf(*model->canes[in_model].parent_id)];
        std::printf("  tapered seed %llu: %.2f m true %d (parent %d), in model %d on true %d; "
                    "inner end to own cane %.3f, to true parent %.3f\n",
                    static_cast<unsigned long long>(seed), c.Length(), g, tp, in_model >= 0,
                    parent_true, to_self, to_parent);
      }
    }
    // Image support of each prepared cane (VB_SUPPORT=1): the fraction of it the images show
    // as wood (GapSupport along its segments), by whether it is this vine's, a ghost or a
    // neighbour's (beyond 0.5 m), and whether it is in the model.
    if (std::getenv("VB_SUPPORT")) {
      for (size_t i = 0; i < prepared->canes.size(); ++i) {
        const Polyline3& c = prepared->canes[i];
        double sum = 0, len = 0;
        for (size_t k = 0; k + 1 < c.points.size(); ++k) {
          const double l = (c.points[k + 1] - c.points[k]).norm();
          sum += l * gap_support(c.points[k], c.points[k + 1]);
          len += l;
        }
        bool in_model = false;
        for (const Cane& m : model->canes) in_model = in_model || HoldsEnds(c, m.polyline);
        std::printf("  support seed %llu cane %zu: true %d, %.3f m, support %.3f, far %d, in model %d\n",
                    static_cast<unsigned long long>(seed), i, majority_prepared[i], len,
                    len > 0 ? sum / len : 0.0,
                    !connect_internal::WhollyWithin(c, centre_x, 0.5), in_model);
      }
    }
    std::printf("seed %llu: attached %d (kept near %d), left out %d, inside %d\n",
                static_cast<unsigned long long>(seed), summary.attached, summary.kept_near,
                summary.unattached, summary.inside_trunk_or_head);
  }
  std::printf("%d stops: recalled after connection %.3f, connected %.3f (of true length)\n", count,
              recalled / total, connected / total);
  std::printf("  of the connected, on the trunk or head though the true parent is a cane %.3f\n",
              on_root_not_true / total);
  std::printf("final (refined) recall %.4f precision %.4f connectivity %.4f (means over stops)\n",
              final_recall, final_precision, final_connectivity);
  std::printf("lost in connection:\n");
  for (int r = 0; r < kLostCount; ++r) std::printf("  %-45s %.4f\n", lost_names[r], lost[r] / total);
  std::printf("this vine's canes (m): %.2f; likeliest join wrong, a right one a candidate %.2f; "
              "no right candidate %.2f\n", join_length[0], join_length[1], join_length[2]);
  std::printf("recalled, not connected:\n");
  for (int w = 0; w < kWrongCount; ++w)
    std::printf("  %-50s %.4f (true parent reconstructed in the model: %.4f)\n", wrong_names[w],
                wrong[w] / total, wrong_parent_present[w] / total);
}

}  // namespace
}  // namespace vb::reconstruct
