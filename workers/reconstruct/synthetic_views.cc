// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/synthetic_views.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "opencv2/imgproc.hpp"

namespace vb::reconstruct {
namespace {

cv::Point ToCv(const Eigen::Vector2d& p) {
  return cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
}

// Width in pixels of a sphere of radius r at p seen by `camera` (2 r f / depth).
double WidthPx(const CameraCalibration& camera, const Eigen::Vector3d& p, double r) {
  const Eigen::Vector3d in_camera = camera.camera_from_platform() * p;
  return 2.0 * r * camera.camera_matrix(0, 0) / std::max(in_camera.z(), 1e-3);
}

Line2D LineFrom(const CameraCalibration& camera, const Eigen::Vector3d& a,
                const Eigen::Vector3d& b, double radius) {
  const Eigen::Isometry3d cam = camera.camera_from_platform();
  const Eigen::Vector3d ha = cam * a;
  const Eigen::Vector3d hb = cam * b;
  Line2D line;
  line.begin = ha.hnormalized();
  line.end = hb.hnormalized();
  Eigen::Vector3d l = ha.cross(hb);
  l /= l.head<2>().norm();
  line.line = l;
  line.width_px = WidthPx(camera, 0.5 * (a + b), radius);
  // The centre as the line's pixels, every ~8 px (the 2D stage's trace of what it saw).
  constexpr int kSamples = 4000;
  for (int k = 0; k <= kSamples; ++k) {
    const std::optional<Eigen::Vector2d> uv = camera.Project(a + (b - a) * k / double(kSamples));
    if (!uv || !camera.InImage(*uv)) continue;
    // Beyond the fold of the lens a point far outside the view can land in the image.
    const Eigen::Vector3d in_camera = cam * (a + (b - a) * k / double(kSamples));
    if ((camera.PixelToNormalised(*uv) - in_camera.hnormalized()).norm() > 1e-6) continue;
    if (!line.centre_px.empty() && (*uv - line.centre_px.back()).norm() < 8.0) continue;
    line.centre_px.push_back(*uv);
  }
  return line;
}

}  // namespace

std::vector<View2D> SyntheticViews(const VineModel& model, const RigCalibration& rig,
                                   const SyntheticViewOptions& options, double thick_width_px) {
  std::vector<View2D> views;
  for (const CameraCalibration& camera : rig.cameras) {
    View2D view;
    view.width = camera.image_width;
    view.height = camera.image_height;
    cv::Mat classes(view.height, view.width, CV_8U, cv::Scalar(0));
    cv::Mat thick(view.height, view.width, CV_8U, cv::Scalar(0));
    cv::Mat skeleton(view.height, view.width, CV_8U, cv::Scalar(255));

    for (const Post& post : model.posts) {
      const auto a = camera.Project(post.base);
      const auto b = camera.Project(post.top);
      view.posts.push_back(LineFrom(camera, post.base, post.top, post.radius));
      if (a && b) {
        const double w = WidthPx(camera, 0.5 * (post.base + post.top), post.radius);
        cv::line(classes, ToCv(*a), ToCv(*b), cv::Scalar(static_cast<int>(PixelClass::kPost)),
                 std::max(1, static_cast<int>(std::lround(w))));
      }
    }
    for (const Wire& wire : model.wires) {
      view.wires.push_back(LineFrom(camera, wire.points.front(), wire.points.back(), wire.radius));
      for (size_t i = 0; i + 1 < wire.points.size(); ++i) {
        // Draw through dense samples so distortion curves the wire as it should.
        const int n = 200;
        for (int k = 0; k < n; ++k) {
          const Eigen::Vector3d p = wire.points[i] + (wire.points[i + 1] - wire.points[i]) * k / n;
          const Eigen::Vector3d q =
              wire.points[i] + (wire.points[i + 1] - wire.points[i]) * (k + 1) / n;
          const auto pa = camera.Project(p);
          const auto pb = camera.Project(q);
          if (pa && pb) {
            cv::line(classes, ToCv(*pa), ToCv(*pb),
                     cv::Scalar(static_cast<int>(PixelClass::kWire)), 2);
          }
        }
      }
    }
    for (const Cane& cane : model.canes) {
      const std::vector<double> s = cane.polyline.ArcLengths();
      const double length = s.empty() ? 0.0 : s.back();
      const int n = std::max(2, static_cast<int>(std::ceil(length / options.sample_step_m)) + 1);
      Segment2D current;
      auto flush = [&]() {
        if (current.points.size() >= 2) {
          const int begin_node = static_cast<int>(view.nodes.size());
          view.nodes.push_back({current.points.front(), {static_cast<int>(view.segments.size())}});
          view.nodes.push_back({current.points.back(), {static_cast<int>(view.segments.size())}});
          current.node_begin = begin_node;
          current.node_end = begin_node + 1;
          view.segments.push_back(current);
        }
        current = Segment2D();
      };
      for (int k = 0; k < n; ++k) {
        const double sk = length * k / (n - 1);
        const Eigen::Vector3d p = cane.polyline.PointAt(sk);
        const auto uv = camera.Project(p);
        if (!uv || !camera.InImage(*uv)) {
          flush();
          continue;
        }
        const double w =
            std::max(options.min_width_px, WidthPx(camera, p, cane.polyline.RadiusAt(sk)));
        if (!current.points.empty()) {
          const int iw = std::max(1, static_cast<int>(std::lround(w)));
          cv::line(classes, ToCv(current.points.back()), ToCv(*uv),
                   cv::Scalar(static_cast<int>(PixelClass::kForeground)), iw);
          if (w >= thick_width_px) cv::line(thick, ToCv(current.points.back()), ToCv(*uv), 1, iw);
          cv::line(skeleton, ToCv(current.points.back()), ToCv(*uv), cv::Scalar(0), 1);
        }
        current.points.push_back(*uv);
        current.widths_px.push_back(w);
      }
      flush();
    }
    if (options.draw_head) {
      for (const Sphere& sphere : model.head.spheres) {
        const auto c = camera.Project(sphere.center);
        if (!c) continue;
        const int r = std::max(
            1, static_cast<int>(std::lround(0.5 * WidthPx(camera, sphere.center, sphere.radius))));
        cv::circle(classes, ToCv(*c), r, cv::Scalar(static_cast<int>(PixelClass::kForeground)),
                   cv::FILLED);
        cv::circle(thick, ToCv(*c), r, cv::Scalar(1), cv::FILLED);
      }
    }

    view.classes = ClassImage(view.width, view.height);
    std::copy(classes.datastart, classes.dataend, view.classes.data.begin());
    view.thick_mask.assign(thick.datastart, thick.dataend);
    cv::Mat distance;
    cv::distanceTransform(skeleton, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    view.centreline_distance_px.resize(static_cast<size_t>(view.width) * view.height);
    for (int y = 0; y < view.height; ++y) {
      const float* row = distance.ptr<float>(y);
      for (int x = 0; x < view.width; ++x) {
        view.centreline_distance_px[static_cast<size_t>(y) * view.width + x] =
            std::min(row[x], kCentrelineDistanceCapPx);
      }
    }
    views.push_back(std::move(view));
  }
  return views;
}

}  // namespace vb::reconstruct
