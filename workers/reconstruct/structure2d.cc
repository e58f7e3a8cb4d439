// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/structure2d.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "opencv2/core.hpp"
#include "opencv2/imgproc.hpp"
#include "workers/reconstruct/mask_ops.h"
#include "workers/reconstruct/skeleton.h"
#include "workers/reconstruct/trellis2d.h"

namespace vb::reconstruct {
namespace {

constexpr uint8_t kBackgroundValue = static_cast<uint8_t>(PixelClass::kBackground);
constexpr uint8_t kForegroundValue = static_cast<uint8_t>(PixelClass::kForeground);
constexpr uint8_t kWireValue = static_cast<uint8_t>(PixelClass::kWire);

// Foreground (0/1) with the gaps that wires in front cut into canes filled: a wire pixel becomes
// foreground if, along one of four directions, the run of wire pixels through it is at most
// max_gap long and ends in foreground on both sides.
BinaryImage BridgedForeground(const ClassImage& classes, int max_gap) {
  const int w = classes.width;
  const int h = classes.height;
  BinaryImage fg(w, h);
  const uint8_t* c = classes.data.data();
  for (size_t i = 0; i < fg.data.size(); ++i) fg.data[i] = c[i] == kForegroundValue;
  if (max_gap <= 0) return fg;
  const auto cls = [&](int x, int y) -> int {
    if (x < 0 || y < 0 || x >= w || y >= h) return kBackgroundValue;
    return c[static_cast<size_t>(y) * w + x];
  };
  // Walks from (x, y) along (dx, dy) over wire pixels; true if foreground comes within reach.
  const auto reaches = [&](int x, int y, int dx, int dy, int* run) {
    for (int s = 1; s <= max_gap; ++s) {
      const int v = cls(x + s * dx, y + s * dy);
      if (v == kForegroundValue) return true;
      if (v != kWireValue) return false;
      ++*run;
    }
    return false;
  };
  static constexpr int kDirections[4][2] = {{0, 1}, {1, 0}, {1, 1}, {1, -1}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (c[static_cast<size_t>(y) * w + x] != kWireValue) continue;
      for (const auto& d : kDirections) {
        int run = 1;
        if (reaches(x, y, d[0], d[1], &run) && reaches(x, y, -d[0], -d[1], &run) &&
            run <= max_gap) {
          fg.set(x, y, 1);
          break;
        }
      }
    }
  }
  return fg;
}

// Opening of `fg` with a disc of `radius`: erosion is {distance to background > radius}, and the
// dilation back is {distance to the eroded set <= radius}, computed only around the eroded set.
std::vector<uint8_t> ThickMask(const cv::Mat& fg, const cv::Mat& distance, double radius) {
  std::vector<uint8_t> thick(static_cast<size_t>(fg.rows) * fg.cols, 0);
  const cv::Mat eroded = distance > radius;
  const cv::Rect box = cv::boundingRect(eroded);
  if (box.area() == 0) return thick;
  const int margin = static_cast<int>(std::ceil(radius)) + 1;
  const cv::Rect roi = (box + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                       cv::Rect(0, 0, fg.cols, fg.rows);
  cv::Mat outside = eroded(roi) == 0;
  cv::Mat to_eroded;
  cv::distanceTransform(outside, to_eroded, cv::DIST_L2, cv::DIST_MASK_5);
  for (int y = 0; y < roi.height; ++y) {
    const float* d = to_eroded.ptr<float>(y);
    const uint8_t* f = fg.ptr<uint8_t>(y + roi.y);
    uint8_t* out = &thick[static_cast<size_t>(y + roi.y) * fg.cols + roi.x];
    for (int x = 0; x < roi.width; ++x) out[x] = f[x + roi.x] && d[x] <= radius;
  }
  return thick;
}

// Bilinear sample of a 0/1 mask; outside the image is background.
double Sample(const cv::Mat& mask, const Eigen::Vector2d& p) {
  const double fx = std::floor(p.x());
  const double fy = std::floor(p.y());
  const int x = static_cast<int>(fx);
  const int y = static_cast<int>(fy);
  const double ax = p.x() - fx;
  const double ay = p.y() - fy;
  const auto at = [&](int u, int v) -> double {
    if (u < 0 || v < 0 || u >= mask.cols || v >= mask.rows) return 0.0;
    return mask.at<uint8_t>(v, u);
  };
  return (1 - ay) * ((1 - ax) * at(x, y) + ax * at(x + 1, y)) +
         ay * ((1 - ax) * at(x, y + 1) + ax * at(x + 1, y + 1));
}

// Distance from p along unit `direction` to the foreground boundary (where the bilinear mask
// falls below 1/2), or a negative value if it is not reached within max_s.
double DistanceToBoundary(const cv::Mat& mask, const Eigen::Vector2d& p,
                          const Eigen::Vector2d& direction, double max_s) {
  constexpr double kStep = 0.5;
  double previous = Sample(mask, p);
  if (previous < 0.5) return -1.0;
  for (double s = kStep; s <= max_s; s += kStep) {
    const double v = Sample(mask, p + s * direction);
    if (v < 0.5) return s - kStep + kStep * (previous - 0.5) / (previous - v);
    previous = v;
  }
  return -1.0;
}

float DistanceAt(const cv::Mat& distance, const Eigen::Vector2d& p) {
  const int x = std::clamp(static_cast<int>(std::lround(p.x())), 0, distance.cols - 1);
  const int y = std::clamp(static_cast<int>(std::lround(p.y())), 0, distance.rows - 1);
  return distance.at<float>(y, x);
}

double FallbackWidth(const cv::Mat& distance, const Eigen::Vector2d& p) {
  // Distances run between pixel centres: a band of n pixels has 2 d - 1 ~ n at its middle.
  return std::max(1.0, 2.0 * DistanceAt(distance, p) - 1.0);
}

// The points and widths of one skeleton path: node positions at junction ends, the path pixels
// re-centred on the cross-section of the foreground, smoothed, free ends extended to the boundary.
Segment2D BuildSegment(const SkeletonGraph& graph, const SkeletonGraph::Path& path,
                       const cv::Mat& fg, const cv::Mat& distance,
                       const Structure2DOptions& options) {
  std::vector<Eigen::Vector2d> points;
  std::vector<uint8_t> fixed;
  // Junction positions (cluster centres, or merged junctions) may lie a few pixels from the
  // path's last pixel: bridge the gap at ~1 px spacing.
  const auto add_node = [&](int node, const Eigen::Vector2d& from, bool at_front) {
    const Eigen::Vector2d position = graph.nodes[node].position;
    const double gap = (position - from).norm();
    if (gap <= 0.5) return;
    const int steps = static_cast<int>(std::ceil(gap));
    for (int k = at_front ? 0 : 1; at_front ? k < steps : k <= steps; ++k) {
      points.push_back(at_front ? position + (from - position) * k / steps
                                : from + (position - from) * k / steps);
      fixed.push_back(1);
    }
  };
  add_node(path.node_begin, path.pixels.front().cast<double>(), true);
  for (const Eigen::Vector2i& pixel : path.pixels) {
    points.push_back(pixel.cast<double>());
    fixed.push_back(0);
  }
  add_node(path.node_end, path.pixels.back().cast<double>(), false);
  if (points.size() < 2) {
    // A one-pixel path between two coincident nodes: make it a two-point segment.
    points.push_back(points.back());
    fixed.push_back(1);
  }

  const int n = static_cast<int>(points.size());
  std::vector<double> widths(n);
  std::vector<Eigen::Vector2d> refined = points;
  constexpr int kTangentReach = 3;
  for (int i = 0; i < n; ++i) {
    widths[i] = FallbackWidth(distance, points[i]);
    if (fixed[i]) continue;
    const Eigen::Vector2d t = points[std::min(n - 1, i + kTangentReach)] -
                              points[std::max(0, i - kTangentReach)];
    if (t.norm() < 1.0) continue;
    const Eigen::Vector2d normal = Eigen::Vector2d(-t.y(), t.x()).normalized();
    const double reach = DistanceAt(distance, points[i]) + 2.0 * options.max_centre_shift_px + 0.5;
    const double hi = DistanceToBoundary(fg, points[i], normal, reach);
    const double lo = DistanceToBoundary(fg, points[i], -normal, reach);
    if (hi < 0.0 || lo < 0.0) continue;
    const double shift = 0.5 * (hi - lo);
    if (std::abs(shift) > options.max_centre_shift_px) continue;
    refined[i] = points[i] + shift * normal;
    widths[i] = hi + lo;
  }
  // [1 2 1] / 4 smoothing of positions and widths; the two end points stay.
  std::vector<double> smoothed_widths = widths;
  for (int pass = 0; pass < options.smoothing_passes; ++pass) {
    std::vector<Eigen::Vector2d> next = refined;
    for (int i = 1; i + 1 < n; ++i) {
      next[i] = 0.25 * (refined[i - 1] + 2.0 * refined[i] + refined[i + 1]);
      smoothed_widths[i] = 0.25 * (widths[i - 1] + 2.0 * widths[i] + widths[i + 1]);
    }
    refined.swap(next);
    widths = smoothed_widths;
  }

  Segment2D segment;
  segment.points = std::move(refined);
  segment.widths_px = std::move(widths);
  // Thinning stops about half a width short of a free end: extend it to the boundary.
  const auto extend = [&](bool at_back) {
    const int node = at_back ? path.node_end : path.node_begin;
    if (graph.Degree(node) != 1 || segment.points.size() < 2) return;
    std::vector<Eigen::Vector2d>& pts = segment.points;
    const int m = static_cast<int>(pts.size());
    const Eigen::Vector2d tip = at_back ? pts.back() : pts.front();
    const Eigen::Vector2d inner = at_back ? pts[std::max(0, m - 5)] : pts[std::min(m - 1, 4)];
    const Eigen::Vector2d direction = (tip - inner).normalized();
    if (!direction.allFinite()) return;
    const double width = at_back ? segment.widths_px.back() : segment.widths_px.front();
    const double s = DistanceToBoundary(fg, tip, direction, 0.5 * width + 3.0);
    if (s < 0.75) return;
    const int steps = static_cast<int>(std::ceil(s / 1.5));
    std::vector<Eigen::Vector2d> extra;
    for (int k = 1; k <= steps; ++k) extra.push_back(tip + direction * (s * k / steps));
    if (at_back) {
      pts.insert(pts.end(), extra.begin(), extra.end());
      segment.widths_px.insert(segment.widths_px.end(), extra.size(), width);
    } else {
      std::reverse(extra.begin(), extra.end());
      pts.insert(pts.begin(), extra.begin(), extra.end());
      segment.widths_px.insert(segment.widths_px.begin(), extra.size(), width);
    }
  };
  extend(false);
  extend(true);
  return segment;
}

std::vector<float> CentrelineDistance(const std::vector<Segment2D>& segments, int width,
                                      int height) {
  if (segments.empty()) {
    return std::vector<float>(static_cast<size_t>(width) * height, kCentrelineDistanceCapPx);
  }
  BinaryImage sites(width, height);
  cv::Mat skeleton(height, width, CV_8U, sites.data.data());
  constexpr int kShift = 4;  // sub-pixel line end points
  const auto fixed = [](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(p.x() * (1 << kShift))),
                     static_cast<int>(std::lround(p.y() * (1 << kShift))));
  };
  for (const Segment2D& segment : segments) {
    for (size_t i = 0; i + 1 < segment.points.size(); ++i) {
      cv::line(skeleton, fixed(segment.points[i]), fixed(segment.points[i + 1]), cv::Scalar(1), 1,
               cv::LINE_8, kShift);
    }
  }
  static_assert(kCentrelineDistanceCapPx == 30.0f, "CappedDistanceTransform takes an integer cap");
  return CappedDistanceTransform(sites, static_cast<int>(kCentrelineDistanceCapPx));
}

