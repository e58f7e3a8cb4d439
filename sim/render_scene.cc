// SPDX-License-Identifier: Apache-2.0
#include "sim/render_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace vb::sim::render {
namespace {

void AddPolyline(const Polyline3& line, Material material, uint16_t label, int object,
                 std::vector<Segment>* out) {
  double s = 0.0;
  for (size_t i = 0; i + 1 < line.points.size() && i + 1 < line.radii.size(); ++i) {
    const double len = (line.points[i + 1] - line.points[i]).norm();
    if (len > 1e-6) {
      out->push_back({line.points[i], line.points[i + 1], line.radii[i], line.radii[i + 1],
                      Shape::kCapsule, material, label, object, static_cast<float>(s)});
    }
    s += len;
  }
}

// Splits a long straight primitive so every piece has a small angular extent: screen bounds are
// computed from projected sample points, and lens distortion bends long pieces.
void AddSplit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, double max_len,
              Shape shape, Material material, uint16_t label, int object,
              std::vector<Segment>* out) {
  const double len = (b - a).norm();
  if (!(len > 1e-6) || !(radius > 0.0)) return;
  const int n = std::max(1, static_cast<int>(std::ceil(len / max_len)));
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(i) / n);
    const Eigen::Vector3d q = a + (b - a) * (static_cast<double>(i + 1) / n);
    out->push_back({p, q, radius, radius, shape, material, label, object,
                    static_cast<float>(len * i / n)});
  }
}

uint16_t CaneLabel(CaneId id) {
  const int64_t v = kLabelCaneBase + id.value;
  return static_cast<uint16_t>(std::clamp<int64_t>(v, kLabelCaneBase, 65535));
}

}  // namespace

std::vector<Segment> BuildSegments(const Scene& scene) {
  std::vector<Segment> out;
  int object = 0;
  for (const Cane& cane : scene.vine.canes) {
    const Material m = cane.kind == CaneKind::kTrunk ? Material::kTrunk : Material::kCane;
    AddPolyline(cane.polyline, m, CaneLabel(cane.id), object++, &out);
  }
  auto add_head = [&](const HeadModel& head, Material m, uint16_t label) {
    const int obj = object++;
    for (const Sphere& s : head.spheres) {
      if (s.radius > 0.0) out.push_back({s.center, s.center, s.radius, s.radius, Shape::kSphere, m, label, obj, 0.0f});
    }
  };
  add_head(scene.vine.head, Material::kHead, kLabelHead);
  for (const Wire& wire : scene.vine.wires) {
    const int obj = object++;
    double s = 0.0;
    for (size_t i = 0; i + 1 < wire.points.size(); ++i) {
      const size_t first = out.size();
      AddSplit(wire.points[i], wire.points[i + 1], wire.radius, 0.03, Shape::kCapsule,
               Material::kWire, kLabelWire, obj, &out);
      for (size_t k = first; k < out.size(); ++k) out[k].s0 += static_cast<float>(s);
      s += (wire.points[i + 1] - wire.points[i]).norm();
    }
  }
  for (const Post& post : scene.vine.posts) {
    AddSplit(post.base, post.top, post.radius, 0.05, Shape::kCylinder, Material::kPost,
             kLabelPost, object++, &out);
  }
  for (const VineModel& n : scene.neighbours) {
    for (const Cane& cane : n.canes) {
      AddPolyline(cane.polyline, Material::kOtherCane, kLabelOtherVine, object++, &out);
    }
    add_head(n.head, Material::kOtherHead, kLabelOtherVine);
  }
  return out;
}

namespace {

// Pinhole + distortion projection with a validity test: points behind the camera or beyond the
// radius where the distortion polynomial is still monotonic have no trustworthy pixel.
struct Projector {
  const CameraCalibration& cam;
  double r2_valid;

