// SPDX-License-Identifier: Apache-2.0
// A diagnosis tool, not a test: where cane recall and connectivity are lost, stage by stage, on
// rendered stops (the bench's stops, MakeRenderedStop). Run with
//   VB_INPUT=labels|images VB_SEED=1100 VB_STOPS=10 vb_reconstruct_test
//     --gtest_also_run_disabled_tests --gtest_filter='PipelineStages.DISABLED_*'
// VB_HEAD_FAR=1 adds the canes hung on another cane by their distance from the head
// (head_far_diagnose.h; VB_HEAD_FAR_CSV=path, one line each); VB_EXIT_REACH, VB_EXIT_COS and
// VB_EXIT_MIN_RADIUS set the head exits of connection (connect.h step 6c).
// Tuning seeds only (1100-1999; docs/reconstruction.md "Seeds").
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <utility>
#include <optional>
#include <string>
#include <vector>

#include "core/model_metrics.h"
#include "core/vine_model_test_util.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/connect_test_util.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/head_far_diagnose.h"
#include "workers/reconstruct/join_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

struct Row {
  double recall = 0, precision = 0, connectivity = 0;
  void Add(const ReconstructionMetrics& m, int n) {
    recall += m.cane_recall / n;
    precision += m.cane_precision / n;
    connectivity += m.connectivity / n;
  }
};

// For the model's canes: how the recalled but unconnected true length is explained by the
// matched model cane's parent: a cane reconstructing some other true cane, or a ghost.
struct ParentBreakdown {
  double wrong_parent_m = 0, ghost_parent_m = 0, truth_m = 0;
};

int Majority(const Polyline3& line, const VineModel& truth) {
  std::vector<double> votes(truth.canes.size(), 0.0);
  for (const Eigen::Vector3d& p : line.Sample(0.005)) {
    int best = -1;
    double best_d = 0.01;
    for (size_t g = 0; g < truth.canes.size(); ++g) {
      const double d = DistanceToPolyline(p, truth.canes[g].polyline);
      if (d <= best_d) best_d = d, best = static_cast<int>(g);
    }
    if (best >= 0) votes[best] += 1;
  }
  int best = -1;
  double most = 0;
  for (size_t g = 0; g < votes.size(); ++g)
    if (votes[g] > most) most = votes[g], best = static_cast<int>(g);
  return best;
}

// The true cane's ancestors (the trunk included) and the cane itself.
std::vector<int> Ancestry(const VineModel& truth, int g) {
  std::vector<int> out;
  for (int at = g, hops = 0; at >= 0 && hops <= static_cast<int>(truth.canes.size()); ++hops) {
    out.push_back(at);
    at = TrueParent(truth, at);
  }
  return out;
}

