// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_carve.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <utility>

#include "opencv2/imgproc.hpp"
#include "workers/reconstruct/head_peel.h"

namespace vb::reconstruct::head_internal {

namespace {

// `box` grown by m px on every side, within the width x height frame.
cv::Rect Grown(const cv::Rect& box, int m, int width, int height) {
  return cv::Rect(box.x - m, box.y - m, box.width + 2 * m, box.height + 2 * m) &
         cv::Rect(0, 0, width, height);
}

}  // namespace

CroppedDistance CroppedDistance::ToSet(const std::vector<uint8_t>& set, int width, int height,
                                       int margin_px, int x_begin, int x_end) {
  CroppedDistance out;
  out.width_ = width;
  out.height_ = height;
  out.outside_ = std::numeric_limits<float>::infinity();
  x_begin = std::clamp(x_begin, 0, width);
  x_end = x_end <= 0 ? width : std::clamp(x_end, x_begin, width);
  const cv::Mat mask(height, width, CV_8U, const_cast<uint8_t*>(set.data()));
  cv::Rect box = cv::boundingRect(mask(cv::Rect(x_begin, 0, x_end - x_begin, height)));
  if (box.area() == 0) return out;
  box.x += x_begin;
  const cv::Rect crop = Grown(box, std::max(0, margin_px), width, height);
  cv::Mat distance(crop.height, crop.width, CV_32F,
                   out.Allocate(crop.x, crop.y, crop.width, crop.height));
  // Only the columns asked for count as the set.
  cv::Mat off_set = mask(crop) == 0;
  for (int x = 0; x < crop.width; ++x) {
    if (crop.x + x < x_begin || crop.x + x >= x_end) off_set.col(x).setTo(255);
  }
  // Every pixel of the set lies in the crop, and a shortest chamfer path from a pixel of the
  // crop to one of the set stays in the box they span: the crop's values are the full frame's.
  cv::distanceTransform(off_set, distance, cv::DIST_L2, 3);
  return out;
}

CroppedDistance CroppedDistance::InsideSet(const std::vector<uint8_t>& set, int width,
                                           int height) {
  CroppedDistance out;
  out.width_ = width;
  out.height_ = height;
  out.outside_ = 0.0f;
  const cv::Mat mask(height, width, CV_8U, const_cast<uint8_t*>(set.data()));
  const cv::Rect box = cv::boundingRect(mask);
  if (box.area() == 0) return out;
  const cv::Rect crop = Grown(box, 1, width, height);
  cv::Mat distance(crop.height, crop.width, CV_32F,
                   out.Allocate(crop.x, crop.y, crop.width, crop.height));
  // The crop's rim lies off the set (or on the image's edge, beyond which the full frame has no
  // pixel either), so the nearest pixel off the set is in the crop.
  cv::distanceTransform(mask(crop) != 0, distance, cv::DIST_L2, 3);
  return out;
}

float* CroppedDistance::Allocate(int x0, int y0, int w, int h) {
  x0_ = x0;
  y0_ = y0;
  w_ = w;
  h_ = h;
  distance_.assign(static_cast<size_t>(w) * h, 0.0f);
  return distance_.data();
}

float CroppedDistance::At(int x, int y) const {
  x -= x0_;
  y -= y0_;
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return outside_;
  return distance_[static_cast<size_t>(y) * w_ + x];
}

double CroppedDistance::CroppedShare() const {
  const double frame = static_cast<double>(width_) * height_;
  return frame > 0 ? static_cast<double>(w_) * h_ / frame : 0.0;
}

struct SetDistance::Full {
  std::vector<uint8_t> set;
  int width = 0, height = 0;
  std::once_flag once;
  std::atomic<bool> computed{false};
  cv::Mat distance;  // CV_32F, width x height
};

SetDistance::SetDistance(std::vector<uint8_t> set, int width, int height, int margin_px)
    : margin_px_(std::max(0, margin_px)), full_(std::make_shared<Full>()) {
  const cv::Mat mask(height, width, CV_8U, set.data());
  cv::Mat columns;  // 1 x width: the largest value in each column
  cv::reduce(mask, columns, 0, cv::REDUCE_MAX);
  int x = 0;
  while (x < width) {
    if (columns.at<uint8_t>(0, x) == 0) {
      ++x;
      continue;
    }
    // A band: columns with set pixels, gaps of up to 2 x margin_px empty columns included (the
    // boxes of two bands then never reach each other's pixels).
    const int begin = x;
    int end = x + 1, empty = 0;
    for (x = end; x < width && empty <= 2 * margin_px_; ++x) {
      if (columns.at<uint8_t>(0, x) != 0) {
        end = x + 1;
        empty = 0;
      } else {
        ++empty;
      }
    }
    bands_.push_back(CroppedDistance::ToSet(set, width, height, margin_px_, begin, end));
    x = end;
  }
  full_->set = std::move(set);
  full_->width = width;
  full_->height = height;
}

bool SetDistance::Exceeds(int x, int y, double threshold) const {
  float nearest = std::numeric_limits<float>::infinity();
  for (const CroppedDistance& band : bands_) nearest = std::min(nearest, band.At(x, y));
  // At most the threshold in a band's box: the whole set's distance is no larger. Otherwise
  // every band whose box misses (x, y) lies farther than kChamferStep x margin_px.
  if (nearest <= threshold) return false;
  if (threshold < CroppedDistance::kChamferStep * margin_px_ || !full_) return true;
  std::call_once(full_->once, [full = full_.get()] {
    const cv::Mat mask(full->height, full->width, CV_8U, full->set.data());
    cv::distanceTransform(mask == 0, full->distance, cv::DIST_L2, 3);
    full->computed = true;
  });
  return full_->distance.at<float>(y, x) > threshold;
}

double SetDistance::CroppedShare() const {
  double share = 0.0;
  for (const CroppedDistance& band : bands_) share += band.CroppedShare();
  return share;
}

bool SetDistance::FullFrameComputed() const { return full_ && full_->computed; }

// Distances from every pixel to the silhouette (0 inside) and to the background (0 outside).
struct SilhouetteMaps {
  int width = 0;
  int height = 0;
  // Distance to the silhouette (the thick mask, peeled and reached when asked) alone, and to
  // the view's posts: to the silhouette or a post is their minimum (a post in front hides
  // whatever is behind it, so its pixels do not carve).
  SetDistance to_thick;
  SetDistance to_post;
  CroppedDistance to_background;  // from inside the silhouette to the nearest pixel off it
  bool OutsideSilhouette(int x, int y, double reach) const {
    return to_thick.Exceeds(x, y, reach) && to_post.Exceeds(x, y, reach);
  }
  // CV_32F, when HeadOptions::leaf_wood_radius_px > 0: distance to the silhouette or to wood
  // that a disc of that radius fits in (the opening of the foreground by that disc).
  cv::Mat to_wide_wood;
  // CV_32F, when HeadOptions::foreground_reach_px > 0: to_silhouette of the thick mask before
  // it reached into the foreground (the silhouette above is the grown one).
  cv::Mat to_unreached;
};

std::vector<uint8_t> ReachIntoForeground(const View2D& view, const std::vector<uint8_t>& silhouette,
                                         int reach_px) {
  std::vector<uint8_t> out = silhouette;
  if (reach_px <= 0) return out;
  cv::Mat mask(view.height, view.width, CV_8U, out.data());
  const cv::Rect box = cv::boundingRect(mask);
  if (box.area() == 0) return out;
  const cv::Rect roi =
      (box + cv::Size(2 * reach_px, 2 * reach_px) - cv::Point(reach_px, reach_px)) &
      cv::Rect(0, 0, view.width, view.height);
  cv::Mat classes(view.height, view.width, CV_8U, const_cast<uint8_t*>(view.classes.data.data()));
  const cv::Mat foreground = classes(roi) == static_cast<int>(PixelClass::kForeground);
  // Geodesic dilation: one step at a time, each kept within the foreground, so the silhouette
  // reaches only along wood that touches it. Cross and square steps alternate (an octagon, close
  // to a disc of reach_px).
  const cv::Mat cross = cv::getStructuringElement(cv::MORPH_CROSS, {3, 3});
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::Mat grown = mask(roi).clone();
  for (int step = 0; step < reach_px; ++step) {
    cv::Mat next;
    cv::dilate(grown, next, step % 2 == 0 ? cross : square);
    grown = (next & foreground) | grown;
  }
  grown.copyTo(mask(roi));
  return out;
}

namespace {

// `silhouette`: the view's thick mask, or that mask with the canes peeled off (head_peel.h),
// grown into the foreground by reach_px (ReachIntoForeground). `wood_radius_px` > 0 also makes
// to_wide_wood. The cropped maps' margin is margin_px (SetDistance).
SilhouetteMaps MakeMaps(const View2D& view, const std::vector<uint8_t>& unreached,
                        int reach_px, double wood_radius_px, int margin_px) {
  const std::vector<uint8_t> silhouette = ReachIntoForeground(view, unreached, reach_px);
  SilhouetteMaps maps;
  maps.width = view.width;
  maps.height = view.height;
  cv::Mat mask(view.height, view.width, CV_8U, const_cast<uint8_t*>(silhouette.data()));
  // A post in front hides whatever is behind it: its pixels may not carve (they count as
  // silhouette for the outside test), but neither do they prove a cube whole.
  cv::Mat classes(view.height, view.width, CV_8U, const_cast<uint8_t*>(view.classes.data.data()));
  std::vector<uint8_t> posts(silhouette.size());
  for (size_t i = 0; i < posts.size(); ++i) {
    posts[i] = view.classes.data[i] == static_cast<uint8_t>(PixelClass::kPost) ? 1 : 0;
  }
  maps.to_thick = SetDistance(silhouette, view.width, view.height, margin_px);
  maps.to_post = SetDistance(std::move(posts), view.width, view.height, margin_px);
  maps.to_background = CroppedDistance::InsideSet(silhouette, view.width, view.height);
  if (reach_px > 0) {
    cv::Mat before(view.height, view.width, CV_8U, const_cast<uint8_t*>(unreached.data()));
    cv::Mat outside_before = (before == 0) & (classes != static_cast<int>(PixelClass::kPost));
    cv::distanceTransform(outside_before, maps.to_unreached, cv::DIST_L2, 3);
  }
  if (wood_radius_px > 0) {
    // The opening of the wood (foreground or silhouette) by a disc of wood_radius_px: erosion
    // is {distance to non-wood > radius}, dilation {distance to the eroded set <= radius}.
    cv::Mat wood = (classes == static_cast<int>(PixelClass::kForeground)) | (mask != 0);
    cv::Mat to_non_wood, to_core;
    cv::distanceTransform(wood, to_non_wood, cv::DIST_L2, 3);
    cv::Mat not_core = to_non_wood <= wood_radius_px;
    cv::distanceTransform(not_core, to_core, cv::DIST_L2, 3);
    cv::Mat outside = (mask == 0) & (classes != static_cast<int>(PixelClass::kPost));
    cv::Mat not_wide = outside & (to_core > wood_radius_px);
    cv::distanceTransform(not_wide, maps.to_wide_wood, cv::DIST_L2, 3);
  }
  return maps;
}

// The cropped maps' margin: the octree's thresholds reach ~72 px with the default rig (a root
// cube of 4 cm near the working volume's near face at an image's bottom corner, tuning stops
// 1400-1405), under 0.955 x 80 px; larger ones outside the crops take the full-frame fallback
// (SetDistance).
constexpr int kCropMarginPx = 80;

}  // namespace

Carver::Carver(const std::vector<View2D>& views, const RigCalibration& rig,
               const HeadOptions& options, const std::vector<Eigen::Vector3d>& canes)
    : rig_(rig), options_(options) {
  for (size_t v = 0; v < views.size(); ++v) {
    const std::vector<uint8_t> silhouette =
        options.peel_canes ? PeelCanesOffSilhouette(views[v], rig.cameras[v], canes, options)
                           : views[v].thick_mask;
    maps_.push_back(MakeMaps(views[v], silhouette, options.foreground_reach_px,
                             options.leaf_radius_fraction < 1.0 ? options.leaf_wood_radius_px
                                                                : 0.0,
                             kCropMarginPx));
  }
}

Carver::~Carver() = default;

std::optional<Carver::InView> Carver::Place(const Cube& cube, double radius, size_t v) const {
  const CameraCalibration& camera = rig_.cameras[v];
  const auto uv = camera.Project(cube.centre);
  if (!uv || !camera.InImage(*uv)) return std::nullopt;
  const double depth = (camera.camera_from_platform() * cube.centre).z();
  if (depth <= radius) return std::nullopt;
  InView at;
  at.r_px = 1.1 * camera.camera_matrix(0, 0) * radius / depth;
  at.x = std::clamp(static_cast<int>(std::lround(uv->x())), 0, maps_[v].width - 1);
  at.y = std::clamp(static_cast<int>(std::lround(uv->y())), 0, maps_[v].height - 1);
  return at;
}

CubeVerdict Carver::Judge(const Cube& cube, bool* seen_as_wood) const {
  const double radius = 0.5 * std::sqrt(3.0) * cube.side;
  int seen = 0;
  bool all_inside = true;
  bool touches_wood = false;  // behind posts in every view is not evidence of a head
  int reached_only = 0;
  *seen_as_wood = true;
  for (size_t v = 0; v < maps_.size(); ++v) {
    const std::optional<InView> at = Place(cube, radius, v);
    if (!at) continue;
    ++seen;
    const int x = at->x, y = at->y;
    const double r_px = at->r_px;
    if (OutsideIn(v, x, y, r_px + options_.silhouette_margin_px, &reached_only))
      return CubeVerdict::kOutside;
    if (maps_[v].to_background.At(x, y) < r_px) all_inside = false;
    if (!maps_[v].to_thick.Exceeds(x, y, r_px + options_.silhouette_margin_px))
      touches_wood = true;
    else
      *seen_as_wood = false;
  }
  if (seen < options_.min_views) return CubeVerdict::kOutside;
  if (!touches_wood) return CubeVerdict::kHidden;
  return all_inside ? CubeVerdict::kInside : CubeVerdict::kBoundary;
}

bool Carver::OutsideInSomeView(const Cube& cube, double radius_fraction) const {
  const double radius = 0.5 * std::sqrt(3.0) * cube.side;
  int reached_only = 0;
  for (size_t v = 0; v < maps_.size(); ++v) {
    const std::optional<InView> at = Place(cube, radius, v);
    if (!at) continue;
    const int x = at->x, y = at->y;
    const double reach = radius_fraction * at->r_px + options_.silhouette_margin_px;
    if (options_.leaf_wood_radius_px > 0) {
      if (maps_[v].to_wide_wood.at<float>(y, x) > reach) return true;
    } else if (OutsideIn(v, x, y, reach, &reached_only)) {
      return true;
    }
  }
  return false;
}

bool Carver::OutsideIn(size_t v, int x, int y, double reach, int* reached_only) const {
  if (maps_[v].OutsideSilhouette(x, y, reach)) return true;
  if (maps_[v].to_unreached.empty() || maps_[v].to_unreached.at<float>(y, x) <= reach)
    return false;
  // Held by the reach alone in this view: allowed in at most foreground_reach_max_views views.
  return ++*reached_only > options_.foreground_reach_max_views;
}

void Carver::Carve(const Cube& cube, std::vector<Cube>* kept) const {
  bool seen_as_wood = true;
  const CubeVerdict verdict = Judge(cube, &seen_as_wood);
  // A post's shadow is no evidence of a head (it runs the height of the images).
  if (verdict == CubeVerdict::kOutside || verdict == CubeVerdict::kHidden) return;
  const bool leaf = cube.side <= options_.min_cell_m * 1.0001;
  if (verdict == CubeVerdict::kInside || leaf) {
    bool tight = true;
    if (verdict == CubeVerdict::kBoundary && options_.leaf_radius_fraction < 1.0)
      tight = !OutsideInSomeView(cube, options_.leaf_radius_fraction);
    kept->push_back({cube.centre, cube.side, seen_as_wood, tight});
    return;
  }
  const double q = cube.side / 4.0;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d offset((i & 1) ? q : -q, (i & 2) ? q : -q, (i & 4) ? q : -q);
    Carve({cube.centre + offset, cube.side / 2.0, true}, kept);
  }
}