absl::Status ValidateInput(const ClassImage& classes, const CameraCalibration& camera) {
  if (absl::Status s = camera.Validate(); !s.ok()) return s;
  if (classes.width != camera.image_width || classes.height != camera.image_height) {
    return absl::InvalidArgumentError(absl::StrCat(
        "classes: size ", classes.width, "x", classes.height, " differs from camera '",
        camera.name, "' image size ", camera.image_width, "x", camera.image_height));
  }
  if (classes.data.size() != static_cast<size_t>(classes.width) * classes.height) {
    return absl::InvalidArgumentError(absl::StrCat("classes.data: ", classes.data.size(),
                                                   " values for ", classes.width, "x",
                                                   classes.height, " pixels"));
  }
  const auto bad = std::find_if(classes.data.begin(), classes.data.end(),
                                [](uint8_t v) { return v >= kPixelClassCount; });
  if (bad != classes.data.end()) {
    return absl::InvalidArgumentError(absl::StrCat("classes.data[", bad - classes.data.begin(),
                                                   "]: class ", static_cast<int>(*bad),
                                                   " is not a PixelClass"));
  }
  return absl::OkStatus();
}

absl::StatusOr<View2D> Extract(const ClassImage& classes, const CameraCalibration& camera,
                               const Structure2DOptions& options, const Deadline& deadline) {
  constexpr const char* kWhat = "structure2d";
  View2D view;
  view.width = classes.width;
  view.height = classes.height;
  view.classes = classes;

  BinaryImage fg_mask = BridgedForeground(classes, options.max_wire_gap_px);
  FlipSmallComponents(1, options.min_speck_area_px - 1, /*eight_connected=*/true,
                      /*border_is_large=*/false, &fg_mask);
  FlipSmallComponents(0, options.max_pinhole_area_px, /*eight_connected=*/false,
                      /*border_is_large=*/true, &fg_mask);
  const cv::Mat fg(fg_mask.height, fg_mask.width, CV_8U, fg_mask.data.data());
  cv::Mat distance;
  cv::distanceTransform(fg, distance, cv::DIST_L2, cv::DIST_MASK_5);
  view.thick_mask = ThickMask(fg, distance, options.thick_radius_px);
  if (absl::Status s = deadline.Check(kWhat); !s.ok()) return s;

  BinaryImage mask = fg_mask;
  ThinMask(&mask);
  if (absl::Status s = deadline.Check(kWhat); !s.ok()) return s;

  SkeletonGraph graph = TraceSkeleton(mask);
  PruneOptions prune;
  prune.spur_width_factor = options.spur_width_factor;
  prune.min_spur_px = options.min_spur_px;
  prune.merge_width_factor = options.junction_merge_factor;
  prune.min_isolated_px = options.min_segment_px;
  PruneSkeleton(
      prune, [&](int x, int y) { return static_cast<double>(distance.at<float>(y, x)); }, &graph);

  view.nodes.resize(graph.nodes.size());
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    view.nodes[i].position = graph.nodes[i].position;
  }
  for (const SkeletonGraph::Path& path : graph.paths) {
    Segment2D segment = BuildSegment(graph, path, fg, distance, options);
    segment.node_begin = path.node_begin;
    segment.node_end = path.node_end;
    const int index = static_cast<int>(view.segments.size());
    view.nodes[path.node_begin].position = segment.points.front();
    view.nodes[path.node_end].position = segment.points.back();
    view.nodes[path.node_begin].segments.push_back(index);
    view.nodes[path.node_end].segments.push_back(index);
    view.segments.push_back(std::move(segment));
  }
  // Junction positions are the cluster centres (segments start there); ends moved with the tips.
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (graph.Degree(static_cast<int>(i)) != 1) view.nodes[i].position = graph.nodes[i].position;
  }
  if (absl::Status s = deadline.Check(kWhat); !s.ok()) return s;

  view.centreline_distance_px = CentrelineDistance(view.segments, view.width, view.height);
  view.wires = ExtractWires(classes, camera, options);
  view.posts = ExtractPosts(classes, camera, options);
  if (absl::Status s = deadline.Check(kWhat); !s.ok()) return s;
  return view;
}

}  // namespace

