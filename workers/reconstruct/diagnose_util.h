// SPDX-License-Identifier: Apache-2.0
// Test support for the diagnosis tools (*_diagnose_test.cc; docs/diagnosis.md): the set-ups they
// share. A rendered stop matched as the pipeline matches it; the stages after correspondence run
// one at a time, so that a report can look between them; every view pair's raw candidates; where
// a true 3D sample falls in each view (inside the image, on foreground, near which skeleton
// segment); option overrides from the environment. Diagnosis and tests only; every function is
// deterministic and holds no state, so reports may call them from any thread.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/geometry.h"
#include "core/vine_model.h"
#include "sim/rig.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// A stop rendered as the bench renders it (MakeRenderedStop) and matched as the pipeline matches
// it (MatchWithRigRefinement with `options`, no deadline).
struct RenderedMatch {
  SimulatedStop stop;
  MatchedStop matched;
  // The views the later stages see: matched.refined_views when the rig refinement re-expressed
  // them, else stop.views.
  const std::vector<View2D>& views() const {
    return matched.refined_views.empty() ? stop.views : matched.refined_views;
  }
};
// Errors: INTERNAL when the stop could not be rendered or its 2D stage failed (MakeRenderedStop
// gave no views), naming the seed; else MatchWithRigRefinement's.
absl::StatusOr<RenderedMatch> RenderAndMatch(uint64_t seed, bool images, bool fiducials,
                                             const ReconstructOptions& options);

// The assembled canes as the head reports set them up (HeadHull.DISABLED_Report,
// HeadExit.DISABLED_Report), with `options`' fields of each stage and no deadline: AssembleCanes
// on `pieces`, the canes mostly outside options.volume dropped, then GrowCaneEnds on `views`
// through `rig` when options.grow grows before connection (as ReconstructFromViews does; the
// depth sweep of step 4e is not run here, although options.sweep enables it by default).
struct GrownCanes {
  std::vector<Polyline3> canes;
  std::vector<Eigen::Vector3d> hints;  // every point of `canes`, in order: the head's hints
};
// Errors: AssembleCanes' and GrowCaneEnds'.
absl::StatusOr<GrownCanes> AssembleAndGrow(const std::vector<View2D>& views,
                                           const RigCalibration& rig,
                                           const std::vector<Piece3D>& pieces,
                                           const ReconstructOptions& options);

// The stages after correspondence as the diagnosis reports run them (not all of
// ReconstructFromViews: no depth sweep, no extension, no left-out wood), with `options`' fields of
// each stage and no deadline: AssembleCanes on `pieces`, the canes mostly outside options.volume
// dropped; ReconstructHeadAndTrunk on `views`, hinted by the assembled canes' points;
// PrepareCanes and FindJoins.
struct AssembledStop {
  std::vector<Polyline3> canes;  // assembled, inside the working volume
  HeadAndTrunk head;
  PreparedCanes prepared;
  std::vector<JoinCandidate> joins;  // FindJoins on `prepared`
};
// Errors: each stage's, as it returns them.
absl::StatusOr<AssembledStop> AssembleStop(const std::vector<View2D>& views,
                                           const RigCalibration& rig,
                                           const std::vector<Piece3D>& pieces,
                                           const ReconstructOptions& options);

// The tree BuildTree makes of `assembled` with `joins` (assembled.joins, or a report's changed
// copy; GapSupport on `views` through `rig`), and that tree after RefineModel on `views`.
struct ConnectedStop {
  VineModel connected;  // as BuildTree returned it
  VineModel refined;    // after RefineModel
  ConnectSummary summary;
};
// Errors: BuildTree's and RefineModel's.
absl::StatusOr<ConnectedStop> ConnectAndRefine(const std::vector<View2D>& views,
                                               const RigCalibration& rig,
                                               const AssembledStop& assembled,
                                               const std::vector<JoinCandidate>& joins,
                                               const ReconstructOptions& options);

// Each view sampled for the candidate search (ViewSamples, every `step_px`) through `rig`'s
// camera of the same index. The samples refer to `views`, which must outlive them.
std::vector<ViewSamples> SampleViews(const std::vector<View2D>& views, const RigCalibration& rig,
                                     double step_px);

// The raw candidates (FindCandidates with `options`) of every view pair a < b, in that order.
std::vector<MatchCandidate> RawCandidates(const std::vector<ViewSamples>& samples,
                                          const RigCalibration& rig,
                                          const CandidateOptions& options);

