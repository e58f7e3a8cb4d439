// SPDX-License-Identifier: Apache-2.0
// The carving half of the head and trunk reconstruction (head.h; docs/reconstruction.md step 5):
// the octree of cubes judged against each view's silhouette, and the voxel grid whose largest
// 26-connected component is this vine's head and trunk. Internal to head.cc and its tests.
//
// A cube whose bounding sphere projects entirely outside the (dilated) silhouette of some view is
// carved; one inside every view is kept whole; the rest are split down to min_cell_m and then
// kept (and a kept smallest cube on the boundary is marked `tight` if a sphere of
// leaf_radius_fraction of its bounding radius also touches every silhouette, or, with
// leaf_wood_radius_px, the wide wood beside it). A post in front
// hides what is behind it: its pixels do not carve, but neither do they prove a cube whole, and
// a cube near thick wood in no view at all (behind posts in every view) is not kept. Carver is
// immutable after construction and thread-safe to share.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/calibration.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::head_internal {

// kHidden: not carved by any view, but near no thick wood in any view either: it is behind
// posts in every view that sees it.
enum class CubeVerdict { kOutside, kInside, kBoundary, kHidden };

struct Cube {
  Eigen::Vector3d centre;
  double side;
  bool seen_as_wood = true;  // near thick wood in every view that sees it (not kept by a post)
  bool tight = true;         // not a leaf that the tight test (leaf_radius_fraction) carves
};

// The distance (cv::distanceTransform's 3x3 chamfer L2, px) from each pixel of a width x height
// image to the nearest pixel of a set, or from each pixel of the set to the nearest pixel off it,
// computed over a box around the set only. A head's silhouette covers a few percent of a frame,
// and a full-frame transform costs ~10 ms.
class CroppedDistance {
 public:
  // Distance to the set's pixels in columns [x_begin, x_end) (`set`: width x height, row-major,
  // nonzero on the set; x_end <= 0 for width). At(x, y) equals the full-frame transform of those
  // pixels inside their bounding box grown by margin_px; outside it, +infinity, where the
  // full-frame value exceeds kChamferStep x margin_px (a chamfer path there takes at least
  // margin_px steps of >= kChamferStep px). An empty set gives +infinity everywhere.
  static CroppedDistance ToSet(const std::vector<uint8_t>& set, int width, int height,
                               int margin_px, int x_begin = 0, int x_end = 0);
  // Distance from each pixel of the set to the nearest pixel off it (0 off the set), equal to
  // the full-frame transform everywhere: computed over the set's box grown by 1 px, whose rim
  // lies off the set.
  static CroppedDistance InsideSet(const std::vector<uint8_t>& set, int width, int height);

  float At(int x, int y) const;
  // The share of the frame computed.
  double CroppedShare() const;

  static constexpr double kChamferStep = 0.955;  // OpenCV's horizontal and vertical step

 private:
  // Sets the box computed; returns its w x h row-major storage.
  float* Allocate(int x0, int y0, int w, int h);

  int width_ = 0, height_ = 0;
  int x0_ = 0, y0_ = 0, w_ = 0, h_ = 0;  // the box computed
  float outside_ = 0.0f;                 // At outside the box
  std::vector<float> distance_;          // w_ x h_, row-major
};

// The distance to a set, for threshold tests that agree exactly with the full-frame transform.
// The set's columns are split into bands (runs of columns holding set pixels, runs closer than
// 2 x margin_px + 1 merged: a post is one band, the head and trunk another), each a
// CroppedDistance; their minimum is the distance to the whole set wherever it is at most
// kChamferStep x margin_px. Larger thresholds outside every band's box fall back to the
// full-frame transform, computed once on first need. Thread-safe.
class SetDistance {
 public:
  SetDistance() = default;
  SetDistance(std::vector<uint8_t> set, int width, int height, int margin_px);

  // Whether the full-frame transform at (x, y), inside the image, exceeds `threshold`.
  bool Exceeds(int x, int y, double threshold) const;
  double CroppedShare() const;     // the bands' boxes' share of the frame
  bool FullFrameComputed() const;  // whether the fallback ran

 private:
  struct Full;  // the set and its lazily computed full-frame transform
  int margin_px_ = 0;
  std::vector<CroppedDistance> bands_;
  std::shared_ptr<Full> full_;
};

struct SilhouetteMaps;  // distance maps of one view (head_carve.cc)

