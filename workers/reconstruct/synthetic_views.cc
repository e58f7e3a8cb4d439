// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/synthetic_views.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <utility>

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

struct Sample {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  double width_px = 0.0;
  bool visible = false;
};

// Every cane's samples in `camera`'s view, every ~step_m along it: position, width (at least
// min_width_px), and whether the image sees it.
std::vector<std::vector<Sample>> ProjectSamples(const VineModel& model,
                                                const CameraCalibration& camera, double step_m,
                                                double min_width_px) {
  std::vector<std::vector<Sample>> samples(model.canes.size());
  for (size_t c = 0; c < model.canes.size(); ++c) {
    const Polyline3& line = model.canes[c].polyline;
    const std::vector<double> s = line.ArcLengths();
    const double length = s.empty() ? 0.0 : s.back();
    const int n = std::max(2, static_cast<int>(std::ceil(length / step_m)) + 1);
    for (int k = 0; k < n; ++k) {
      const double sk = length * k / (n - 1);
      const Eigen::Vector3d p = line.PointAt(sk, s);
      Sample sample;
      const auto uv = camera.Project(p);
      if (uv && camera.InImage(*uv)) {
        sample.uv = *uv;
        sample.width_px = std::max(min_width_px, WidthPx(camera, p, line.RadiusAt(sk, s)));
        sample.visible = true;
      }
      samples[c].push_back(sample);
    }
  }
  return samples;
}

// What lies beside a sample in its view.
enum class Beside : uint8_t {
  kNothing,
  kCrossing,    // another cane, in a run of such samples at most kMaxCrossingRunPx long
  kAlongFirst,  // another cane, in a longer run; this cane is listed before every such cane
  kAlongLater,  // ... a cane listed before this one lies beside it
};
// Runs longer than this are a cane lying along another: a skeleton draws one path for the pair
// rather than breaking it.
constexpr double kMaxCrossingRunPx = 30.0;

// For each sample, what lies within `margin_px` plus the two half-widths of it (visible samples of
// other canes only). All kNothing for margin_px <= 0.
std::vector<std::vector<Beside>> Classify(const std::vector<std::vector<Sample>>& samples,
                                          double margin_px) {
  std::vector<std::vector<Beside>> beside(samples.size());
  std::vector<std::vector<int>> first_other(samples.size());
  for (size_t c = 0; c < samples.size(); ++c) {
    beside[c].assign(samples[c].size(), Beside::kNothing);
    first_other[c].assign(samples[c].size(), static_cast<int>(samples.size()));
  }
  if (!(margin_px > 0.0)) return beside;
  // A grid of cells of `cell` px holding (cane, sample) of every visible sample.
  double widest = 0.0;
  for (const auto& cane : samples)
    for (const Sample& s : cane) widest = std::max(widest, s.visible ? s.width_px : 0.0);
  const double cell = std::max(4.0, widest + margin_px);
  std::unordered_map<int64_t, std::vector<std::pair<int, int>>> grid;
  auto key = [&](const Eigen::Vector2d& uv, int dx, int dy) {
    const int64_t x = static_cast<int64_t>(std::floor(uv.x() / cell)) + dx;
    const int64_t y = static_cast<int64_t>(std::floor(uv.y() / cell)) + dy;
    return (x << 32) ^ (y & 0xffffffff);
  };
  for (size_t c = 0; c < samples.size(); ++c)
    for (size_t k = 0; k < samples[c].size(); ++k)
      if (samples[c][k].visible)
        grid[key(samples[c][k].uv, 0, 0)].emplace_back(static_cast<int>(c), static_cast<int>(k));
  for (size_t c = 0; c < samples.size(); ++c) {
    for (size_t k = 0; k < samples[c].size(); ++k) {
      const Sample& s = samples[c][k];
      if (!s.visible) continue;
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          const auto it = grid.find(key(s.uv, dx, dy));
          if (it == grid.end()) continue;
          for (const auto& [oc, ok] : it->second) {
            if (oc == static_cast<int>(c)) continue;
            const Sample& o = samples[oc][ok];
            if ((o.uv - s.uv).norm() <= 0.5 * (s.width_px + o.width_px) + margin_px) {
              beside[c][k] = Beside::kCrossing;
              first_other[c][k] = std::min(first_other[c][k], oc);
            }
          }
        }
      }
    }
  }
  for (size_t c = 0; c < samples.size(); ++c) {
    for (size_t k = 0; k < samples[c].size();) {
      if (beside[c][k] == Beside::kNothing) {
        ++k;
        continue;
      }
      size_t end = k;
      double run_px = 0.0;
      while (end + 1 < samples[c].size() && beside[c][end + 1] != Beside::kNothing) {
        run_px += (samples[c][end + 1].uv - samples[c][end].uv).norm();
        ++end;
      }
      if (run_px > kMaxCrossingRunPx) {
        for (size_t i = k; i <= end; ++i) {
          beside[c][i] = first_other[c][i] < static_cast<int>(c) ? Beside::kAlongLater
                                                                 : Beside::kAlongFirst;
        }
      }
      k = end + 1;
    }
  }
  return beside;
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
    const std::vector<std::vector<Sample>> samples =
        ProjectSamples(model, camera, options.sample_step_m, options.min_width_px);
    const std::vector<std::vector<Beside>> beside =
        Classify(samples, options.break_at_crossings_px);
    for (size_t c = 0; c < model.canes.size(); ++c) {
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
      for (size_t k = 0; k < samples[c].size(); ++k) {
        const Sample& sample = samples[c][k];
        if (!sample.visible) {
          flush();
          continue;
        }
        const double w = sample.width_px;
        if (k > 0 && samples[c][k - 1].visible) {
          const Eigen::Vector2d& prev = samples[c][k - 1].uv;
          const int iw = std::max(1, static_cast<int>(std::lround(w)));
          cv::line(classes, ToCv(prev), ToCv(sample.uv),
                   cv::Scalar(static_cast<int>(PixelClass::kForeground)), iw);
          if (w >= thick_width_px) cv::line(thick, ToCv(prev), ToCv(sample.uv), 1, iw);
          cv::line(skeleton, ToCv(prev), ToCv(sample.uv), cv::Scalar(0), 1);
        }
        if (beside[c][k] == Beside::kCrossing ||
            (options.merge_overlaps && beside[c][k] == Beside::kAlongLater)) {
          flush();
          continue;
        }
        current.points.push_back(sample.uv);
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

std::vector<std::vector<bool>> LyingAlongAnother(const VineModel& model,
                                                 const CameraCalibration& camera, double step_m,
                                                 double margin_px) {
  const std::vector<std::vector<Beside>> beside =
      Classify(ProjectSamples(model, camera, step_m, 1.0), margin_px);
  std::vector<std::vector<bool>> along(beside.size());
  for (size_t c = 0; c < beside.size(); ++c) {
    for (Beside b : beside[c]) {
      along[c].push_back(b == Beside::kAlongFirst || b == Beside::kAlongLater);
    }
  }
  return along;
}

}  // namespace vb::reconstruct
