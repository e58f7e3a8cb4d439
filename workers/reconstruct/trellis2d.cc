// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/trellis2d.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "opencv2/core.hpp"
#include "opencv2/imgproc.hpp"
#include "workers/reconstruct/lines2d.h"

namespace vb::reconstruct {
namespace {

// Normalised units per pixel around pixel uv (the lens stretches the image edges).
double LocalScale(const CameraCalibration& camera, const Eigen::Vector2d& uv) {
  const Eigen::Vector2d c = camera.PixelToNormalised(uv);
  return 0.5 * ((camera.PixelToNormalised(uv + Eigen::Vector2d(1, 0)) - c).norm() +
                (camera.PixelToNormalised(uv + Eigen::Vector2d(0, 1)) - c).norm());
}

// Connected components (8-connected) of the pixels of one class, with at least min_area pixels.
struct Regions {
  cv::Mat labels;
  cv::Mat stats;
  cv::Mat centroids;
  std::vector<int> kept;  // labels with enough pixels
};

Regions RegionsOf(const ClassImage& classes, PixelClass cls, int min_area) {
  const cv::Mat image(classes.height, classes.width, CV_8U,
                      const_cast<uint8_t*>(classes.data.data()));
  const cv::Mat mask = image == static_cast<int>(cls);
  Regions regions;
  const int n = cv::connectedComponentsWithStats(mask, regions.labels, regions.stats,
                                                 regions.centroids, 8, CV_32S);
  for (int i = 1; i < n; ++i) {
    if (regions.stats.at<int>(i, cv::CC_STAT_AREA) >= std::max(1, min_area)) {
      regions.kept.push_back(i);
    }
  }
  return regions;
}

cv::Rect BoxOf(const Regions& regions, int label) {
  return cv::Rect(regions.stats.at<int>(label, cv::CC_STAT_LEFT),
                  regions.stats.at<int>(label, cv::CC_STAT_TOP),
                  regions.stats.at<int>(label, cv::CC_STAT_WIDTH),
                  regions.stats.at<int>(label, cv::CC_STAT_HEIGHT));
}

Eigen::Vector2d CentroidOf(const Regions& regions, int label) {
  return {regions.centroids.at<double>(label, 0), regions.centroids.at<double>(label, 1)};
}

// Sorted projections of the inliers onto the line; the length covered by runs whose gaps are
// under max_gap (in the points' units).
double CoveredLength(const std::vector<Eigen::Vector2d>& points, const LinePiece& piece,
                     double max_gap) {
  std::vector<double> t;
  t.reserve(piece.inliers.size());
  const Eigen::Vector2d direction = piece.Direction();
  for (int i : piece.inliers) t.push_back(direction.dot(points[i]));
  std::sort(t.begin(), t.end());
  double covered = 0.0;
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] - t[i - 1] <= max_gap) covered += t[i] - t[i - 1];
  }
  return covered;
}

// The weighted means of `pixels` over the piece's inliers in runs of about `step_px` along the
// line, in order along it.
std::vector<Eigen::Vector2d> CentreTrace(const std::vector<Eigen::Vector2d>& points,
                                         const std::vector<Eigen::Vector2d>& pixels,
                                         const std::vector<int>& weights, const LinePiece& piece,
                                         double step_px) {
  std::vector<int> order = piece.inliers;
  const Eigen::Vector2d direction = piece.Direction();
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return direction.dot(points[a]) < direction.dot(points[b]);
  });
  std::vector<Eigen::Vector2d> trace;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double weight = 0.0;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  for (int i : order) {
    if (weight > 0 && (pixels[i] - start).norm() >= step_px) {
      trace.push_back(sum / weight);
      sum.setZero();
      weight = 0.0;
    }
    if (weight == 0.0) start = pixels[i];
    sum += weights[i] * pixels[i];
    weight += weights[i];
  }
  if (weight > 0) trace.push_back(sum / weight);
  return trace;
}

constexpr double kTraceStepPx = 8.0;

Line2D ToLine2D(const LinePiece& piece, double width_px, int support_px) {
  Line2D line;
  line.line = piece.line;
  line.begin = piece.begin;
  line.end = piece.end;
  line.width_px = width_px;
  line.support_px = support_px;
  return line;
}

}  // namespace

