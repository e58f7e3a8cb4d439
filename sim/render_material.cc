// SPDX-License-Identifier: Apache-2.0
// The Shader of render_shading.h: what each surface looks like under the rig's LED flashes.
#include <algorithm>
#include <cmath>

#include "sim/render_shading.h"

namespace vb::sim::render {
namespace {

constexpr float kRefDistance2 = 0.64f;  // Light::intensity is defined at 0.8 m (sim/scene.h)
constexpr float kGridCell = 0.02f;
constexpr float kTwoPi = 6.2831853f;
constexpr float kBackdrop[3] = {0.09f, 0.24f, 0.66f};  // blue cloth albedo
constexpr float kFiducialWhite = 0.8f;                  // albedo of the printed discs

inline float Clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }
inline float Frac(float v) { return v - std::floor(v); }
inline float Unit(uint32_t h) { return static_cast<float>(h) * (1.0f / 4294967295.0f); }

// atan2 to ~0.01 rad (a rational approximation on [0, 1] plus octant folding): texture
// coordinates do not need libm's accuracy, and this runs for every cane pixel.
inline float FastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay);
  if (mx <= 0.0f) return 0.0f;
  const float a = std::min(ax, ay) / mx;
  float r = a * (0.7853982f + 0.273f * (1.0f - a));
  if (ay > ax) r = 1.5707963f - r;
  if (x < 0.0f) r = 3.1415927f - r;
  return y < 0.0f ? -r : r;
}

inline float PowInt(float x, int n) {
  float r = 1.0f;
  while (n > 0) {
    if (n & 1) r *= x;
    x *= x;
    n >>= 1;
  }
  return r;
}

}  // namespace

Shader::Shader(const Scene& scene, const std::vector<Segment>& segments,
               const RenderOptions& options, const Eigen::Vector3d& camera_centre,
               const RayTable& rays)
    : scene_(scene),
      segments_(segments),
      options_(options),
      cx_(static_cast<float>(camera_centre.x())),
      cy_(static_cast<float>(camera_centre.y())),
      cz_(static_cast<float>(camera_centre.z())),
      shadows_(scene, segments, options, camera_centre, rays) {
  for (const sim::Light& l : scene.lights) {
    lights_.push_back({static_cast<float>(l.position_in_platform.x()),
                       static_cast<float>(l.position_in_platform.y()),
                       static_cast<float>(l.position_in_platform.z()),
                       static_cast<float>(l.intensity) * kRefDistance2});
  }
  // The backdrop is a cloth: broad uneven illumination and a few soft vertical folds. Computed
  // on a coarse grid once so the per-pixel cost is a bilinear lookup.
  grid_x0_ = cx_ - 4.0f;
  grid_z0_ = -1.0f;
  grid_nx_ = static_cast<int>(8.0f / kGridCell) + 2;
  grid_nz_ = static_cast<int>(5.0f / kGridCell) + 2;
  grid_.assign(static_cast<size_t>(grid_nx_) * grid_nz_, 1.0f);
  if (options.texture) FillUnevenness(scene);
  BuildBackdrop();
  for (const Fiducial& f : scene.fiducials) {
    fiducials_.push_back({static_cast<float>(f.position_in_platform.x()),
                          static_cast<float>(f.position_in_platform.z()),
                          static_cast<float>(f.radius_m)});
  }
  const int mx = rays.width() / 2, my = rays.height() / 2;
  if (mx + 1 < rays.width()) {
    const RayF& a = rays.at(mx, my);
    const RayF& b = rays.at(mx + 1, my);
    pix_angle_ = std::hypot(b.x - a.x, b.y - a.y, b.z - a.z);
  }
}

float Shader::FiducialCoverage(float x, float z, float t) const {
  // The footprint at the image centre: at the edges a barrel lens widens it, which only makes the
  // discs' edges there a little sharper than a box filter would.
  const float w = std::max(t * pix_angle_, 1e-6f);
  float best = 0.0f;
  for (const FiducialF& f : fiducials_) {
    const float dx = x - f.x, dz = z - f.z, reach = f.radius + w;
    if (std::abs(dx) > reach || std::abs(dz) > reach) continue;
    best = std::max(best, Clamp01((f.radius - std::sqrt(dx * dx + dz * dz)) / w + 0.5f));
  }
  return best;
}