// The triangulated points of a candidate's hits, in order.
std::vector<Eigen::Vector3d> HitPoints(const MatchCandidate& candidate);

// Per view, the index of the skeleton segment near each pixel: each segment point's 7 x 7 square
// (3 px either way of its rounded position), a later segment overwriting an earlier one.
class SegmentMaps {
 public:
  explicit SegmentMaps(const std::vector<View2D>& views);
  // The segment near pixel (x, y) of view `view`; -1 if none or outside the image.
  int At(int view, int x, int y) const;

 private:
  std::vector<int> width_, height_;
  std::vector<std::vector<int>> index_;
};

// Where a 3D point falls in each view, projected through `rig` (the true rig in the reports).
struct SampleInViews {
  int in_image = 0;                   // views whose image holds its projection
  int foreground = 0;                 // of those, views with foreground within 2 px of it
  int skeleton = 0;                   // of those, views with a segment near it (SegmentMaps)
  std::vector<bool> inside;           // per view: the image holds its projection
  std::vector<bool> on_foreground;    // per view: foreground within 2 px (ForegroundWithin)
  std::vector<int> segment;           // per view: the segment near it, -1 if none or outside
  std::vector<Eigen::Vector2d> px;    // per view: its projection, where inside
};
// `views` and `maps` (SegmentMaps of those views) must have one entry per camera of `rig`.
SampleInViews LocateSample(const Eigen::Vector3d& p, const RigCalibration& rig,
                           const std::vector<View2D>& views, const SegmentMaps& maps);

// The unit tangent at points[i] of a sampled curve: the central difference, one-sided at the ends.
Eigen::Vector3d TangentAt(const std::vector<Eigen::Vector3d>& points, size_t i);

// |sin| of the angle in view a's image between a cane through p with tangent t and the epipolar
// line of view pair (a, b) through p's projection `px_a` (0: the cane runs along it, the pair
// cannot place it); cameras a and b of `rig`. Empty where a projection fails.
std::optional<double> EpipolarSin(const RigCalibration& rig, int a, int b,
                                  const Eigen::Vector3d& p, const Eigen::Vector3d& t,
                                  const Eigen::Vector2d& px_a);

// The true length of a stop's vine (trunk and canes, stop.scene.vine) as LyingAlongAnother
// samples it (every ~step_m along each cane, both ends included), each sample with what the true
// rig's views show of it. Canes with fewer than 2 samples are left out.
struct LengthSample {
  size_t cane = 0;    // index in stop.scene.vine.canes
  size_t index = 0;   // sample index along it (LyingAlongAnother's)
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d tangent = Eigen::Vector3d::UnitX();  // unit; p's neighbours half a step away
  double step_m = 0.0;    // the cane's sample spacing: its length / (samples - 1)
  double weight_m = 0.0;  // its share of the length: step_m, half that at either end
  int in_image = 0;       // views whose image holds its projection
  int along = 0;          // of those, views where it lies along another drawn cane (stop.drawn:
                          // the vine's and its neighbours'); 0 unless `neighbours`
  int along_own = 0;      // of those, views where it lies along another cane of the vine
};
// LyingAlongAnother with margin 2 px; `neighbours`: also against stop.drawn (fills `along`).
std::vector<LengthSample> SampleTrueLength(const SimulatedStop& stop, double step_m,
                                           bool neighbours);

// What the views show of a true sample, for the loss reports' first stages (FirstLostStage):
// LocateSample's counts, and where skeleton meets foreground, the pairs that could place it.
struct SampleEvidence {
  int in_image = 0;             // views whose image holds its projection
  int foreground = 0;           // of those, views with foreground within 2 px
  int skeleton = 0;             // views with foreground and a segment near it
  bool conditioned = false;     // a pair of `pairs` with EpipolarSin >= min_epipolar_sin
  std::vector<int> segment;     // per view: the segment near it where on foreground, else -1
  std::vector<std::pair<int, int>> pairs;  // view pairs a < b with a segment in both where
                                           // EpipolarSin could be measured, in order
};
// `at` is LocateSample of p (tangent t) through `rig` (the true rig in the reports).
SampleEvidence EvidenceOf(const SampleInViews& at, const RigCalibration& rig,
                          const Eigen::Vector3d& p, const Eigen::Vector3d& t,
                          double min_epipolar_sin);