  std::optional<Eigen::Vector2d> operator()(const Eigen::Vector3d& p, double* z_out) const {
    const Eigen::Vector3d q = cam.rotation_camera_from_platform * p + cam.translation_camera_from_platform;
    if (q.z() < 0.02) return std::nullopt;
    const Eigen::Vector2d xy(q.x() / q.z(), q.y() / q.z());
    if (xy.squaredNorm() > r2_valid) return std::nullopt;
    *z_out = q.z();
    return cam.NormalisedToPixel(xy);
  }
};

double ValidRadius2(const CameraCalibration& cam, const RayTable& rays) {
  // Widest normalised radius seen by the image border, plus margin so that primitives just
  // outside the image still get bounds that reach into it.
  double r2_max = 0.0;
  const Eigen::Matrix3d& r = cam.rotation_camera_from_platform;
  auto visit = [&](int x, int y) {
    const RayF& f = rays.at(x, y);
    const Eigen::Vector3d d = r * Eigen::Vector3d(f.x, f.y, f.z);
    if (d.z() > 1e-6) r2_max = std::max(r2_max, (d.head<2>() / d.z()).squaredNorm());
  };
  for (int x = 0; x < rays.width(); x += 4) {
    visit(x, 0);
    visit(x, rays.height() - 1);
  }
  for (int y = 0; y < rays.height(); y += 4) {
    visit(0, y);
    visit(rays.width() - 1, y);
  }
  // The radial polynomial's fold (where r_d stops growing) bounds the usable radius.
  const auto& [k1, k2, p1, p2, k3] = cam.distortion;
  double prev = 0.0;
  double r_fold = 10.0;
  for (double rr = 1e-3; rr < 10.0; rr += 1e-3) {
    const double r2 = rr * rr;
    const double rd = rr * (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)));
    if (rd <= prev) {
      r_fold = rr;
      break;
    }
    prev = rd;
  }
  const double r_valid = std::min(1.2 * std::sqrt(r2_max) + 0.05, 0.98 * r_fold);
  return r_valid * r_valid;
}

struct Box {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0;
  double x1 = -std::numeric_limits<double>::infinity(), y1 = x1;
  void Add(const Eigen::Vector2d& p, double pad) {
    x0 = std::min(x0, p.x() - pad);
    y0 = std::min(y0, p.y() - pad);
    x1 = std::max(x1, p.x() + pad);
    y1 = std::max(y1, p.y() + pad);
  }
  bool empty() const { return !(x0 <= x1); }
};

void BoundSegment(const Projector& project, double fx, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, double radius, int depth, Box* box) {
  const Eigen::Vector3d pts[3] = {a, 0.5 * (a + b), b};
  std::optional<Eigen::Vector2d> uv[3];
  bool all = true;
  for (int i = 0; i < 3; ++i) {
    double z = 0.0;
    uv[i] = project(pts[i], &z);
    if (uv[i]) {
      // fx over-estimates the local magnification of a barrel lens, so this pad is conservative.
      box->Add(*uv[i], radius * fx / z + 2.0);
    } else {
      all = false;
    }
  }
  if (all || depth >= 4 || (b - a).norm() < 1e-3) return;
  BoundSegment(project, fx, a, pts[1], radius, depth + 1, box);
  BoundSegment(project, fx, pts[1], b, radius, depth + 1, box);
}

}  // namespace

