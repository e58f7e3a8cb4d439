// SPDX-License-Identifier: Apache-2.0
// Candidate matches of 2D cane segments between two views, found along epipolar lines, after
// Botterill et al., "A Robot System for Pruning Grape Vines" (J. Field Robotics 2017),
// sec. 3.2.3. Everything here works in normalised, undistorted image coordinates
// (CameraCalibration::PixelToNormalised), where epipolar lines are straight. Internal to
// correspondence (correspondence.h); exposed for its tests and the classifier's training.
// Thread-compatible value types; the functions are pure.
#pragma once

#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// One View2D segment resampled at a fixed pixel step, in normalised coordinates.
struct SegmentSamples {
  std::vector<Eigen::Vector2d> pixel;       // resampled skeleton points, pixels
  std::vector<Eigen::Vector2d> normalised;  // the same points, normalised coordinates
  std::vector<Eigen::Vector2d> tangent;     // unit tangent in normalised coordinates
  std::vector<double> width;                // foreground width, normalised units
  std::vector<double> arc_px;               // pixel arc length from the segment start
};

// A view's segments resampled, with a uniform grid over their pieces (sample k to k + 1) for
// fast line and nearest-point queries.
class ViewSamples {
 public:
  // With `halves` (may be null: none), their paths are resampled after the view's segments and
  // numbered from view.segments.size() on, as correspondence's second pass searches them.
  ViewSamples(const View2D& view, const CameraCalibration& camera, double step_px,
              const std::vector<StrandHalf>* halves = nullptr);

  const std::vector<SegmentSamples>& segments() const { return segments_; }
  // Pieces (segment, k) whose bounding boxes touch the grid cells the segment p0-p1 passes
  // through. Each piece once; order unspecified. `out` is cleared first.
  void PiecesNearSegment(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                         std::vector<std::pair<int, int>>* out) const;
  // Nearest piece within `radius` (normalised units) of p: returns false if none; otherwise its
  // distance, the piece's unit direction and, if `closest` is given, its point nearest p.
  bool NearestPiece(const Eigen::Vector2d& p, double radius, double* distance,
                    Eigen::Vector2d* direction, Eigen::Vector2d* closest = nullptr) const;

 private:
  void CellOf(const Eigen::Vector2d& p, int* cx, int* cy) const;

  std::vector<SegmentSamples> segments_;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  double cell_ = 1.0;
  int nx_ = 0;
  int ny_ = 0;
  std::vector<std::vector<std::pair<int, int>>> cells_;
  mutable std::vector<int> stamp_;     // per segment*piece query stamps (dedup)
  mutable std::vector<int> piece_base_;  // first piece index of each segment in stamp_
  mutable int query_ = 0;
};

// One sample of segment_a whose epipolar segment crossed segment_b.
struct EpipolarHit {
  int sample_a = -1;                           // index into SegmentSamples of segment_a
  Eigen::Vector2d xa = Eigen::Vector2d::Zero();  // normalised point in view a
  Eigen::Vector2d xb = Eigen::Vector2d::Zero();  // crossing in view b, normalised
  Eigen::Vector2d normal_b = Eigen::Vector2d::Zero();  // unit normal of segment_b there
  Eigen::Vector3d point = Eigen::Vector3d::Zero();     // triangulated, platform frame
  double arc_a_px = 0.0;                       // position along segment_a / segment_b
  double arc_b_px = 0.0;
  double depth_a = 0.0;                        // distance along the ray of view a, metres
  double width_a = 0.0;                        // normalised widths in a and b
  double width_b = 0.0;
  double sin_a = 0.0;                          // |sin| of the angle segment / epipolar line
  double sin_b = 0.0;
};

// A candidate match: a run of consecutive samples of segment_a whose epipolar segments cross
// segment_b at consistent depths.
struct MatchCandidate {
  int view_a = -1;
  int segment_a = -1;
  int view_b = -1;
  int segment_b = -1;
  double begin_a_px = 0.0;  // covered arc-length interval of segment_a and of segment_b
  double end_a_px = 0.0;
  double begin_b_px = 0.0;
  double end_b_px = 0.0;
  double length_a_px = 0.0;  // full lengths of the two segments
  double length_b_px = 0.0;
  std::vector<EpipolarHit> hits;  // ordered along segment_a
};

struct CandidateOptions {
  WorkingVolume volume;            // depth range of the epipolar segments
  double min_epipolar_sin = 0.2;   // samples more parallel to the epipolar line are skipped
  int min_hits = 5;                // shortest run kept
  int max_gap_samples = 3;         // samples a run may skip
  // Samples not searched (min_epipolar_sin) that a run may skip on top of max_gap_samples: where
  // a segment turns along the epipolar line for a while, the run resumes beyond (0: it breaks).
  int max_ill_conditioned_gap_samples = 0;
  double max_depth_slope = 3.0;    // depth change per unit of lateral distance along a run
  double depth_tolerance_m = 0.006;  // plus this per step
};

// Candidates of view pair (a, b) (a's segments sampled, b's crossed), in deterministic order.
std::vector<MatchCandidate> FindCandidates(int view_a, const ViewSamples& a,
                                           const CameraCalibration& camera_a, int view_b,
                                           const ViewSamples& b,
                                           const CameraCalibration& camera_b,
                                           const CandidateOptions& options);

}  // namespace vb::reconstruct