// The stages the loss reports follow a true sample through (MatchLoss.DISABLED_Report,
// OverlapLoss.DISABLED_ByStage), in pipeline order; a sample is lost at the first it fails:
// in < 2 images, foreground in < 2 views, skeleton in < 2 views, no well-conditioned pair, no raw
// candidate near it, no fitted candidate near, none above the threshold, no selected piece near,
// not in the assembled canes and trunk, not in the connected tree, not after refinement.
// kLossKept: not lost; kLossStageCount: how many (indexes of per-stage arrays).
enum LossStage {
  kLossInImage, kLossForeground, kLossSkeleton, kLossConditioned, kLossRaw, kLossFitted,
  kLossProbable, kLossPiece, kLossAssembled, kLossConnected, kLossFinal, kLossKept,
  kLossStageCount
};

// Each stage's output as points (PointGrid: near = within 10 mm), for FirstLostStage.
struct StageGrids {
  PointGrid raw;        // raw candidates' hits (value 1)
  PointGrid fitted;     // fitted candidates' control points, valued by their probability
  PointGrid piece;      // selected pieces (1)
  PointGrid assembled;  // assembled canes and the trunk (1)
  PointGrid connected;  // BuildTree's canes (1)
  PointGrid final;      // the canes after RefineModel (1)
};
StageGrids MakeStageGrids(const std::vector<MatchCandidate>& raw,
                          const std::vector<ScoredCandidate>& scored,
                          const std::vector<Piece3D>& pieces, const AssembledStop& assembled,
                          const ConnectedStop& connected);

// The first stage at which sample p with `evidence` is lost (kLossKept if none); a fitted
// candidate near p counts only above `threshold` (1 / (1 + alpha)).
LossStage FirstLostStage(const Eigen::Vector3d& p, const SampleEvidence& evidence,
                         const StageGrids& grids, double threshold);

// Whether `b` holds both ends of `a` (exactly, to 1e-9 m): connection keeps a cane's points
// (reversed, with a base point added, or appended to its parent), so a connected polyline that
// holds an assembled cane's ends carries it. `a` must have points.
bool HoldsEnds(const Polyline3& a, const Polyline3& b);

// The 3D distance from p to the nearest cane of `vine` other than its cane `own` (axis to axis;
// 1e9 if none).
double NearestOtherCane(const VineModel& vine, size_t own, const Eigen::Vector3d& p);

// Whether p lies within `radius_m` of a cane of `canes` (DistanceToPolyline).
bool NearAnyCane(const Eigen::Vector3d& p, const std::vector<Cane>& canes,
                 double radius_m = 0.01);

// Distance from p to the nearest segment of the canes' polylines (1e9 if none); `nearest`, if
// given, gets that nearest point and `cane`, if given, the index in `canes` of the cane it lies
// on (both left as they are when there is no segment).
double DistanceToCanes(const Eigen::Vector3d& p, const std::vector<Cane>& canes,
                       Eigen::Vector3d* nearest = nullptr, int* cane = nullptr);
// The same over bare polylines; `line` gets the index in `lines`.
double DistanceToLines(const Eigen::Vector3d& p, const std::vector<Polyline3>& lines,
                       Eigen::Vector3d* nearest = nullptr, int* line = nullptr);

// Every polyline as a cane on a stand-in trunk (the first), so that recall and precision of a bag
// of unconnected polylines can be scored with the bench's metrics (core/model_metrics.h).
VineModel Flat(const std::vector<Polyline3>& lines);

// The simulator's default rig before 2026-11-22: at the vine's distance 0.8 m, triangle side
// 0.22 m, aimed at its own height.
sim::RigOptions OldRigOptions();

// Sets *field from the environment variable `name` when it is set (std::atof; an int std::atoi;
// a bool std::atoi != 0); leaves it as it is otherwise. Returns whether it was set.
bool OverrideFromEnv(const char* name, double* field);
bool OverrideFromEnv(const char* name, int* field);
bool OverrideFromEnv(const char* name, bool* field);

// A comma-separated list of numbers from the environment variable `name` (std::strtod; the list
// ends at the first item that is not a number), or `fallback` when it is not set.
std::vector<double> ListFromEnv(const char* name, std::vector<double> fallback);

}  // namespace vb::reconstruct