bool Contains(const std::vector<int>& v, int x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

// VB_ORACLE=ancestors: as LabelJoins, but a join to a cane is also right when the target
// reconstructs any ancestor of the child's true cane (a grandparent: the metric's own notion of
// a true route), so that a cane whose true parent was not reconstructed keeps a right join.
void RelabelToAncestors(const PreparedCanes& prepared, const VineModel& truth,
                        std::vector<LabelledJoin>* labels,
                        const std::vector<JoinCandidate>& joins) {
  std::vector<int> majority;
  for (const Polyline3& c : prepared.canes) majority.push_back(MajorityCane(c, truth));
  for (size_t j = 0; j < joins.size(); ++j) {
    const JoinCandidate& join = joins[j];
    const int g = majority[join.child];
    if (g < 0 || join.parent < 0 || (*labels)[j].right) continue;
    const Polyline3& true_cane = truth.canes[g].polyline;
    const Polyline3& child = prepared.canes[join.child];
    const double s_first = true_cane.Project(child.points.front());
    const double s_last = true_cane.Project(child.points.back());
    const bool base_right = join.base_is_last ? s_last <= s_first : s_first <= s_last;
    const int h = majority[join.parent];
    if (base_right && h >= 0 && h != g && Contains(Ancestry(truth, g), h))
      (*labels)[j].right = true;
  }
}

// Recalled but unconnected true length (as EvaluateReconstruction scores it: each 5 mm sample
// of a true cane, its nearest model cane within 1 cm and that cane's route to the trunk), by
// why the route is wrong, as fractions of the true cane length.
struct RouteLoss {
  double unattached = 0;     // the route ends at a root that is not the trunk
  double merged_child = 0;   // the nearest model cane mostly reconstructs another true cane
  double ghost_parent = 0;   // the first wrong link hangs on a model cane matching no true cane
  double parent_absent = 0;  // no model cane reconstructs the true parent (not the trunk)
  double parent_far = 0;     // it does, but none of the true ancestors' model canes is within
                             // 3 cm of the hung cane's base (the parent broken at the fork)
  double parent_beyond = 0;  // of parent_far: none within max_attach_m's 15 cm (out of reach
                             // of any join, whatever the classifier)
  double beyond_from_head = 0;  // of parent_beyond: canes whose true parent is the trunk (the
                                // head's surface, not measured here, may be nearer)
  // beyond_from_head by how far the hung cane's inner end (nearer the model head) lies from the
  // model head's spheres (HeadFarBin: < 15, 15-25, 25-40, > 40 cm), and of that, pointing at the
  // head (cosine of its outward tangent there with the direction to the head >= 0.8)
  double from_head_by_reach[HeadFarTally::kBins] = {};
  double from_head_pointing[HeadFarTally::kBins] = {};
  double parent_near = 0;    // one is within 3 cm: a wrong choice of parent
  double merged_parent = 0;  // of the three above: the wrong parent has >= 5 cm within 1 cm
                             // of a true ancestor (a parent merged with another cane)
  void Add(const RouteLoss& o, double w) {
    unattached += o.unattached * w, merged_child += o.merged_child * w;
    ghost_parent += o.ghost_parent * w, parent_absent += o.parent_absent * w;
    parent_far += o.parent_far * w, parent_near += o.parent_near * w;
    parent_beyond += o.parent_beyond * w, beyond_from_head += o.beyond_from_head * w;
    merged_parent += o.merged_parent * w;
    for (int b = 0; b < HeadFarTally::kBins; ++b) {
      from_head_by_reach[b] += o.from_head_by_reach[b] * w;
      from_head_pointing[b] += o.from_head_pointing[b] * w;
    }
  }
};

RouteLoss MeasureRouteLoss(const VineModel& model, const VineModel& truth) {
  RouteLoss loss;
  std::vector<int> majority;
  for (const Cane& m : model.canes) majority.push_back(Majority(m.polyline, truth));
  double truth_m = 0;
  for (size_t g = 0; g < truth.canes.size(); ++g) {
    if (truth.canes[g].kind == CaneKind::kSpur) continue;
    const std::vector<int> ancestry = Ancestry(truth, static_cast<int>(g));
    const std::vector<Eigen::Vector3d> samples = truth.canes[g].polyline.Sample(0.005);
    const double w = truth.canes[g].polyline.Length() / std::max<size_t>(1, samples.size());
    truth_m += truth.canes[g].polyline.Length();
    for (const Eigen::Vector3d& p : samples) {
      int owner = -1;
      double best = 0.01;
      for (size_t i = 0; i < model.canes.size(); ++i) {
        const double d = DistanceToPolyline(p, model.canes[i].polyline);
        if (d <= best) best = d, owner = static_cast<int>(i);
      }
      if (owner < 0) continue;
      // Walk up to the first link onto a cane that is not a true ancestor.
      int child = owner, bad = -1;
      bool rooted = false;
      for (size_t hops = 0; hops <= model.canes.size(); ++hops) {
        const Cane& c = model.canes[child];
        if (!c.parent_id) {
          rooted = c.kind == CaneKind::kTrunk;
          break;
        }
        const int parent = static_cast<int>(*model.IndexOf(*c.parent_id));
        if (model.canes[parent].kind == CaneKind::kTrunk) {
          rooted = true;
          break;
        }
        if (!Contains(ancestry, majority[parent])) {
          bad = parent;
          break;
        }
        child = parent;
      }
      if (rooted && bad < 0) continue;  // connected
      if (bad < 0) {
        loss.unattached += w;
        continue;
      }
      if (majority[owner] != static_cast<int>(g) && !Contains(ancestry, majority[owner])) {
        loss.merged_child += w;
        continue;
      }
      if (majority[bad] < 0) {
        loss.ghost_parent += w;
        continue;
      }
      const int true_parent = TrueParent(truth, static_cast<int>(g));
      bool parent_in_model = true_parent <= 0;
      for (size_t i = 0; i < model.canes.size(); ++i)
        parent_in_model = parent_in_model || majority[i] == true_parent;
      const Polyline3& hung = model.canes[child].polyline;
      // Its base as seen: a first point drawn onto the parent (a bridge) is skipped.
      const bool bridged = hung.points.size() > 2 &&
                           DistanceToPolyline(hung.points[0], model.canes[bad].polyline) < 1e-3;
      const Eigen::Vector3d base = hung.points[bridged ? 1 : 0];
      double nearest = 1e9;
      for (size_t i = 0; i < model.canes.size(); ++i)
        if (static_cast<int>(i) != child && Contains(ancestry, majority[i]) &&
            majority[i] != static_cast<int>(g))
          nearest = std::min(nearest, DistanceToPolyline(base, model.canes[i].polyline));
      if (!parent_in_model) loss.parent_absent += w;
      else if (nearest <= 0.03) loss.parent_near += w;
      else loss.parent_far += w, loss.parent_beyond += nearest > 0.15 ? w : 0.0;
      if (parent_in_model && nearest > 0.15 && true_parent == 0) {
        loss.beyond_from_head += w;
        if (!model.head.spheres.empty()) {
          Polyline3 seen = hung;
          if (bridged) seen.points.erase(seen.points.begin()), seen.radii.erase(seen.radii.begin());
          const InnerEnd end = InnerEndToHead(seen, model.head);
          loss.from_head_by_reach[HeadFarBin(end.distance_m)] += w;
          if (end.cos >= 0.8) loss.from_head_pointing[HeadFarBin(end.distance_m)] += w;
        }
      }
      double on_ancestor = 0;
      for (const Eigen::Vector3d& q : model.canes[bad].polyline.Sample(0.005))
        for (int a : ancestry)
          if (a != static_cast<int>(g) && DistanceToPolyline(q, truth.canes[a].polyline) <= 0.01) {
            on_ancestor += 0.005;
            break;
          }
      if (on_ancestor >= 0.05) loss.merged_parent += w;
    }
  }
  RouteLoss out;
  out.Add(loss, truth_m > 0 ? 1.0 / truth_m : 0.0);
  return out;
}

// Known answers of MeasureRouteLoss (this runs in ctest): a trunk, cane A on it, B forking from
// A's middle, C on the trunk.
TEST(PipelineStages, RouteLossKnownAnswers) {
  using connect_test::Line;
  const Eigen::Vector3d top(0, 0, 1.0), fork(0.2, 0, 1.0);
  VineModel truth;
  truth.canes = {CaneOf(1, {}, CaneKind::kTrunk, Line({0, 0, 0.5}, top)),
                 CaneOf(2, 1, CaneKind::kCane, Line(top, {0.4, 0, 1.0})),        // A
                 CaneOf(3, 2, CaneKind::kCane, Line(fork, {0.2, 0, 1.3})),       // B
                 CaneOf(4, 1, CaneKind::kCane, Line(top, {0.3, 0.05, 1.3}))};    // C
  // B's base point: 1 cm above the fork (its reconstruction starts there).
  const Polyline3 b_line = Line({0.2, 0, 1.01}, {0.2, 0, 1.3});
  const double length = 0.5 + 0.4 + 0.3 + truth.canes[3].polyline.Length();
  auto model_with = [&](const Polyline3& a_line, int b_parent) {
    VineModel m;
    m.canes = {CaneOf(1, {}, CaneKind::kTrunk, truth.canes[0].polyline),
               CaneOf(2, 1, CaneKind::kCane, a_line),
               CaneOf(3, b_parent, CaneKind::kCane, b_line),
               CaneOf(4, 1, CaneKind::kCane, truth.canes[3].polyline)};
    EXPECT_TRUE(m.Validate().ok());
    return m;
  };
  // B on A: connected, no loss.
  const RouteLoss right = MeasureRouteLoss(model_with(truth.canes[1].polyline, 2), truth);
  EXPECT_NEAR(right.parent_near + right.parent_far + right.merged_child, 0.0, 1e-12);
  // B on C while A (its parent) passes through B's base: a wrong choice, B's length lost.
  const RouteLoss near = MeasureRouteLoss(model_with(truth.canes[1].polyline, 4), truth);
  EXPECT_NEAR(near.parent_near, 0.29 / length, 0.01 / length);
  EXPECT_EQ(near.parent_far, 0.0);
  // B on C while A was reconstructed only up to 10 cm from the fork: the parent broken there.
  const RouteLoss far = MeasureRouteLoss(model_with(Line(top, {0.1, 0, 1.0}), 4), truth);
  EXPECT_NEAR(far.parent_far, 0.29 / length, 0.01 / length);
  EXPECT_EQ(far.parent_beyond, 0.0);
  EXPECT_EQ(far.parent_near, 0.0);
}

TEST(PipelineStages, DISABLED_Report) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1100, 8);
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  ReconstructOptions options;
  // Knobs: the environment variable and the option it sets.
  for (const auto& [name, field] : std::initializer_list<std::pair<const char*, double*>>{
           {"VB_MIN_JOIN", &options.connect.min_join_probability},
           {"VB_MAX_BRIDGE", &options.connect.max_bridge_m},
           {"VB_MAX_ATTACH", &options.connect.max_attach_m},
           {"VB_ALPHA", &options.correspondence.alpha},
           {"VB_GAP_SUPPORT", &options.connect.min_gap_support},
           {"VB_KEEP_WITHIN", &options.connect.keep_within_m},
           {"VB_KEEP_MIN_LENGTH", &options.connect.keep_min_length_m},
           {"VB_MIN_ISOLATED", &options.assembly.min_isolated_length_m},
           {"VB_MIN_EVIDENCE", &options.assembly.min_evidence_m},
           {"VB_MIN_PIECE_P", &options.assembly.min_piece_probability},
           {"VB_EXIT_REACH", &options.connect.head_exit_reach_m},
           {"VB_EXIT_COS", &options.connect.head_exit_min_cos},
           {"VB_EXIT_MIN_RADIUS", &options.connect.head_exit_min_radius_m}})
    OverrideFromEnv(name, field);
  OverrideFromEnv("VB_MERGE", &options.connect.merge_continuations);
  OverrideFromEnv("VB_MIN_HITS", &options.correspondence.min_hits);
  OverrideFromEnv("VB_MAX_GAP", &options.correspondence.max_gap_samples);
  Row pieces_row, assembled_row, connected_row, final_row;
  double unattached_recall = 0;
  ParentBreakdown parents;
  RouteLoss route_loss;
  HeadFarTally head_far;
  const bool head_far_on = std::getenv("VB_HEAD_FAR") != nullptr;
  std::FILE* head_far_csv = nullptr;  // VB_HEAD_FAR_CSV=path: one line per hung cane
  if (const char* path = std::getenv("VB_HEAD_FAR_CSV")) head_far_csv = std::fopen(path, "w");
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    // Correspondence with the rig refined in between, as the pipeline does it.
    const auto run = RenderAndMatch(seed, images, /*fiducials=*/false, options);
    ASSERT_TRUE(run.ok()) << run.status();
    const SimulatedStop& stop = run->stop;
    const VineModel& truth = stop.scene.vine;
    const std::vector<Piece3D>& pieces = run->matched.pieces;
    const RigCalibration& rig = run->matched.rig;
    std::vector<Polyline3> piece_lines;
    for (const Piece3D& p : pieces) piece_lines.push_back(p.polyline);
    const auto assembled = AssembleStop(stop.views, rig, pieces, options);
    ASSERT_TRUE(assembled.ok()) << assembled.status();
    const std::vector<Polyline3>& canes = assembled->canes;
    const HeadAndTrunk& head = assembled->head;
    const PreparedCanes& prepared = assembled->prepared;
    std::vector<JoinCandidate> joins = assembled->joins;
    if (std::getenv("VB_ORACLE") && *std::getenv("VB_ORACLE")) {
      // The join classifier replaced by the true labels (LabelJoins: the true parent only; with
      // VB_ORACLE=ancestors any true ancestor, RelabelToAncestors).
      OverrideFromEnv("VB_BASE_REACH", &kBaseReach);
      std::vector<LabelledJoin> labels = LabelJoins(prepared, joins, truth);
      if (std::string(std::getenv("VB_ORACLE")) == "ancestors")
        RelabelToAncestors(prepared, truth, &labels, joins);
      for (size_t j = 0; j < joins.size(); ++j) joins[j].probability = labels[j].right ? 0.95 : 0.01;
    }
    const auto built = ConnectAndRefine(stop.views, rig, *assembled, joins, options);
    ASSERT_TRUE(built.ok()) << built.status();
    const VineModel& connected = built->connected;
    const ConnectSummary& summary = built->summary;

    const auto mp = EvaluateReconstruction(Flat(piece_lines), truth).value();
    std::vector<Polyline3> with_trunk;
    if (head.trunk) with_trunk.push_back(*head.trunk);
    with_trunk.insert(with_trunk.end(), canes.begin(), canes.end());
    const auto ma = EvaluateReconstruction(Flat(with_trunk), truth).value();
    const auto mc = EvaluateReconstruction(connected, truth).value();
    const auto mf = EvaluateReconstruction(built->refined, truth).value();
    if (verbose) {
      VineModel bridgeless = connected;
      for (size_t i = 1; i < bridgeless.canes.size(); ++i) {
        Polyline3& l = bridgeless.canes[i].polyline;
        if (l.points.size() > 2) l.points.erase(l.points.begin()), l.radii.erase(l.radii.begin());
      }
      const auto mb = EvaluateReconstruction(bridgeless, truth).value();
      // Bridges: length and imprecise length by target (root / cane) and gap (< 3 cm, 3-8, > 8).
      double total[2][3] = {}, bad[2][3] = {};
      for (size_t i = 1; i < connected.canes.size(); ++i) {
        const Polyline3& l = connected.canes[i].polyline;
        const double gap = (l.points[1] - l.points[0]).norm();
        const int t = connected.canes[*connected.IndexOf(*connected.canes[i].parent_id)].kind == CaneKind::kTrunk ? 0 : 1;
        const int b = gap < 0.03 ? 0 : (gap < 0.08 ? 1 : 2);
        for (int q = 0; q < 10; ++q) {
          const Eigen::Vector3d x = l.points[0] + (q + 0.5) / 10.0 * (l.points[1] - l.points[0]);
          const bool near = NearAnyCane(x, truth.canes);
          total[t][b] += gap / 10;
          if (!near) bad[t][b] += gap / 10;
        }
      }
      std::printf("  bridges (m, imprecise m): root <3cm %.2f %.2f, 3-8 %.2f %.2f, >8 %.2f %.2f; cane <3cm %.2f %.2f, 3-8 %.2f %.2f, >8 %.2f %.2f\n",
                  total[0][0], bad[0][0], total[0][1], bad[0][1], total[0][2], bad[0][2], total[1][0], bad[1][0], total[1][1], bad[1][1], total[1][2], bad[1][2]);
      std::printf("  without bridges: %.3f / %.3f\n", mb.cane_recall, mb.cane_precision);
    }
    const RouteLoss route = MeasureRouteLoss(built->refined, truth);
    if (head_far_on) head_far.Add(connected, prepared, joins, truth, head_far_csv, seed);
    route_loss.Add(route, 1.0 / count);
    pieces_row.Add(mp, count);
    assembled_row.Add(ma, count);
    connected_row.Add(mc, count);
    final_row.Add(mf, count);

    // Recall the connection step lost: assembled canes it left out or dropped inside the head.
    std::vector<Polyline3> left_out;
    if (head.trunk) left_out.push_back(*head.trunk);
    for (const Polyline3& c : canes) {
      bool in_model = false;
      for (const Cane& m : connected.canes) {
        // Attached canes keep their points (plus a base point on the parent).
        if (m.polyline.points.size() >= c.points.size() &&
            ((m.polyline.points.back() - c.points.back()).norm() < 1e-9 ||
             (m.polyline.points.back() - c.points.front()).norm() < 1e-9)) {
          in_model = true;
          break;
        }
      }
      if (!in_model) left_out.push_back(c);
    }
    std::vector<Polyline3> model_lines;
    for (const Cane& m : connected.canes) model_lines.push_back(m.polyline);
    std::vector<Polyline3> both = model_lines;
    both.insert(both.end(), left_out.begin() + (head.trunk ? 1 : 0), left_out.end());
    const double recall_with_left_out = EvaluateReconstruction(Flat(both), truth)->cane_recall;
    unattached_recall += (recall_with_left_out - mc.cane_recall) / count;

    // Prepared canes the tree left out: their length, how much of it lies within 1 cm of the
    // true vine, by the best join they had (VB_LEFT_OUT=1).
    if (std::getenv("VB_LEFT_OUT")) {
      std::vector<double> best_p(prepared.canes.size(), 0.0);
      std::vector<int> best_target(prepared.canes.size(), -3);
      for (const JoinCandidate& j : joins)
        if (j.probability > best_p[j.child]) best_p[j.child] = j.probability, best_target[j.child] = j.parent;
      for (size_t i = 0; i < prepared.canes.size(); ++i) {
        const Polyline3& c = prepared.canes[i];
        bool in_model = false;
        for (const Cane& m : connected.canes)  // merged continuations lie inside their parent
          for (const Eigen::Vector3d& q : m.polyline.points)
            in_model = in_model || (q - c.points.back()).norm() < 1e-9 ||
                       (q - c.points.front()).norm() < 1e-9;
        if (in_model) continue;
        double near = 0, all = 0;
        for (const Eigen::Vector3d& p : c.Sample(0.005)) {
          all += 1;
          near += NearAnyCane(p, truth.canes);
        }
        const int g = MajorityCane(c, truth);
        double min_x = 1e9, max_x = -1e9;
        for (const Eigen::Vector3d& p : c.points) min_x = std::min(min_x, p.x()), max_x = std::max(max_x, p.x());
        std::printf("  left-out seed %llu cane %zu: %.3f m, precise %.2f, true %d%s, best join %.3f to %d, x %.2f..%.2f\n",
                    static_cast<unsigned long long>(seed), i, c.Length(), all > 0 ? near / all : 0.0, g,
                    g >= 0 && truth.canes[g].kind == CaneKind::kTrunk ? " (trunk)" : "", best_p[i],
                    best_target[i], min_x, max_x);
      }
    }

    // Unconnected recalled length by the parent of the matched model cane.
    std::vector<int> majority;
    for (const Cane& m : connected.canes) majority.push_back(Majority(m.polyline, truth));
    ParentBreakdown pb;
    for (size_t i = 0; i < connected.canes.size(); ++i) {
      const Cane& m = connected.canes[i];
      if (!m.parent_id || majority[i] < 0) continue;
      const size_t parent = *connected.IndexOf(*m.parent_id);
      if (connected.canes[parent].kind == CaneKind::kTrunk) continue;
      // Is the parent a reconstruction of an ancestor (or the cane itself)?
      const int g = majority[i];
      bool ok = false;
      for (int at = g; at >= 0;) {
        if (majority[parent] == at) ok = true;
        const auto& pid = truth.canes[at].parent_id;
        at = pid ? static_cast<int>(*truth.IndexOf(*pid)) : -1;
      }
      if (ok) continue;
      const double length = m.polyline.Length();
      if (majority[parent] < 0) pb.ghost_parent_m += length;
      else pb.wrong_parent_m += length;
      if (std::getenv("VB_CASES") && majority[parent] >= 0) {
        // Is the parent's true cane a descendant of the child's (hung upside down)?
        bool inverted = false;
        for (int at = majority[parent]; at >= 0;) {
          if (at == g) inverted = true;
          const auto& pid = truth.canes[at].parent_id;
          at = pid ? static_cast<int>(*truth.IndexOf(*pid)) : -1;
        }
        const Polyline3& c = m.polyline;
        const Polyline3& par = connected.canes[parent].polyline;
        Eigen::Vector3d tc = (c.points[std::min<size_t>(3, c.points.size() - 1)] - c.points[1]);
        double s_best = 1e9, at_s = 0, acc = 0;
        Eigen::Vector3d tp = Eigen::Vector3d::UnitX();
        for (size_t q = 0; q + 1 < par.points.size(); ++q) {
          const double d = PointSegmentDistance(c.points[0], par.points[q], par.points[q + 1]);
          if (d < s_best) s_best = d, at_s = acc, tp = par.points[q + 1] - par.points[q];
          acc += (par.points[q + 1] - par.points[q]).norm();
        }
        const double angle = std::acos(std::min(1.0, std::abs(tc.normalized().dot(tp.normalized())))) * 57.3;
        // Distance from the child's base to the true parent's reconstruction, if any.
        double to_true = 1e9;
        const int true_parent = truth.canes[g].parent_id ? static_cast<int>(*truth.IndexOf(*truth.canes[g].parent_id)) : -1;
        for (size_t j = 0; j < connected.canes.size(); ++j) {
          if (majority[j] != g && majority[j] != true_parent && !(true_parent == 0 && j == 0)) continue;
          if (j == i) continue;
          for (const Eigen::Vector3d& p : {c.points[1], c.points.back()})
            to_true = std::min(to_true, DistanceToPolyline(p, connected.canes[j].polyline));
        }
        std::printf("  case seed %llu: cane %zu (true %d, %.2f m, r %.4f) on %zu (true %d%s) parent pos %.2f/%.2f m, angle %.0f deg, true-route piece at %.3f m\n",
                    static_cast<unsigned long long>(seed), i, g, length, c.radii[1], parent, majority[parent],
                    inverted ? " INVERTED" : "", at_s, par.Length(), angle, to_true);
      }
    }
    for (const Cane& c : truth.canes)
      if (c.kind != CaneKind::kSpur) pb.truth_m += c.polyline.Length();
    parents.wrong_parent_m += pb.wrong_parent_m / pb.truth_m / count;
    parents.ghost_parent_m += pb.ghost_parent_m / pb.truth_m / count;
    if (verbose) {
      std::printf("seed %llu: pieces %.3f/%.3f assembled %.3f/%.3f connected %.3f/%.3f/%.3f "
                  "final %.3f/%.3f/%.3f attached %d (kept near %d) unattached %d inside %d; left-out recall "
                  "+%.3f; wrong-parent %.3f ghost-parent %.3f (of truth length)\n",
                  static_cast<unsigned long long>(seed), mp.cane_recall, mp.cane_precision,
                  ma.cane_recall, ma.cane_precision, mc.cane_recall, mc.cane_precision,
                  mc.connectivity, mf.cane_recall, mf.cane_precision, mf.connectivity,
                  summary.attached, summary.kept_near, summary.unattached, summary.inside_trunk_or_head,
                  recall_with_left_out - mc.cane_recall, pb.wrong_parent_m / pb.truth_m,
                  pb.ghost_parent_m / pb.truth_m);
    }
  }
  std::printf("mean over %d stops (recall / precision / connectivity):\n", count);
  std::printf("  pieces     %.3f / %.3f\n", pieces_row.recall, pieces_row.precision);
  std::printf("  assembled  %.3f / %.3f (with the silhouette trunk)\n", assembled_row.recall,
              assembled_row.precision);
  std::printf("  connected  %.3f / %.3f / %.3f; recall of canes left out or dropped: %.3f\n",
              connected_row.recall, connected_row.precision, connected_row.connectivity,
              unattached_recall);
  std::printf("  refined    %.3f / %.3f / %.3f\n", final_row.recall, final_row.precision,
              final_row.connectivity);
  std::printf("  hung on a wrong true cane: %.3f, on a ghost: %.3f (cane length / truth length)\n",
              parents.wrong_parent_m, parents.ghost_parent_m);
  const RouteLoss& r = route_loss;
  std::printf("  refined, recalled but unconnected (of truth length): unattached %.4f, merged "
              "child %.4f, ghost parent %.4f, true parent absent %.4f, far (> 3 cm) %.4f (> 15 cm "
              "%.4f, of which from the head %.4f), near %.4f; of the last three, the wrong parent "
              "merged with an ancestor %.4f\n",
              r.unattached, r.merged_child, r.ghost_parent, r.parent_absent, r.parent_far,
              r.parent_beyond, r.beyond_from_head, r.parent_near, r.merged_parent);
  std::printf("  of the last's canes from the head, by the hung cane's inner end from the model "
              "head (< 15 / 15-25 / 25-40 / > 40 cm): %.4f / %.4f / %.4f / %.4f; pointing at it "
              "(cos >= 0.8): %.4f / %.4f / %.4f / %.4f\n",
              r.from_head_by_reach[0], r.from_head_by_reach[1], r.from_head_by_reach[2],
              r.from_head_by_reach[3], r.from_head_pointing[0], r.from_head_pointing[1],
              r.from_head_pointing[2], r.from_head_pointing[3]);
  if (head_far_on) head_far.Print();
  if (head_far_csv) std::fclose(head_far_csv);
}

}  // namespace
}  // namespace vb::reconstruct
