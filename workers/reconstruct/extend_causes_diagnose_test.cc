// SPDX-License-Identifier: Apache-2.0
// Diagnosis tool, not a test: why the single-view extension (extend.h) adds wrong length, on
// rendered stops (VB_SEED, VB_STOPS, VB_INPUT as ReportStopsFromEnv; images by default). Run with
// --gtest_also_run_disabled_tests --gtest_filter='Extend.DISABLED_Causes'. Tuning seeds only.
//
// Per stop: the model without the extension, then ExtendCanes on a copy for each arm of VB_ARMS
// (';'-separated, each "key=value,..." on the default options, enabled; see ParseArm; unset: the
// defaults): paired changes of recall, precision and connectivity. For the first arm, every added point is right (within 10 mm of a true trunk or cane of
// this vine, as the metrics count) or wrong, and a wrong point gets one cause, the first that
// holds:
//   tip:*     the cane's tip was already wrong; split by what the tip lies on: a neighbour's cane
//             (tip:neighbour), within 15 mm of a wire or post (tip:trellis), on a ray of some
//             camera through a true cane (tip:depth, a mis-depthed end) or nothing (tip:ghost);
//   back      the added stretch turns back (its direction against the tip's tangent);
//   depth     the followed view's ray passes within 10 mm of the tip's true cane: the 2D path is
//             right, the depth diverged;
//   jump      the ray passes within 10 mm of another true cane of this vine: the path switched;
//   neighbour the ray passes a neighbour's cane;
//   trellis   the ray passes within 10 mm of a wire or a post's surface;
//   other     none of these.
// Prints one TIP line per extended tip (VB_VERBOSE) with its features and wrong length by cause,
// then totals per stop.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/model_metrics.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/extend.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

double Trellis(const Eigen::Vector3d& p, const VineModel& truth) {
  double best = 1e9;
  for (const Wire& w : truth.wires)
    for (size_t i = 0; i + 1 < w.points.size(); ++i) {
      double t = 0;
      best = std::min(best, PointSegmentDistance(p, w.points[i], w.points[i + 1], &t) - w.radius);
    }
  for (const Post& post : truth.posts) {
    double t = 0;
    best = std::min(best, PointSegmentDistance(p, post.base, post.top, &t) - post.radius);
  }
  return best;
}

// Distance from q to the ray from c along unit dir (ahead of c only).
double RayDistance(const Eigen::Vector3d& q, const Eigen::Vector3d& c, const Eigen::Vector3d& dir) {
  const double along = (q - c).dot(dir);
  if (along <= 0) return (q - c).norm();
  return ((q - c) - along * dir).norm();
}

// Does the ray from c through p pass within tol of any sample of `canes` (only cane `only` if
// >= 0, all but `except` if >= 0)?
bool RayHits(const Eigen::Vector3d& c, const Eigen::Vector3d& p,
             const std::vector<std::vector<Eigen::Vector3d>>& samples, int only, int except,
             double tol) {
  const Eigen::Vector3d dir = (p - c).normalized();
  for (size_t k = 0; k < samples.size(); ++k) {
    if (only >= 0 && static_cast<int>(k) != only) continue;
    if (except >= 0 && static_cast<int>(k) == except) continue;
    for (const Eigen::Vector3d& q : samples[k])
      if (RayDistance(q, c, dir) <= tol) return true;
  }
  return false;
}

bool RayHitsTrellis(const Eigen::Vector3d& c, const Eigen::Vector3d& p, const VineModel& truth) {
  const Eigen::Vector3d dir = (p - c).normalized();
  // Walk the ray near p (+-0.5 m) every 5 mm.
  const double at = (p - c).norm();
  for (double s = std::max(0.05, at - 0.5); s <= at + 0.5; s += 0.005)
    if (Trellis(c + s * dir, truth) <= 0.010) return true;
  return false;
}

bool InTree(const VineModel& model, size_t c) {
  std::map<int64_t, size_t> by_id;
  for (size_t i = 0; i < model.canes.size(); ++i) by_id[model.canes[i].id.value] = i;
  size_t at = c;
  for (int guard = 0; guard < 1000; ++guard) {
    if (model.canes[at].kind == CaneKind::kTrunk) return true;
    if (!model.canes[at].parent_id) return false;
    const auto it = by_id.find(model.canes[at].parent_id->value);
    if (it == by_id.end()) return false;
    at = it->second;
  }
  return false;
}