std::vector<Primitive> PreparePrimitives(const std::vector<Segment>& segments,
                                         const CameraCalibration& camera, const RayTable& rays) {
  const Projector project{camera, ValidRadius2(camera, rays)};
  const double fx = std::max(camera.camera_matrix(0, 0), camera.camera_matrix(1, 1));
  const Eigen::Vector3d c = camera.CentreInPlatform();
  const int w = rays.width();
  const int h = rays.height();
  std::vector<Primitive> out;
  out.reserve(segments.size());
  for (size_t i = 0; i < segments.size(); ++i) {
    const Segment& s = segments[i];
    Box box;
    BoundSegment(project, fx, s.a, s.b, std::max(s.ra, s.rb), 0, &box);
    if (box.empty()) continue;
    Primitive p{};
    p.x0 = std::max(0, static_cast<int>(std::floor(box.x0)));
    p.y0 = std::max(0, static_cast<int>(std::floor(box.y0)));
    p.x1 = std::min(w - 1, static_cast<int>(std::ceil(box.x1)));
    p.y1 = std::min(h - 1, static_cast<int>(std::ceil(box.y1)));
    if (p.x0 > p.x1 || p.y0 > p.y1) continue;
    const Eigen::Vector3d a = s.a - c;
    Eigen::Vector3d u = s.b - s.a;
    const double len = u.norm();
    p.shape = s.shape;
    if (s.shape == Shape::kSphere || len < 1e-9) {
      u.setZero();
      p.shape = Shape::kSphere;
    } else {
      u /= len;
    }
    p.ax = static_cast<float>(a.x());
    p.ay = static_cast<float>(a.y());
    p.az = static_cast<float>(a.z());
    p.ux = static_cast<float>(u.x());
    p.uy = static_cast<float>(u.y());
    p.uz = static_cast<float>(u.z());
    p.length = p.shape == Shape::kSphere ? 0.0f : static_cast<float>(len);
    p.ra = static_cast<float>(s.ra);
    p.drds = p.shape == Shape::kSphere ? 0.0f : static_cast<float>((s.rb - s.ra) / len);
    p.a2 = static_cast<float>(a.squaredNorm());
    p.eu = static_cast<float>(u.dot(a));
    // Angular pixel size where the primitive appears: lens distortion makes it vary a lot
    // across a wide-angle image, and coverage needs the pixel's footprint in metres.
    const int mx = std::clamp((p.x0 + p.x1) / 2, 0, w - 2);
    const int my = std::clamp((p.y0 + p.y1) / 2, 0, h - 2);
    const RayF& r0 = rays.at(mx, my);
    const RayF& rx = rays.at(mx + 1, my);
    const RayF& ry = rays.at(mx, my + 1);
    const float ax = std::hypot(rx.x - r0.x, rx.y - r0.y, rx.z - r0.z);
    const float ay = std::hypot(ry.x - r0.x, ry.y - r0.y, ry.z - r0.z);
    p.pix_angle = (ax > 0.0f && ay > 0.0f) ? 0.5f * (ax + ay) : static_cast<float>(1.0 / fx);
    p.seg = static_cast<int>(i);
    out.push_back(p);
  }
  return out;
}

std::vector<PixelHit> CastPrimary(const std::vector<Primitive>& prims,
                                  const std::vector<Segment>& segments, const RayTable& rays) {
  const int w = rays.width();
  constexpr float kFar = std::numeric_limits<float>::infinity();
  std::vector<PixelHit> hits(static_cast<size_t>(w) * rays.height(),
                             PixelHit{kFar, -1, kFar, -1, 0.0f});
  for (size_t i = 0; i < prims.size(); ++i) {
    const Primitive& p = prims[i];
    const int object = segments[p.seg].object;
    for (int y = p.y0; y <= p.y1; ++y) {
      const RayF* ray = rays.row(y);
      PixelHit* row = &hits[static_cast<size_t>(y) * w];
      for (int x = p.x0; x <= p.x1; ++x) {
        const RayF& r = ray[x];
        Approach ap = Closest(p, r.x, r.y, r.z, /*with_distance=*/false);
        if (!ap.ok) continue;
        const float footprint = ap.t * p.pix_angle;
        const float reach = ap.radius + 0.5f * footprint;
        if (ap.d2 >= reach * reach) continue;  // most of a bounding box misses; skip the sqrt
        ap.d = std::sqrt(ap.d2);
        const float cov = Coverage(ap.d, ap.radius, footprint);
        const float t = ap.d < ap.radius ? ap.t - std::sqrt(ap.radius * ap.radius - ap.d * ap.d) : ap.t;
        PixelHit& px = row[x];
        if (t >= px.depth) continue;
        if (cov >= 0.999f) {
          px.depth = t;
          px.prim = static_cast<int32_t>(i);
        } else if (cov > 0.01f) {
          // Consecutive pieces of one object overlap at joints; their coverages are of the same
          // surface, so keep the larger rather than letting the nearer sliver win.
          if (px.front_prim >= 0 && segments[prims[px.front_prim].seg].object == object) {
            if (cov > px.front_cov) {
              px.front_cov = cov;
              px.front_prim = static_cast<int32_t>(i);
              px.front_depth = std::min(px.front_depth, t);
            }
          } else if (t < px.front_depth) {
            px.front_depth = t;
            px.front_prim = static_cast<int32_t>(i);
            px.front_cov = cov;
          }
        }
      }
    }
  }
  return hits;
}

}  // namespace vb::sim::render