absl::Status Structure2DOptions::Validate() const {
  const auto bad = [](const char* field, double value) {
    return absl::InvalidArgumentError(
        absl::StrCat("Structure2DOptions.", field, ": invalid value ", value));
  };
  if (min_speck_area_px < 0) return bad("min_speck_area_px", min_speck_area_px);
  if (max_pinhole_area_px < 0) return bad("max_pinhole_area_px", max_pinhole_area_px);
  if (max_wire_gap_px < 0) return bad("max_wire_gap_px", max_wire_gap_px);
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!non_negative(spur_width_factor)) return bad("spur_width_factor", spur_width_factor);
  if (!non_negative(min_spur_px)) return bad("min_spur_px", min_spur_px);
  if (!non_negative(junction_merge_factor)) {
    return bad("junction_merge_factor", junction_merge_factor);
  }
  if (!non_negative(min_segment_px)) return bad("min_segment_px", min_segment_px);
  if (!non_negative(max_centre_shift_px)) return bad("max_centre_shift_px", max_centre_shift_px);
  if (smoothing_passes < 0 || smoothing_passes > 20) {
    return bad("smoothing_passes", smoothing_passes);
  }
  if (!(std::isfinite(thick_radius_px) && thick_radius_px >= 1.0)) {
    return bad("thick_radius_px", thick_radius_px);
  }
  if (min_wire_piece_px < 0) return bad("min_wire_piece_px", min_wire_piece_px);
  if (!positive(wire_inlier_px)) return bad("wire_inlier_px", wire_inlier_px);
  if (!positive(wire_merge_px)) return bad("wire_merge_px", wire_merge_px);
  if (!(positive(wire_merge_angle_deg) && wire_merge_angle_deg < 90.0)) {
    return bad("wire_merge_angle_deg", wire_merge_angle_deg);
  }
  if (!non_negative(min_wire_length_px)) return bad("min_wire_length_px", min_wire_length_px);
  if (min_post_area_px < 0) return bad("min_post_area_px", min_post_area_px);
  if (!positive(post_inlier_px)) return bad("post_inlier_px", post_inlier_px);
  if (!positive(post_merge_px)) return bad("post_merge_px", post_merge_px);
  if (!non_negative(min_post_length_px)) return bad("min_post_length_px", min_post_length_px);
  if (!(positive(max_post_tilt_deg) && max_post_tilt_deg < 90.0)) {
    return bad("max_post_tilt_deg", max_post_tilt_deg);
  }
  if (ransac_iterations < 1) return bad("ransac_iterations", ransac_iterations);
  return absl::OkStatus();
}

absl::StatusOr<View2D> ExtractStructure(const ClassImage& classes,
                                        const CameraCalibration& camera,
                                        const Structure2DOptions& options,
                                        const Deadline& deadline) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = ValidateInput(classes, camera); !s.ok()) return s;
  if (absl::Status s = deadline.Check("structure2d"); !s.ok()) return s;
  try {
    return Extract(classes, camera, options, deadline);
  } catch (const cv::Exception& e) {
    return absl::InternalError(absl::StrCat("structure2d: OpenCV: ", e.what()));
  }
}

}  // namespace vb::reconstruct