void Shader::FillUnevenness(const Scene& scene) {
  const auto seed = static_cast<uint32_t>(scene.seed ^ (scene.seed >> 32)) + 977u * scene.vine_index;
  for (int iz = 0; iz < grid_nz_; ++iz) {
    for (int ix = 0; ix < grid_nx_; ++ix) {
      const float x = grid_x0_ + ix * kGridCell + static_cast<float>(scene.vine_position_m);
      const float z = grid_z0_ + iz * kGridCell;
      const float broad = 0.65f * ValueNoise(x / 0.5f, z / 0.5f, seed) +
                          0.35f * ValueNoise(x / 0.17f, z / 0.17f, seed + 1);
      const float fold = ValueNoise(x / 0.06f, z / 0.9f, seed + 2);
      grid_[static_cast<size_t>(iz) * grid_nx_ + ix] =
          (0.80f + 0.38f * broad) * (1.0f - 0.10f * fold * fold * fold);
    }
  }
}

void Shader::BuildBackdrop() {
  // Everything on the backdrop except its colour varies slowly or is already sampled on the shadow
  // cells (lighting, shadows, unevenness), so it is evaluated once per cell rather than per pixel;
  // a backdrop pixel is then one bilinear lookup. Cells (6 mm) are 2-3 pixels wide, finer than the shadow penumbrae.
  const ShadowMaps::Grid& g = shadows_.grid();
  backdrop_.assign(static_cast<size_t>(g.nx) * g.nz, 0.0f);
  const float by = static_cast<float>(scene_.backdrop_y_m);
  for (int iz = 0; iz < g.nz; ++iz) {
    const float z = g.z0 + iz * g.cell;
    for (int ix = 0; ix < g.nx; ++ix) {
      const float x = g.x0 + ix * g.cell;
      const size_t cell = static_cast<size_t>(iz) * g.nx + ix;
      float e = static_cast<float>(options_.ambient);
      for (size_t i = 0; i < lights_.size(); ++i) {
        const LightF& l = lights_[i];
        const float lx = l.x - x, ly = l.y - by, lz = l.z - z;
        if (ly >= 0.0f) continue;  // the light is behind the backdrop
        const float d2 = lx * lx + ly * ly + lz * lz;
        const float cos = -ly / std::sqrt(d2);
        e += l.power / d2 * cos * (1.0f - shadows_.BackdropCoverage(static_cast<int>(i), cell));
      }
      backdrop_[cell] = e * Unevenness(x, z);
    }
  }
}

float Shader::Unevenness(float x, float z) const {
  const float u = (x - grid_x0_) * (1.0f / kGridCell);
  const float v = (z - grid_z0_) * (1.0f / kGridCell);
  if (!(u >= 0.0f && v >= 0.0f && u < grid_nx_ - 1 && v < grid_nz_ - 1)) return 1.0f;
  const int iu = static_cast<int>(u), iv = static_cast<int>(v);
  const float fu = u - iu, fv = v - iv;
  const float* g = &grid_[static_cast<size_t>(iv) * grid_nx_ + iu];
  return (g[0] * (1 - fu) + g[1] * fu) * (1 - fv) + (g[grid_nx_] * (1 - fu) + g[grid_nx_ + 1] * fu) * fv;
}