const char* StopName(ExtendStop stop) {
  switch (stop) {
    case ExtendStop::kPathEnd: return "path_end";
    case ExtendStop::kMaxLength: return "max_length";
    case ExtendStop::kOtherCane: return "other_cane";
    case ExtendStop::kUncertain: return "uncertain";
    case ExtendStop::kVolume: return "volume";
    case ExtendStop::kContradicted: return "contradicted";
  }
  return "?";
}

// Options of one arm: "key=value,key=value" with keys sd, dd, len, turn, other, background,
// support, span, row, plane (the ExtendOptions fields), on the defaults.
ExtendOptions ParseArm(const std::string& text) {
  ExtendOptions ext;
  ext.enabled = true;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = item.substr(0, eq);
    const double value = std::atof(item.c_str() + eq + 1);
    if (key == "sd") ext.max_depth_sd_m = value;
    if (key == "dd") ext.second_difference_sd_m = value;
    if (key == "len") ext.max_length_m = value;
    if (key == "turn") ext.max_turn_rad = value;
    if (key == "other") ext.other_cane_px = value;
    if (key == "background") ext.background_px = value;
    if (key == "support") ext.max_support_px = value;
    if (key == "span") ext.support_span_m = value;
    if (key == "row") ext.max_tip_row_distance_m = value;
    if (key == "plane") ext.max_tip_out_of_plane = value;
  }
  return ext;
}