class Carver {
 public:
  // rig.cameras[i] belongs to views[i] (sizes checked by the caller). `canes`: 3D cane points
  // peeled off the silhouettes when options.peel_canes (head_peel.h). Keeps references to `rig`
  // and `options`, which must outlive it. The silhouette maps are cropped (SetDistance,
  // CroppedDistance), and every comparison agrees with full-frame maps.
  Carver(const std::vector<View2D>& views, const RigCalibration& rig, const HeadOptions& options,
         const std::vector<Eigen::Vector3d>& canes);
  ~Carver();
  Carver(const Carver&) = delete;
  Carver& operator=(const Carver&) = delete;

  // The cube's verdict; *seen_as_wood is false if some view that sees it finds no thick wood
  // near it (it is kept only because a post hides it there).
  CubeVerdict Judge(const Cube& cube, bool* seen_as_wood) const;
  // The tight test (HeadOptions::leaf_radius_fraction): true if some view that sees `cube` (as
  // Judge counts them) finds its sphere of radius_fraction x its bounding radius wholly outside
  // its silhouette, or, when leaf_wood_radius_px > 0, outside both the silhouette and the wood
  // that a disc of that radius fits in.
  bool OutsideInSomeView(const Cube& cube, double radius_fraction) const;
  // Appends to *kept the leaves of `cube`'s octree that survive carving.
  void Carve(const Cube& cube, std::vector<Cube>* kept) const;

 private:
  // Where a cube's bounding sphere (radius `radius`) falls in view v: its centre pixel, clamped
  // to the image, and its radius in px (10% slack for the lens distortion's change of scale
  // across the image). Nothing when the centre projects outside the image or the sphere reaches
  // the camera.
  struct InView {
    int x = 0, y = 0;
    double r_px = 0.0;
  };
  std::optional<InView> Place(const Cube& cube, double radius, size_t v) const;

  // True if pixel (x, y) of view v lies farther than `reach` px from its silhouette, or from
  // the unreached thick mask when *reached_only (the views so far held by the reach alone,
  // incremented here) would pass HeadOptions::foreground_reach_max_views.
  bool OutsideIn(size_t v, int x, int y, double reach, int* reached_only) const;

  const RigCalibration& rig_;
  const HeadOptions& options_;
  std::vector<SilhouetteMaps> maps_;
};

// `silhouette` (a view's thick mask, width x height, 0/1) grown into the view's foreground
// (PixelClass::kForeground): the pixels joined to it by a path of at most `reach_px` steps
// through foreground (8-connected, cross and square steps alternating: about a disc). Narrow
// parts and corners of a head that the thick mask's opening lost come back; a cane leaving the
// silhouette comes back for reach_px of its length only (HeadOptions::foreground_reach_px).
// reach_px <= 0 returns `silhouette` unchanged.
std::vector<uint8_t> ReachIntoForeground(const View2D& view, const std::vector<uint8_t>& silhouette,
                                         int reach_px);

// Voxels of side `cell` over a box, for connected components of the kept cubes.
class VoxelGrid {
 public:
  VoxelGrid(const Eigen::AlignedBox3d& box, double cell) : origin_(box.min()), cell_(cell) {
    size_ = ((box.max() - box.min()) / cell).array().ceil().cast<int>().max(1);
    labels_.assign(static_cast<size_t>(size_.prod()), 0);
  }
  bool Index(const Eigen::Vector3d& p, Eigen::Vector3i* ijk) const {
    *ijk = ((p - origin_) / cell_).array().floor().cast<int>();
    return (ijk->array() >= 0).all() && (ijk->array() < size_.array()).all();
  }
  size_t Flat(const Eigen::Vector3i& ijk) const {
    return (static_cast<size_t>(ijk.z()) * size_.y() + ijk.y()) * size_.x() + ijk.x();
  }
  Eigen::Vector3d Centre(const Eigen::Vector3i& ijk) const {
    return origin_ + (ijk.cast<double>().array() + 0.5).matrix() * cell_;
  }
  const Eigen::Vector3i& size() const { return size_; }
  std::vector<int>& labels() { return labels_; }
  const std::vector<int>& labels() const { return labels_; }

 private:
  Eigen::Vector3d origin_;
  double cell_;
  Eigen::Vector3i size_;
  std::vector<int> labels_;  // 0 empty, -1 occupied, >0 component id
};

// Rasterises `kept` into `grid` (whose cell is min_cell_m; labels all 0 on entry) and labels its
// 26-connected components 1, 2, ...; returns the label of the largest (0 if none). On return
// (*voxels_of_cube)[c] lists the flat indices of cube c's voxels inside the grid.
int LabelLargestComponent(const std::vector<Cube>& kept, double min_cell_m, VoxelGrid* grid,
                          std::vector<std::vector<size_t>>* voxels_of_cube);

}  // namespace vb::reconstruct::head_internal
