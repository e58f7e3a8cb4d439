// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/match_classifier.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "Eigen/Core"
#include "workers/reconstruct/logistic.h"

namespace vb::reconstruct {

MatchClassifier DefaultMatchClassifier() {
  // Trained by MatchClassifier.DISABLED_TrainOnSimulatedStops (match_classifier_test.cc;
  // VB_TRAIN_INPUT=labels,images, VB_TRAIN_PASS=second, the default) on candidates of the
  // pipeline's second pass (after MatchWithRigRefinement) on rendered stops with the platform's
  // fiducials, seeds 1000-1099, vine 1, calibration 1 px off: once on the renderer's label images
  // and once on the segmenter's output, the default rig of 2026-11-22, with the refinement
  // features 19-21: 181348 candidates, 29516 right; training AUC 0.986 (multi-view), 0.972
  // (two-view) (VB_DEV_STOPS=0).
  MatchClassifier c;
  c.multi_view = {-2.3742, -0.2758, -0.2329, 0.1134, -0.0223, -8.1053, -0.2816, -1.2012, 3.7284, 1.0856, 0.8379, -6.5119, 5.7752, -7.4007, 0.2930, -1.4455, -0.4452, 1.6496, -16.7099, 1.1531, -2.6993, -2.5107};
  c.two_view = {-5.3968, -0.2740, -1.2360, -0.1466, 0.7152, -9.8974, -0.1747, 0.7356, 4.6802, 1.1054, 1.1247, 0.0000, 0.0000, 0.0000, 0.0000, -1.5798, 0.0000, 0.0000, -27.5482, 0.0000, 0.0000, 0.0000};
  c.multi_view_quadratic = DefaultQuadraticMatchModel();
  return c;
}

MatchClassifier CalibratedRigMatchClassifier() {
  // Trained by MatchClassifier.DISABLED_TrainOnSimulatedStops with VB_TRAIN_PASS=first on
  // candidates of the real 2D stage (ExtractStructure) on rendered stops without fiducials, seeds
  // 1000-1099, vine 1, calibration 1 px off, the rig as calibrated: once on the renderer's label
  // images and once on the segmenter's output: 179482 candidates, 21702 right; training AUC 0.972
  // (multi-view), 0.957 (two-view). These were the default weights until 2026-11-22.
  MatchClassifier c;
  c.multi_view = {-3.5899, -0.2461, -0.2559, 0.0031, 0.0655, -7.3093, -0.3162, 1.5653, 1.7336, 0.8547, 0.9052, -5.9593, 5.0423, -3.8213, -0.2812, -0.9800, 0.8279, 1.7564, -13.6510};
  c.two_view = {-5.9586, -0.3003, -0.8521, -0.2348, 0.5206, -8.4593, -0.2857, 2.7239, 2.9663, 1.0360, 1.1333, 0.0000, 0.0000, 0.0000, 0.0000, -1.0951, 0.0000, 0.0000, -22.1416};
  return c;
}

namespace {

// Mean over views of in_image * centreline_px / 10 px: feature 13 of ComputeMatchFeatures.
double WeightedCentreline(const std::vector<ViewSupport>& supports) {
  double centreline = 0.0;
  for (const ViewSupport& s : supports) centreline += s.in_image * s.centreline_px;
  return supports.empty() ? 0.0 : centreline / static_cast<double>(supports.size()) / 10.0;
}

}  // namespace

RefinementAgreement MeasureRefinement(const MatchCandidate& candidate, const PolylineFit& fit,
                                      const CameraCalibration& camera_a,
                                      const CameraCalibration& camera_b,
                                      const std::vector<OtherView>& others,
                                      const std::vector<ViewSupport>& before,
                                      const PolylineFitOptions& fit_options,
                                      const OtherViewFitOptions& other_options) {
  RefinementAgreement out;
  if (others.empty() || other_options.rounds <= 0 || before.size() != others.size() ||
      std::any_of(others.begin(), others.end(), [](const OtherView& o) { return !o.view; })) {
    return out;
  }
  PolylineFit refined = fit;
  if (RefineInOtherViews(candidate, camera_a, camera_b, others, fit_options, other_options,
                         &refined) <= 0) {
    return out;
  }
  out.kept = true;
  const size_t n = std::min(fit.points.size(), refined.points.size());
  for (size_t i = 0; i < n; ++i) out.mean_shift_m += (refined.points[i] - fit.points[i]).norm();
  out.mean_shift_m /= std::max<size_t>(1, n);
  std::vector<ViewSupport> after;
  after.reserve(others.size());
  for (size_t v = 0; v < others.size(); ++v) {
    after.push_back(CheckInView(refined.points, *others[v].view, *others[v].samples,
                                *others[v].camera));
  }
  out.centreline_gain = WeightedCentreline(before) - WeightedCentreline(after);
  return out;
}

MatchFeatures ComputeMatchFeatures(const MatchCandidate& candidate, const PolylineFit& fit,
                                   const std::vector<ViewSupport>& others,
                                   const WorkingVolume& volume,
                                   const RefinementAgreement& refinement) {
  MatchFeatures f{};
  const auto& hits = candidate.hits;
  const double n = std::max<double>(1.0, hits.size());
  f[0] = 1.0;
  f[1] = std::log(std::max(fit.length_m, 1e-3) / 0.1);
  f[2] = std::log(0.25 + fit.rms_a_px);
  f[3] = std::log(0.25 + fit.rms_b_px);
  f[4] = std::log(0.25 + fit.max_residual_px);
  f[5] = fit.width_log_ratio;
  f[6] = std::log1p(fit.turning_rad / std::max(fit.length_m, 0.05));
  double sin_a = 0.0, sin_b = 0.0, radius = 0.0;
  for (const EpipolarHit& hit : hits) {
    sin_a += hit.sin_a;
    sin_b += hit.sin_b;
  }
  for (double r : fit.hit_radii) radius += r;
  f[7] = std::min(sin_a, sin_b) / n;
  if (!hits.empty()) f[8] = n / (hits.back().sample_a - hits.front().sample_a + 1.0);
  f[9] = (candidate.end_a_px - candidate.begin_a_px) / std::max(1.0, candidate.length_a_px);
  f[10] = (candidate.end_b_px - candidate.begin_b_px) / std::max(1.0, candidate.length_b_px);
  double in_image = 0.0, foreground = 0.0, centreline = 0.0, tangent = 0.0, near = 0.0,
         aligned = 0.0;
  for (const ViewSupport& s : others) {
    near += s.in_image * s.near;
    aligned += s.in_image * s.aligned;
    in_image += s.in_image;
    foreground += s.in_image * s.foreground;
    centreline += s.in_image * s.centreline_px;
    tangent += s.in_image * s.tangent;
  }
  if (in_image > 0.0) {
    const double views = static_cast<double>(others.size());
    f[11] = in_image / views;
    f[12] = f[11] * foreground / in_image;
    f[13] = f[11] * centreline / in_image / 10.0;
    f[14] = f[11] * tangent / in_image;
    f[16] = f[11] * near / in_image;
    f[17] = f[11] * aligned / in_image;
  }
  double mean_y = 0.0;
  for (const Eigen::Vector3d& p : fit.points) mean_y += p.y();
  mean_y /= std::max<size_t>(1, fit.points.size());
  const double half_y = 0.5 * std::max(1e-3, volume.box.max().y() - volume.box.min().y());
  const double offset = (mean_y - 0.5 * (volume.box.min().y() + volume.box.max().y())) / half_y;
  f[18] = offset * offset;
  f[15] = std::log(std::max(radius / std::max<size_t>(1, fit.hit_radii.size()), 1e-4) / 0.005);
  if (refinement.kept) {
    f[19] = 1.0;
    f[20] = std::log1p(refinement.mean_shift_m / 0.005);
    f[21] = refinement.centreline_gain;
  }
  for (double& v : f) {
    if (!std::isfinite(v)) v = 0.0;
  }
  return f;
}

double MatchProbability(const MatchFeatures& features, const MatchFeatures& weights) {
  return LogisticProbability(features, weights);
}

double MatchClassifier::Probability(const MatchFeatures& features, bool multi) const {
  if (!multi) return MatchProbability(features, two_view);
  if (!multi_view_quadratic.empty()) return multi_view_quadratic.Probability(features);
  return MatchProbability(features, multi_view);
}

absl::Status MatchClassifier::Validate() const {
  for (int i = 0; i < kMatchFeatureCount; ++i) {
    if (!std::isfinite(multi_view[i]) || !std::isfinite(two_view[i])) {
      return absl::InvalidArgumentError(absl::StrCat("weight ", i, " not finite"));
    }
  }
  if (multi_view_quadratic.empty()) return absl::OkStatus();
  return multi_view_quadratic.Validate(kMatchFeatureCount);
}

absl::StatusOr<MatchFeatures> TrainMatchClassifier(const std::vector<LabelledMatch>& examples,
                                                   const TrainOptions& options) {
  return TrainLogistic<kMatchFeatureCount>(examples, options.l2, options.iterations, "matches",
                                           "TrainMatchClassifier");
}

double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& polyline) {
  const auto& q = polyline.points;
  if (q.empty()) return std::numeric_limits<double>::infinity();
  if (q.size() == 1) return (p - q[0]).norm();
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < q.size(); ++i) best = std::min(best, PointSegmentDistance(p, q[i], q[i + 1]));
  return best;
}

bool IsRightMatch(const std::vector<Eigen::Vector3d>& points,
                  const std::vector<const Polyline3*>& truth, double tolerance_m,
                  double min_fraction) {
  if (points.empty()) return false;
  Eigen::AlignedBox3d bounds;
  for (const Eigen::Vector3d& p : points) bounds.extend(p);
  const int allowed_misses =
      static_cast<int>(std::floor((1.0 - min_fraction) * static_cast<double>(points.size())));
  for (const Polyline3* cane : truth) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& q : cane->points) box.extend(q);
    box.min().array() -= tolerance_m;
    box.max().array() += tolerance_m;
    if (!box.intersects(bounds)) continue;
    int misses = 0;
    for (const Eigen::Vector3d& p : points) {
      if (DistanceToPolyline(p, *cane) > tolerance_m && ++misses > allowed_misses) break;
    }
    if (misses <= allowed_misses) return true;
  }
  return false;
}

}  // namespace vb::reconstruct