TEST(Extend, DISABLED_Causes) {
  const auto [first, count, images, fiducials] = ReportStopsFromEnv(1300, 10, true);
  // VB_ARMS: arms separated by ';' (ParseArm); the first gets the causes and the TIP lines.
  std::vector<std::string> arm_texts;
  {
    const char* arms = std::getenv("VB_ARMS");
    std::stringstream in(arms ? arms : "");
    std::string item;
    while (std::getline(in, item, ';')) arm_texts.push_back(item);
    if (arm_texts.empty()) arm_texts.push_back("");
  }
  std::vector<ExtendOptions> arms;
  for (const std::string& t : arm_texts) arms.push_back(ParseArm(t));
  std::vector<std::vector<double>> arm_dr(arms.size()), arm_dp(arms.size()), arm_dc(arms.size());
  std::vector<double> arm_added(arms.size()), arm_right(arms.size());
  const ExtendOptions& ext = arms.front();
  const bool verbose = std::getenv("VB_VERBOSE") != nullptr;
  const std::vector<std::string> causes = {"tip:neighbour", "tip:trellis", "tip:depth",
                                           "tip:ghost",     "back",        "depth",
                                           "jump",          "neighbour",   "trellis",
                                           "other"};
  std::map<std::string, double> wrong;
  double added = 0, right = 0, d_recall = 0, d_precision = 0;
  std::vector<double> depth_first_wrong;  // arc from the tip of a right tip's first depth error
  ReconstructOptions options;
  options.extend.enabled = false;
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first + k;
    const SimulatedStop stop = MakeRenderedStop(seed, images, fiducials);
    ASSERT_FALSE(stop.views.empty());
    const auto result = ReconstructFromViews(stop.views, stop.rig, options, Deadline::Infinite());
    ASSERT_TRUE(result.ok()) << result.status();
    const VineModel& truth = stop.scene.vine;
    std::vector<Cane> neighbour_canes;
    for (const VineModel& n : stop.scene.neighbours)
      neighbour_canes.insert(neighbour_canes.end(), n.canes.begin(), n.canes.end());
    std::vector<std::vector<Eigen::Vector3d>> true_samples, neighbour_samples;
    for (const Cane& c : truth.canes) true_samples.push_back(c.polyline.Sample(0.005));
    for (const Cane& c : neighbour_canes) neighbour_samples.push_back(c.polyline.Sample(0.005));
    const auto before = EvaluateReconstruction(result->model, truth);
    ASSERT_TRUE(before.ok());
    for (size_t a = 1; a < arms.size(); ++a) {
      VineModel m = result->model;
      ExtendSummary sum;
      ASSERT_TRUE(ExtendCanes(stop.views, result->rig, options.volume, arms[a], &m, &sum).ok());
      const auto after = EvaluateReconstruction(m, truth);
      ASSERT_TRUE(after.ok());
      arm_dr[a].push_back(after->cane_recall - before->cane_recall);
      arm_dp[a].push_back(after->cane_precision - before->cane_precision);
      arm_dc[a].push_back(after->connectivity - before->connectivity);
      arm_added[a] += sum.added_length_m;
      for (const ExtendedTip& tip : sum.extended)
        for (int i = tip.first_point; i < tip.first_point + tip.points; ++i)
          arm_right[a] += (m.canes[tip.cane].polyline.points[i] -
                           m.canes[tip.cane].polyline.points[i - 1])
                              .norm() *
                          (DistanceToCanes(m.canes[tip.cane].polyline.points[i], truth.canes) <=
                           0.010);
    }
    VineModel model = result->model;
    ExtendSummary summary;
    ASSERT_TRUE(ExtendCanes(stop.views, result->rig, options.volume, ext, &model, &summary).ok());
    const auto after = EvaluateReconstruction(model, truth);
    ASSERT_TRUE(after.ok());
    d_recall += after->cane_recall - before->cane_recall;
    d_precision += after->cane_precision - before->cane_precision;
    arm_dr[0].push_back(after->cane_recall - before->cane_recall);
    arm_dp[0].push_back(after->cane_precision - before->cane_precision);
    arm_dc[0].push_back(after->connectivity - before->connectivity);
    arm_added[0] += summary.added_length_m;
    for (const ExtendedTip& tip : summary.extended) {
      const Polyline3& line = model.canes[tip.cane].polyline;
      const Eigen::Vector3d tip_point = line.points[tip.first_point - 1];
      const Eigen::Vector3d tangent =
          (tip_point - line.PointAt(std::max(0.0, result->model.canes[tip.cane].polyline.Length() -
                                                      0.03)))
              .normalized();
      int tip_cane = -1;
      const bool tip_right = DistanceToCanes(tip_point, truth.canes, nullptr, &tip_cane) <= 0.010;
      std::string tip_cause;
      if (!tip_right) {
        bool on_ray = false;
        for (const CameraCalibration& camera : stop.true_rig.cameras)
          on_ray |= RayHits(camera.CentreInPlatform(), tip_point, true_samples, -1, -1, 0.010);
        tip_cause = DistanceToCanes(tip_point, neighbour_canes) <= 0.010 ? "tip:neighbour"
                    : Trellis(tip_point, truth) <= 0.015                  ? "tip:trellis"
                    : on_ray                                              ? "tip:depth"
                                                                          : "tip:ghost";
      }
      const Eigen::Vector3d centre = stop.true_rig.cameras[tip.view].CentreInPlatform();
      double len = 0, len_right = 0, first_wrong = -1;
      std::map<std::string, double> mine;
      for (int i = tip.first_point; i < tip.first_point + tip.points; ++i) {
        const Eigen::Vector3d& p = line.points[i];
        const double step = (p - line.points[i - 1]).norm();
        len += step;
        if (DistanceToCanes(p, truth.canes) <= 0.010) {
          len_right += step;
          continue;
        }
        std::string cause;
        if (!tip_right) {
          cause = tip_cause;
        } else if ((p - line.points[i - 1]).dot(tangent) < 0) {
          cause = "back";
        } else if (RayHits(centre, p, true_samples, tip_cane, -1, 0.010)) {
          cause = "depth";
          if (first_wrong < 0) first_wrong = len;
        } else if (RayHits(centre, p, true_samples, -1, tip_cane, 0.010)) {
          cause = "jump";
        } else if (RayHits(centre, p, neighbour_samples, -1, -1, 0.010)) {
          cause = "neighbour";
        } else if (RayHitsTrellis(centre, p, truth)) {
          cause = "trellis";
        } else {
          cause = "other";
        }
        mine[cause] += step;
        wrong[cause] += step;
      }
      added += len;
      right += len_right;
      arm_right[0] += len_right;
      if (first_wrong >= 0) depth_first_wrong.push_back(first_wrong);
      if (!verbose) continue;
      // The support of the tip as it was (the cane before the extension appended to it).
      const TipSupport support =
          TipSupportOf(result->model.canes[tip.cane].polyline, stop.views, result->rig, 0.03);
      // In the other views: the tip's distance to the image border and to the nearest skeleton
      // end or junction; the share of added points inside another image.
      double border_px = 1e9, node_px = 1e9;
      for (size_t w = 0; w < stop.views.size(); ++w) {
        if (static_cast<int>(w) == tip.view) continue;
        const CameraCalibration& camera = result->rig.cameras[w];
        const auto uv = camera.Project(tip_point);
        if (!uv || !camera.InImage(*uv)) continue;
        border_px = std::min({border_px, uv->x(), uv->y(), camera.image_width - 1 - uv->x(),
                              camera.image_height - 1 - uv->y()});
        for (const Node2D& node : stop.views[w].nodes)
          node_px = std::min(node_px, (node.position - *uv).norm());
      }
      int in_other = 0;
      for (int i = tip.first_point; i < tip.first_point + tip.points; ++i)
        for (size_t w = 0; w < stop.views.size(); ++w) {
          if (static_cast<int>(w) == tip.view) continue;
          const auto uv = result->rig.cameras[w].Project(line.points[i]);
          if (uv && result->rig.cameras[w].InImage(*uv)) {
            ++in_other;
            break;
          }
        }
      int children = 0;
      for (const Cane& other : model.canes)
        children += other.parent_id && *other.parent_id == model.canes[tip.cane].id;
      std::printf(
          "TIP stop %llu cane %d view %d stop %s len %.3f right %.3f tip_right %d tip_cause %s "
          "in_tree %d x %.3f y %.3f z %.3f tx %.2f ty %.2f tz %.2f cane_len %.3f radius %.4f "
          "seeing %d support_px %.2f children %d trellis_mm %.1f first_wrong %.3f border_px %.0f "
          "node_px %.1f in_other %.2f",
          static_cast<unsigned long long>(seed), tip.cane, tip.view, StopName(tip.stop), len,
          len_right, tip_right, tip_right ? "-" : tip_cause.c_str(),
          InTree(model, tip.cane), tip_point.x(), tip_point.y(), tip_point.z(), tangent.x(),
          tangent.y(), tangent.z(), result->model.canes[tip.cane].polyline.Length(),
          line.radii[tip.first_point - 1], support.views, support.worst_mean_px, children,
          1000 * Trellis(tip_point, truth), first_wrong, border_px, node_px,
          double(in_other) / std::max(1, tip.points));
      for (const std::string& c : causes) std::printf(" %s %.3f", c.c_str(), mine[c]);
      std::printf("\n");
    }
  }
  std::printf("stops %llu-%llu (%s): recall %+.4f precision %+.4f (means over stops)\n",
              static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + count - 1), images ? "images" : "labels",
              d_recall / count, d_precision / count);
  std::printf("added %.3f m/stop, right %.3f m/stop (%.2f); wrong by cause, m/stop:\n",
              added / count, right / count, added > 0 ? right / added : 0.0);
  for (const std::string& c : causes) std::printf("  %-14s %.4f\n", c.c_str(), wrong[c] / count);
  auto mean_se = [](const std::vector<double>& v) {
    double m = 0, s2 = 0;
    for (double x : v) m += x;
    m /= std::max<size_t>(1, v.size());
    for (double x : v) s2 += (x - m) * (x - m);
    return std::make_pair(m, v.size() > 1 ? std::sqrt(s2 / (v.size() - 1) / v.size()) : 0.0);
  };
  for (size_t a = 0; a < arms.size(); ++a) {
    const auto [dr, dr_se] = mean_se(arm_dr[a]);
    const auto [dp, dp_se] = mean_se(arm_dp[a]);
    const auto [dc, dc_se] = mean_se(arm_dc[a]);
    std::printf(
        "ARM [%s]: recall %+.4f +- %.4f precision %+.4f +- %.4f connectivity %+.4f +- %.4f; "
        "added %.3f m/stop, %.2f right\n",
        arm_texts[a].c_str(), dr, dr_se, dp, dp_se, dc, dc_se, arm_added[a] / count,
        arm_added[a] > 0 ? arm_right[a] / arm_added[a] : 0.0);
  }
  std::sort(depth_first_wrong.begin(), depth_first_wrong.end());
  if (!depth_first_wrong.empty())
    std::printf("depth errors from right tips: %zu stretches, first wrong at median %.3f m\n",
                depth_first_wrong.size(), depth_first_wrong[depth_first_wrong.size() / 2]);
}

}  // namespace
}  // namespace vb::reconstruct
