// SPDX-License-Identifier: Apache-2.0
// Internal to the renderer: materials, procedural textures, LED lighting and shadows.
//
// Shadows: for each light, every caster (cane, trunk, head, wire, post) is projected from the light
// onto the backdrop plane and rasterised there into a coverage map that also records the depth (y)
// of the nearest caster, with a penumbra from the light's size. A surface point is shadowed by the
// casters that cover its own projection onto the plane and lie nearer the light than it: this
// shadows the backdrop, the ground and canes behind other canes with one lookup per light.
// Not part of the public API.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/render_rays.h"
#include "sim/render_scene.h"
#include "sim/renderer.h"
#include "sim/scene.h"

namespace vb::sim::render {

// Deterministic lattice value noise in [0, 1], smooth (C1) between integer lattice points.
float ValueNoise(float x, float y, uint32_t seed);
uint32_t HashU32(uint32_t a, uint32_t b, uint32_t c);

class ShadowMaps {
 public:
  // Maps cover the part of the backdrop plane seen through `rays` (plus a margin).
  // With options.shadows false nothing is ever blocked.
  ShadowMaps(const Scene& scene, const std::vector<Segment>& segments, const RenderOptions& options,
             const Eigen::Vector3d& camera_centre, const RayTable& rays);

  // Fraction in [0, 1] of light `light`'s disc hidden from platform point (x, y, z).
  float Blocked(int light, float x, float y, float z) const;

  // The cells of the maps: the visible part of the backdrop plane, x and z from (x0, z0) in steps
  // of `cell` metres. Defined even when shadows are off.
  struct Grid {
    float x0 = 0, z0 = 0, cell = 0.006f;
    int nx = 0, nz = 0;
  };
  const Grid& grid() const { return grid_; }
  // Shadow coverage in [0, 1] of light `light` on the backdrop at cell index iz * nx + ix.
  float BackdropCoverage(int light, size_t cell) const {
    const Map& m = maps_[light];
    return m.cells.empty() ? 0.0f : static_cast<float>(m.cells[cell] & 0xFFu) * (1.0f / 255.0f);
  }

 private:
  struct Map {
    float lx = 0, ly = 0, lz = 0;  // light position
    float x0 = 0, z0 = 0;          // plane coordinates of cell (0, 0)
    int nx = 0, nz = 0;
    // Per cell: coverage * 255 in the low byte, the nearest caster's y quantised over
    // [ly, backdrop_y] in the high byte (one load per cell in the per-pixel lookup).
    std::vector<uint16_t> cells;
  };
  void Rasterise(const Segment& s, Map* m) const;

  Grid grid_;
  float backdrop_y_;
  float light_radius_;
  float depth_scale_;  // quantisation steps per metre of y for the light being built
  std::vector<Map> maps_;
};

// Shades surface points into linear RGB (1.0 = white) before exposure, vignetting and noise.
class Shader {
 public:
  Shader(const Scene& scene, const std::vector<Segment>& segments, const RenderOptions& options,
         const Eigen::Vector3d& camera_centre, const RayTable& rays);

  // The surface of `prim` hit (or, for partial coverage, grazed) by unit ray `r` from the camera.
  void ShadePrimitive(const Primitive& prim, const Approach& ap, const RayF& r, float rgb[3]) const;
  // The backdrop, the ground, or black where the ray meets neither.
  void ShadeBackground(const RayF& r, float rgb[3]) const;

 private:
  // Adds the lights' contribution at platform point p with unit normal n, unit vector to the
  // camera v, for a surface with the given albedo and specular strength / exponent.
  void Light(const float p[3], const float n[3], const float v[3], const float albedo[3],
             float specular, int shininess, float rgb[3]) const;
  float Unevenness(float x, float z) const;
  // Fraction of the pixel whose ray meets the backdrop at (x, z), t metres from the camera, that
  // a fiducial disc covers (box filter over the pixel footprint).
  float FiducialCoverage(float x, float z, float t) const;
  void FillUnevenness(const Scene& scene);
  void BuildBackdrop();

  struct LightF {
    float x, y, z, power;  // power = intensity * (0.8 m)^2
  };
  std::vector<LightF> lights_;
  struct FiducialF {
    float x, z, radius;
  };
  std::vector<FiducialF> fiducials_;
  float pix_angle_ = 0.0f;  // angle between neighbouring pixels' rays at the image centre
  const Scene& scene_;
  const std::vector<Segment>& segments_;
  const RenderOptions& options_;
  float cx_, cy_, cz_;  // camera centre
  ShadowMaps shadows_;
  // Low-frequency backdrop shading on a coarse grid over the plane (bilinear lookups).
  float grid_x0_ = 0, grid_z0_ = 0;
  int grid_nx_ = 0, grid_nz_ = 0;
  std::vector<float> grid_;
  // Backdrop irradiance (lights, shadows, ambient) times unevenness on the shadow map cells.
  std::vector<float> backdrop_;
};

}  // namespace vb::sim::render
