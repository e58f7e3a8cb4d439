// SPDX-License-Identifier: Apache-2.0
// Internal to the renderer: the scene as a flat list of ray-castable primitives (capsule pieces,
// flat-ended cylinder pieces, spheres), their screen bounds in one camera, and the visibility pass
// that fills a two-layer depth buffer (the nearest opaque hit plus the nearest partially covering
// thin structure in front of it, for sub-pixel coverage). Not part of the public API.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/calibration.h"
#include "Eigen/Core"
#include "sim/render_rays.h"
#include "sim/scene.h"

namespace vb::sim::render {

enum class Shape : uint8_t { kCapsule, kCylinder, kSphere };  // kCylinder has flat ends
enum class Material : uint8_t { kCane, kTrunk, kHead, kWire, kPost, kOtherCane, kOtherHead };

// One primitive in the platform frame.
struct Segment {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // axis start (sphere: centre)
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  // axis end (sphere: = a)
  double ra = 0.0;                              // radius at a
  double rb = 0.0;                              // radius at b
  Shape shape = Shape::kCapsule;
  Material material = Material::kCane;
  uint16_t label = kLabelBackground;
  int object = 0;      // index of the cane / wire / post / head it belongs to (unique per scene)
  float s0 = 0.0f;     // arc length of `a` along its object (texture coordinate)
};

// Canes and trunk per polyline segment, head spheres, wires in <= 3 cm capsule pieces, posts in
// <= 5 cm cylinder pieces, neighbours' canes and heads. Ignores degenerate pieces.
std::vector<Segment> BuildSegments(const Scene& scene);

// A segment prepared for ray casting from one camera: coordinates relative to the camera centre,
// in float, with the constants of the ray/axis closest-approach formula.
struct Primitive {
  float ax, ay, az;  // axis start minus camera centre
  float ux, uy, uz;  // unit axis (zero for spheres)
  float length;      // axis length (0 for spheres)
  float ra, drds;    // radius at a and its derivative along the axis
  float a2, eu;      // |a|^2 and u.a
  float pix_angle;   // angle subtended by one pixel near the primitive, radians
  int seg;           // index into the segment list
  Shape shape;
  int x0, y0, x1, y1;  // inclusive screen bounds, clipped to the image
};

// Closest approach of a unit ray from the camera centre to a primitive's axis.
struct Approach {
  float t;      // ray parameter of the closest point (metres from the camera centre)
  float s;      // axis parameter of the closest point, clamped to [0, length]
  float d2;     // squared distance between ray and axis at the closest approach
  float d;      // that distance (0 unless computed, see Closest)
  float radius; // primitive radius at s
  bool ok;      // false if behind the camera, or off the end of a flat-ended cylinder
};

// `with_distance` false leaves `d` for the caller to compute from `d2` when it needs it.
inline Approach Closest(const Primitive& p, float rx, float ry, float rz, bool with_distance = true) {
  Approach out{};
  float s = 0.0f;
  float tc;
  if (p.shape == Shape::kSphere) {
    tc = rx * p.ax + ry * p.ay + rz * p.az;
  } else {
    const float b = rx * p.ux + ry * p.uy + rz * p.uz;
    const float dr = rx * p.ax + ry * p.ay + rz * p.az;
    const float denom = 1.0f - b * b;
    s = denom > 1e-8f ? (dr * b - p.eu) / denom : 0.0f;
    if (p.shape == Shape::kCylinder && (s < 0.0f || s > p.length)) return out;
    s = s < 0.0f ? 0.0f : (s > p.length ? p.length : s);
    tc = dr + s * b;
  }
  if (tc <= 1e-3f) return out;
  const float d2 = p.a2 + 2.0f * s * p.eu + s * s - tc * tc;
  out.t = tc;
  out.s = s;
  out.d2 = d2 > 0.0f ? d2 : 0.0f;
  out.d = with_distance ? std::sqrt(out.d2) : 0.0f;
  out.radius = p.ra + p.drds * s;
  out.ok = true;
  return out;
}

// Fraction of a pixel footprint of width w (metres, at the primitive's depth) covered by a
// cylinder of radius r whose axis passes at distance d from the pixel's ray (box filter across
// the axis).
inline float Coverage(float d, float r, float w) {
  const float hi = (d + 0.5f * w < r) ? d + 0.5f * w : r;
  const float lo = (d - 0.5f * w > -r) ? d - 0.5f * w : -r;
  const float c = (hi - lo) / w;
  return c < 0.0f ? 0.0f : (c > 1.0f ? 1.0f : c);
}

// Primitives of `segments` that may be visible in `camera`, with screen bounds. Bounds come from
// projecting sample points of each segment (subdividing where points lie behind the camera or
// beyond where the lens model is monotonic) padded by the projected radius.
std::vector<Primitive> PreparePrimitives(const std::vector<Segment>& segments,
                                         const CameraCalibration& camera, const RayTable& rays);

// Per-pixel result of the visibility pass. prim indexes the Primitive list; -1 = none (the ray
// continues to the backdrop / ground).
struct PixelHit {
  float depth;        // ray parameter of the nearest opaque hit
  int32_t prim;
  float front_depth;  // nearest partially covering primitive in front of `depth`
  int32_t front_prim;
  float front_cov;    // its coverage in (0, 1)
};

// Ray-casts every primitive inside its screen bounds; nearest hit wins.
std::vector<PixelHit> CastPrimary(const std::vector<Primitive>& prims,
                                  const std::vector<Segment>& segments, const RayTable& rays);

}  // namespace vb::sim::render