int LabelLargestComponent(const std::vector<Cube>& kept, double min_cell_m, VoxelGrid* grid,
                          std::vector<std::vector<size_t>>* voxels_of_cube) {
  std::vector<int>& labels = grid->labels();
  voxels_of_cube->assign(kept.size(), {});
  for (size_t c = 0; c < kept.size(); ++c) {
    const int n = std::max(1, static_cast<int>(std::lround(kept[c].side / min_cell_m)));
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        for (int d = 0; d < n; ++d) {
          const Eigen::Vector3d p =
              kept[c].centre +
              (Eigen::Vector3d(a, b, d).array() + 0.5 - n / 2.0).matrix() * min_cell_m;
          Eigen::Vector3i ijk;
          if (!grid->Index(p, &ijk)) continue;
          labels[grid->Flat(ijk)] = -1;
          (*voxels_of_cube)[c].push_back(grid->Flat(ijk));
        }
  }
  const Eigen::Vector3i size = grid->size();
  int best_label = 0;
  size_t best_count = 0;
  int next_label = 0;
  std::vector<Eigen::Vector3i> stack;
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const Eigen::Vector3i seed(x, y, z);
        if (labels[grid->Flat(seed)] != -1) continue;
        ++next_label;
        size_t count = 0;
        stack.assign(1, seed);
        labels[grid->Flat(seed)] = next_label;
        while (!stack.empty()) {
          const Eigen::Vector3i at = stack.back();
          stack.pop_back();
          ++count;
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const Eigen::Vector3i n = at + Eigen::Vector3i(dx, dy, dz);
                if ((n.array() < 0).any() || (n.array() >= size.array()).any()) continue;
                int& label = labels[grid->Flat(n)];
                if (label != -1) continue;
                label = next_label;
                stack.push_back(n);
              }
        }
        if (count > best_count) {
          best_count = count;
          best_label = next_label;
        }
      }
  return best_label;
}

}  // namespace vb::reconstruct::head_internal