void Shader::Light(const float p[3], const float n[3], const float v[3], const float albedo[3],
                   float specular, int shininess, float rgb[3]) const {
  float diffuse = static_cast<float>(options_.ambient);
  float spec = 0.0f;
  for (size_t i = 0; i < lights_.size(); ++i) {
    const LightF& light = lights_[i];
    const float lx = light.x - p[0];
    const float ly = light.y - p[1];
    const float lz = light.z - p[2];
    const float d2 = lx * lx + ly * ly + lz * lz;
    if (d2 < 1e-8f) continue;
    const float inv_d = 1.0f / std::sqrt(d2);
    const float ndotl = (n[0] * lx + n[1] * ly + n[2] * lz) * inv_d;
    if (ndotl <= 0.0f) continue;
    float e = light.power / d2;
    const float blocked = shadows_.Blocked(static_cast<int>(i), p[0], p[1], p[2]);
    if (blocked >= 1.0f) continue;
    e *= 1.0f - blocked;
    diffuse += e * ndotl;
    if (specular > 0.0f) {
      float hx = lx * inv_d + v[0], hy = ly * inv_d + v[1], hz = lz * inv_d + v[2];
      const float hn = 1.0f / std::sqrt(hx * hx + hy * hy + hz * hz + 1e-12f);
      const float ndoth = (n[0] * hx + n[1] * hy + n[2] * hz) * hn;
      if (ndoth > 0.0f) spec += e * PowInt(ndoth, shininess);
    }
  }
  for (int c = 0; c < 3; ++c) rgb[c] = albedo[c] * diffuse + specular * spec;
}

void Shader::ShadeBackground(const RayF& r, float rgb[3]) const {
  const float by = static_cast<float>(scene_.backdrop_y_m);
  const float gz = static_cast<float>(scene_.ground_z_m);
  float t_back = r.y > 1e-6f ? (by - cy_) / r.y : -1.0f;
  float t_ground = r.z < -1e-6f ? (gz - cz_) / r.z : -1.0f;
  if (t_back <= 0.0f) t_back = 1e30f;
  if (t_ground <= 0.0f) t_ground = 1e30f;
  const float t = std::min(t_back, t_ground);
  if (t >= 1e30f) {
    rgb[0] = rgb[1] = rgb[2] = 0.0f;  // under the rig's hood nothing else is lit
    return;
  }
  const float p[3] = {cx_ + t * r.x, cy_ + t * r.y, cz_ + t * r.z};
  const float v[3] = {-r.x, -r.y, -r.z};
  if (t_back <= t_ground) {
    const float cov = fiducials_.empty() ? 0.0f : FiducialCoverage(p[0], p[2], t);
    float colour[3];
    for (int c = 0; c < 3; ++c) colour[c] = kBackdrop[c] + cov * (kFiducialWhite - kBackdrop[c]);
    const ShadowMaps::Grid& g = shadows_.grid();
    const float u = (p[0] - g.x0) / g.cell;
    const float w = (p[2] - g.z0) / g.cell;
    if (u >= 0.0f && w >= 0.0f && u < g.nx - 1 && w < g.nz - 1) {
      const int iu = static_cast<int>(u), iw = static_cast<int>(w);
      const float fu = u - iu, fw = w - iw;
      const float* c = &backdrop_[static_cast<size_t>(iw) * g.nx + iu];
      const float e = (c[0] * (1 - fu) + c[1] * fu) * (1 - fw) + (c[g.nx] * (1 - fu) + c[g.nx + 1] * fu) * fw;
      rgb[0] = colour[0] * e, rgb[1] = colour[1] * e, rgb[2] = colour[2] * e;
      return;
    }
    const float n[3] = {0.0f, -1.0f, 0.0f};
    const float k = Unevenness(p[0], p[2]);
    const float albedo[3] = {colour[0] * k, colour[1] * k, colour[2] * k};
    Light(p, n, v, albedo, 0.0f, 1, rgb);
  } else {
    const float n[3] = {0.0f, 0.0f, 1.0f};
    float k = 1.0f;
    if (options_.texture) {
      k = 0.6f + 0.5f * ValueNoise(p[0] * 9.0f, p[1] * 9.0f, 71u) +
          0.25f * ValueNoise(p[0] * 120.0f, p[1] * 120.0f, 72u) - 0.12f;
    }
    const float albedo[3] = {0.36f * k, 0.28f * k, 0.20f * k};
    Light(p, n, v, albedo, 0.0f, 1, rgb);
  }
}

