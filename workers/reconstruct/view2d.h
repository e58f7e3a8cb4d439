// SPDX-License-Identifier: Apache-2.0
// The 2D evidence of one camera view, as the reconstruction stages pass it on: the per-pixel
// classes from segmentation (segmenter.h) and the structure extracted from them
// (structure2d.h): the foreground skeleton as a graph of segments with widths, the wires and
// posts as lines, and the thick region where the head and trunk are. Pixel coordinates follow
// core/calibration.h (pixel centres at integers, x right, y down). Plain value types.
#pragma once

#include <cstdint>
#include <vector>

#include "Eigen/Core"

namespace vb::reconstruct {

// Pixel classes of the segmenter. kForeground is wood: canes, trunk, head (of this vine or a
// neighbour). Posts have a class of their own (see docs/reconstruction.md).
enum class PixelClass : uint8_t { kBackground = 0, kForeground = 1, kWire = 2, kPost = 3 };
inline constexpr int kPixelClassCount = 4;

struct ClassImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> data;  // PixelClass values, row-major

  ClassImage() = default;
  ClassImage(int w, int h) : width(w), height(h), data(static_cast<size_t>(w) * h, 0) {}
  PixelClass at(int x, int y) const {
    return static_cast<PixelClass>(data[static_cast<size_t>(y) * width + x]);
  }
  void set(int x, int y, PixelClass c) {
    data[static_cast<size_t>(y) * width + x] = static_cast<uint8_t>(c);
  }
};

// One path of the foreground skeleton between two nodes (ends or junctions): a piece of cane,
// trunk or head outline as seen in this view.
struct Segment2D {
  std::vector<Eigen::Vector2d> points;  // skeleton path in pixels, spacing ~1-2 px, >= 2 points
  std::vector<double> widths_px;        // foreground width across the path at each point
  int node_begin = -1;                  // index into View2D::nodes of points.front()
  int node_end = -1;                    // index into View2D::nodes of points.back()
};

// An end (one segment) or junction (three or more) of the skeleton graph.
struct Node2D {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // pixels
  std::vector<int> segments;                           // indices into View2D::segments
};

// A straight structure (wire or post axis) in normalised, undistorted image coordinates
// (CameraCalibration::PixelToNormalised), where straight 3D lines stay straight.
struct Line2D {
  Eigen::Vector3d line = Eigen::Vector3d::Zero();  // l . (x, y, 1) = 0, with |(l0, l1)| = 1
  Eigen::Vector2d begin = Eigen::Vector2d::Zero();  // extent of the support, normalised coords
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
  double width_px = 0.0;   // mean width across the line, pixels
  int support_px = 0;      // number of class pixels explained by the line
  // The observed centre of the wire or post in pixels, every ~8 px along it, in order: what the
  // straight line was fitted to, kept in pixels so that a later correction of the calibration
  // (rig_refine.h) can compare against what was seen, not against a line straightened through
  // the old lens model. May be empty (then the line stands for its pixels).
  std::vector<Eigen::Vector2d> centre_px;
};

// One of the platform's fiducials (RigCalibration::fiducials) found in this view (fiducials.h).
struct FiducialObservation {
  int fiducial = -1;                                      // index into RigCalibration::fiducials
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();        // detected centre, pixels
  Eigen::Vector2d expected_px = Eigen::Vector2d::Zero();  // projection through the calibration
};

// One of the two halves of a skeleton stretch where two canes lie side by side in the view and
// the skeleton runs between them (strand_halves.h): each half follows one cane's axis, w/4 off the
// skeleton across a strand w wide, w/2 wide. Correspondence searches halves like segments (in its
// second pass), numbered after the view's own segments.
struct StrandHalf {
  Segment2D path;      // the half's centre line and widths; node_begin/node_end are -1
  int parent = -1;     // index into View2D::segments of the halved stretch's segment
  int sibling = -1;    // index into View2D::strand_halves of the other half
  std::vector<Eigen::Vector2d> to_sibling_px;  // per path point: the step to the sibling's, px
};

struct View2D {
  int width = 0;
  int height = 0;
  ClassImage classes;
  std::vector<Segment2D> segments;
  std::vector<Node2D> nodes;
  std::vector<Line2D> wires;
  std::vector<Line2D> posts;
  // 1 where the foreground is thick (survives a morphological opening wider than any cane):
  // the head and the trunk. Row-major, width * height.
  std::vector<uint8_t> thick_mask;
  // Distance in pixels from each pixel to the nearest skeleton point (any segment), capped at
  // kCentrelineDistanceCapPx. Row-major, width * height. Used as a smooth reprojection cost.
  std::vector<float> centreline_distance_px;
  // The platform's fiducials seen in the image (empty when the rig has none or they were not
  // looked for); rig_refine.h uses them as points of known position.
  std::vector<FiducialObservation> fiducials;
  // Halves of the stretches where two canes lie side by side (FindStrandHalves; empty when not
  // looked for: the 2D stage needs the colour image for them).
  std::vector<StrandHalf> strand_halves;

  bool IsForeground(int x, int y) const {
    return classes.at(x, y) == PixelClass::kForeground;
  }
};

inline constexpr float kCentrelineDistanceCapPx = 30.0f;

}  // namespace vb::reconstruct