std::vector<Line2D> ExtractWires(const ClassImage& classes, const CameraCalibration& camera,
                                 const Structure2DOptions& options) {
  const Regions regions = RegionsOf(classes, PixelClass::kWire, options.min_wire_piece_px);
  if (regions.kept.empty()) return {};
  // Each piece is summarised by the centroids of its pixels in bins of kBin columns (rows, for
  // pieces taller than wide): sub-pixel points along the wire, and few calls to the iterative
  // undistortion.
  constexpr int kBin = 2;
  struct Bins {
    cv::Rect box;
    bool by_column = true;
    std::vector<double> sum_x, sum_y;
    std::vector<int> count;
  };
  std::vector<int> slot(regions.stats.rows, -1);
  std::vector<Bins> bins(regions.kept.size());
  for (size_t k = 0; k < regions.kept.size(); ++k) {
    slot[regions.kept[k]] = static_cast<int>(k);
    Bins& b = bins[k];
    b.box = BoxOf(regions, regions.kept[k]);
    b.by_column = b.box.width >= b.box.height;
    const int n = (b.by_column ? b.box.width : b.box.height) / kBin + 1;
    b.sum_x.assign(n, 0.0);
    b.sum_y.assign(n, 0.0);
    b.count.assign(n, 0);
  }
  for (int y = 0; y < classes.height; ++y) {
    const int* label = regions.labels.ptr<int>(y);
    for (int x = 0; x < classes.width; ++x) {
      if (label[x] <= 0 || slot[label[x]] < 0) continue;
      Bins& b = bins[slot[label[x]]];
      const int i = (b.by_column ? x - b.box.x : y - b.box.y) / kBin;
      b.sum_x[i] += x;
      b.sum_y[i] += y;
      ++b.count[i];
    }
  }
  std::vector<Eigen::Vector2d> points;
  std::vector<Eigen::Vector2d> pixels;  // the same points in pixels
  std::vector<int> weights;  // wire pixels summarised by each point
  std::vector<std::vector<int>> members(regions.kept.size());
  for (size_t k = 0; k < bins.size(); ++k) {
    const Bins& b = bins[k];
    for (size_t i = 0; i < b.count.size(); ++i) {
      if (b.count[i] == 0) continue;
      members[k].push_back(static_cast<int>(points.size()));
      pixels.emplace_back(b.sum_x[i] / b.count[i], b.sum_y[i] / b.count[i]);
      points.push_back(camera.PixelToNormalised(pixels.back()));
      weights.push_back(b.count[i]);
    }
  }
  std::vector<LinePiece> pieces;
  for (size_t k = 0; k < regions.kept.size(); ++k) {
    const double scale = LocalScale(camera, CentroidOf(regions, regions.kept[k]));
    RansacOptions ransac;
    ransac.inlier_distance = options.wire_inlier_px * scale;
    ransac.min_support = 3;  // bins: a few pixels of length; short lines go by length below
    ransac.iterations = options.ransac_iterations;
    ransac.max_lines = 3;
    ransac.seed = options.seed + k;
    for (LinePiece& piece : FitLinesRansac(points, members[k], ransac)) {
      piece.scale = scale;
      pieces.push_back(std::move(piece));
    }
  }
  const std::vector<LinePiece> merged = MergeCollinear(
      points, std::move(pieces), options.wire_merge_px, options.wire_merge_angle_deg * M_PI / 180);
  std::vector<Line2D> wires;
  for (const LinePiece& piece : merged) {
    // Runs of bins cover their length plus one bin.
    const double length_px =
        CoveredLength(points, piece, 2.5 * kBin * piece.scale) / piece.scale + kBin;
    if (length_px < std::max(1.0, options.min_wire_length_px)) continue;
    int support = 0;
    for (int i : piece.inliers) support += weights[i];
    wires.push_back(ToLine2D(piece, support / length_px, support));
    wires.back().centre_px = CentreTrace(points, pixels, weights, piece, kTraceStepPx);
  }
  return wires;
}

std::vector<Line2D> ExtractPosts(const ClassImage& classes, const CameraCalibration& camera,
                                 const Structure2DOptions& options) {
  const Regions regions = RegionsOf(classes, PixelClass::kPost, options.min_post_area_px);
  std::vector<Eigen::Vector2d> centres;  // normalised, one per row of each region
  std::vector<Eigen::Vector2d> centres_px;  // the same in pixels
  std::vector<double> spans_px;          // row span, pixels
  std::vector<int> counts;               // post pixels in that row
  std::vector<LinePiece> pieces;
  for (size_t k = 0; k < regions.kept.size(); ++k) {
    const int label = regions.kept[k];
    const cv::Rect box = BoxOf(regions, label);
    std::vector<int> members;
    for (int y = box.y; y < box.y + box.height; ++y) {
      const int* row = regions.labels.ptr<int>(y);
      int lo = -1;
      int hi = -1;
      int count = 0;
      for (int x = box.x; x < box.x + box.width; ++x) {
        if (row[x] != label) continue;
        if (lo < 0) lo = x;
        hi = x;
        ++count;
      }
      if (count == 0 || lo == 0 || hi == classes.width - 1) continue;
      // The pixel midpoint: the lens bends a post's width by far less than a pixel.
      members.push_back(static_cast<int>(centres.size()));
      centres_px.emplace_back(0.5 * (lo + hi), y);
      centres.push_back(camera.PixelToNormalised(centres_px.back()));
      spans_px.push_back(hi - lo + 1);
      counts.push_back(count);
    }
    const double scale = LocalScale(camera, CentroidOf(regions, label));
    RansacOptions ransac;
    ransac.inlier_distance = options.post_inlier_px * scale;
    ransac.min_support = std::max(2, static_cast<int>(0.5 * options.min_post_length_px));
    ransac.iterations = options.ransac_iterations;
    ransac.max_lines = 1;
    ransac.seed = options.seed + k;
    for (LinePiece& piece : FitLinesRansac(centres, members, ransac)) {
      piece.scale = scale;
      pieces.push_back(std::move(piece));
    }
  }
  const std::vector<LinePiece> merged = MergeCollinear(
      centres, std::move(pieces), options.post_merge_px, options.wire_merge_angle_deg * M_PI / 180);
  std::vector<Line2D> posts;
  const double max_lean = std::sin(options.max_post_tilt_deg * M_PI / 180);
  for (const LinePiece& piece : merged) {
    if (std::abs(piece.Direction().x()) > max_lean) continue;
    const double length_px = (piece.end - piece.begin).norm() / piece.scale;
    if (length_px < std::max(1.0, options.min_post_length_px)) continue;
    std::vector<double> spans;
    int support = 0;
    for (int i : piece.inliers) {
      spans.push_back(spans_px[i]);
      support += counts[i];
    }
    std::nth_element(spans.begin(), spans.begin() + spans.size() / 2, spans.end());
    posts.push_back(ToLine2D(piece, spans[spans.size() / 2], support));
    posts.back().centre_px = CentreTrace(centres, centres_px, counts, piece, kTraceStepPx);
  }
  return posts;
}

}  // namespace vb::reconstruct