void Shader::ShadePrimitive(const Primitive& prim, const Approach& ap, const RayF& r,
                            float rgb[3]) const {
  const Segment& seg = segments_[prim.seg];
  // Surface point and normal, camera-relative, from the offset across the axis at which the
  // pixel sees the surface. A pixel the structure only partly covers sees the part of it inside
  // the pixel footprint, so it is shaded at the middle of that part rather than at the ray
  // (which may miss): otherwise thin wires and cane edges would be shaded at grazing normals.
  // Shading uses the closest point on the infinite axis line: at the joints between capsule pieces
  // the clamped point would turn the overlapping end caps into dark rings.
  float s_line = ap.s;
  float t_line = ap.t;
  if (prim.shape != Shape::kSphere) {
    const float b = r.x * prim.ux + r.y * prim.uy + r.z * prim.uz;
    const float dr = r.x * prim.ax + r.y * prim.ay + r.z * prim.az;
    const float denom = 1.0f - b * b;
    if (denom > 1e-8f) {
      s_line = (dr * b - prim.eu) / denom;
      t_line = dr + s_line * b;
    }
  }
  const float qx = prim.ax + s_line * prim.ux, qy = prim.ay + s_line * prim.uy, qz = prim.az + s_line * prim.uz;
  // Towards the camera, perpendicular to the axis.
  float vx = -r.x, vy = -r.y, vz = -r.z;
  if (prim.shape != Shape::kSphere) {
    const float a = vx * prim.ux + vy * prim.uy + vz * prim.uz;
    vx -= a * prim.ux, vy -= a * prim.uy, vz -= a * prim.uz;
  }
  float vn = std::sqrt(vx * vx + vy * vy + vz * vz);
  if (vn < 1e-6f) vx = -r.x, vy = -r.y, vz = -r.z, vn = 1.0f;
  vx /= vn, vy /= vn, vz /= vn;
  // Sideways: from the axis towards the ray's closest point.
  float ex = t_line * r.x - qx, ey = t_line * r.y - qy, ez = t_line * r.z - qz;
  const float along_v = ex * vx + ey * vy + ez * vz;
  ex -= along_v * vx, ey -= along_v * vy, ez -= along_v * vz;
  const float en = std::sqrt(ex * ex + ey * ey + ez * ez);
  float offset = 0.0f;  // signed offset across the axis, as a fraction of the radius
  if (en > 1e-9f && ap.radius > 0.0f) {
    ex /= en, ey /= en, ez /= en;
    const float half = 0.5f * ap.t * prim.pix_angle;
    const float lo = std::max(en - half, -ap.radius);
    const float hi = std::min(en + half, ap.radius);
    offset = std::clamp(0.5f * (lo + hi) / ap.radius, -0.999f, 0.999f);
  } else {
    ex = ey = ez = 0.0f;
  }
  const float toward = std::sqrt(1.0f - offset * offset);
  const float nx = offset * ex + toward * vx, ny = offset * ey + toward * vy, nz = offset * ez + toward * vz;
  const float px = qx + ap.radius * nx, py = qy + ap.radius * ny, pz = qz + ap.radius * nz;
  const float p[3] = {cx_ + px, cy_ + py, cz_ + pz};
  const float n[3] = {nx, ny, nz};
  const float v[3] = {-r.x, -r.y, -r.z};

  // Texture coordinates: arc length along the object and the angle around its axis.
  const float along = seg.s0 + s_line;
  float around = 0.0f;
  if (prim.shape != Shape::kSphere) {
    // A basis perpendicular to the axis; horizontal reference unless the axis is near vertical.
    float e1x = prim.uy, e1y = -prim.ux, e1z = 0.0f;
    if (std::abs(prim.uz) > 0.9f) e1x = 0.0f, e1y = prim.uz, e1z = -prim.uy;
    const float e1n = 1.0f / std::sqrt(e1x * e1x + e1y * e1y + e1z * e1z);
    e1x *= e1n, e1y *= e1n, e1z *= e1n;
    const float e2x = prim.uy * e1z - prim.uz * e1y, e2y = prim.uz * e1x - prim.ux * e1z,
                e2z = prim.ux * e1y - prim.uy * e1x;
    around = FastAtan2(nx * e2x + ny * e2y + nz * e2z, nx * e1x + ny * e1y + nz * e1z) / kTwoPi + 0.5f;
  }
  const auto obj = static_cast<uint32_t>(seg.object);
  const float tint = Unit(HashU32(obj, 17u, 5u)) * 2.0f - 1.0f;  // per-object variation
  const float tint2 = Unit(HashU32(obj, 23u, 9u)) * 2.0f - 1.0f;
  const bool tex = options_.texture;
  float albedo[3];
  float specular = 0.0f;
  int shininess = 8;
  switch (seg.material) {
    case Material::kCane:
    case Material::kOtherCane: {
      // Dormant canes: brown-grey, some redder, some greyer; fine longitudinal bark fissures and
      // slightly darker nodes every ~7-9 cm.
      const float k = 1.0f + 0.10f * tint;
      albedo[0] = 0.38f * k + 0.03f * tint2, albedo[1] = 0.305f * k, albedo[2] = 0.245f * k - 0.02f * tint2;
      if (tex) {
        const float fiss = ValueNoise(along * 70.0f, around * 14.0f, obj);
        const float grain = ValueNoise(along * 600.0f, around * 40.0f, obj + 101u);
        const float node_period = 0.07f + 0.02f * Unit(HashU32(obj, 3u, 3u));
        const float ph = Frac(along / node_period) - 0.5f;
        // A smooth bump ~1 cm wide at each node.
        const float q = 1.0f - ph * ph * (node_period * node_period) / (0.004f * 0.004f);
        const float node = q > 0.0f ? q * q : 0.0f;
        const float m = (0.72f + 0.40f * fiss + 0.18f * (grain - 0.5f)) * (1.0f - 0.18f * node);
        for (float& a : albedo) a *= m;
      }
      specular = 0.05f;
      break;
    }
    case Material::kTrunk: {
      albedo[0] = 0.31f, albedo[1] = 0.26f, albedo[2] = 0.21f;
      if (tex) {
        // Shaggy bark: strong strips along the trunk, broken up across it.
        const float strip = ValueNoise(along * 12.0f, around * 22.0f, obj);
        const float grain = ValueNoise(along * 150.0f, around * 60.0f, obj + 7u);
        const float m = 0.55f + 0.65f * strip * strip + 0.25f * (grain - 0.5f);
        for (float& a : albedo) a *= m;
      }
      specular = 0.02f;
      break;
    }
    case Material::kHead:
    case Material::kOtherHead: {
      albedo[0] = 0.30f, albedo[1] = 0.245f, albedo[2] = 0.19f;
      if (tex) {
        // Gnarled knot: noise in the surface point itself, with a dark crevice component.
        const float a = ValueNoise(p[0] * 90.0f + p[2] * 40.0f, p[1] * 90.0f - p[2] * 70.0f, obj);
        const float b = ValueNoise(p[0] * 300.0f - p[1] * 100.0f, p[2] * 300.0f, obj + 3u);
        const float m = 0.45f + 0.75f * a * a + 0.25f * (b - 0.5f);
        for (float& c : albedo) c *= m;
      }
      specular = 0.02f;
      break;
    }
    case Material::kWire:
      albedo[0] = 0.50f, albedo[1] = 0.52f, albedo[2] = 0.55f;
      specular = 0.9f;
      shininess = 24;
      break;
    case Material::kPost: {
      // Weathered treated pine: grey-brown with grain along the post.
      albedo[0] = 0.46f, albedo[1] = 0.42f, albedo[2] = 0.35f;
      if (tex) {
        const float g = ValueNoise(along * 6.0f, around * 40.0f, obj);
        const float m = 0.8f + 0.35f * g;
        for (float& a : albedo) a *= m;
      }
      specular = 0.03f;
      break;
    }
  }
  Light(p, n, v, albedo, specular, shininess, rgb);
}

}  // namespace vb::sim::render
