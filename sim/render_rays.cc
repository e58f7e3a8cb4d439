// SPDX-License-Identifier: Apache-2.0
#include "sim/render_rays.h"

#include <cmath>
#include <deque>
#include <mutex>

namespace vb::sim {
namespace {

std::vector<double> KeyOf(const CameraCalibration& c) {
  std::vector<double> key = {static_cast<double>(c.image_width),
                             static_cast<double>(c.image_height)};
  for (int i = 0; i < 9; ++i) key.push_back(c.camera_matrix(i / 3, i % 3));
  for (double d : c.distortion) key.push_back(d);
  for (int i = 0; i < 9; ++i) key.push_back(c.rotation_camera_from_platform(i / 3, i % 3));
  return key;
}

}  // namespace

RayTable::RayTable(const CameraCalibration& camera)
    : width_(camera.image_width), height_(camera.image_height), key_(KeyOf(camera)) {
  rays_.resize(static_cast<size_t>(width_) * height_);
  const Eigen::Matrix3d platform_from_camera = camera.rotation_camera_from_platform.transpose();
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const Eigen::Vector2d uv(x, y);
      const Eigen::Vector2d xy = camera.PixelToNormalised(uv);
      // The fixed-point inverse silently returns garbage where it fails to converge; the round trip
      // catches that, and a black pixel is more honest than a ray from the wrong place.
      const bool ok = xy.allFinite() && (camera.NormalisedToPixel(xy) - uv).norm() < 1e-3;
      RayF& r = rays_[static_cast<size_t>(y) * width_ + x];
      if (!ok) {
        ++invalid_count_;
        continue;
      }
      const Eigen::Vector3d d = (platform_from_camera * Eigen::Vector3d(xy.x(), xy.y(), 1.0)).normalized();
      r = {static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())};
    }
  }
}

bool RayTable::Matches(const CameraCalibration& camera) const { return key_ == KeyOf(camera); }

std::shared_ptr<const RayTable> RayTableFor(const CameraCalibration& camera) {
  static std::mutex mu;
  static std::deque<std::shared_ptr<const RayTable>> cache;  // guarded by mu; newest at front
  {
    std::lock_guard<std::mutex> lock(mu);
    for (auto it = cache.begin(); it != cache.end(); ++it) {
      if ((*it)->Matches(camera)) {
        std::shared_ptr<const RayTable> hit = *it;
        cache.erase(it);
        cache.push_front(hit);
        return hit;
      }
    }
  }
  // Built outside the lock: it takes a while and other cameras should not wait for it.
  auto table = std::make_shared<const RayTable>(camera);
  std::lock_guard<std::mutex> lock(mu);
  cache.push_front(table);
  constexpr size_t kCapacity = 8;
  while (cache.size() > kCapacity) cache.pop_back();
  return table;
}

}  // namespace vb::sim
