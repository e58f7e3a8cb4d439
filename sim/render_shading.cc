// SPDX-License-Identifier: Apache-2.0
#include "sim/render_shading.h"

#include <algorithm>
#include <cmath>

namespace vb::sim::render {
namespace {

constexpr float kCell = 0.006f;  // shadow map cell on the backdrop plane, metres (2-3 px; penumbrae are ~1 cm)
constexpr float kShadowBias = 0.015f;  // casters must be this much nearer the light (y) to count

inline float Clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }
inline float Lerp(float a, float b, float t) { return a + (b - a) * t; }

// Region of the plane y = plane_y seen through the border of the image, with a margin.
void VisiblePlaneRegion(const RayTable& rays, const Eigen::Vector3d& c, double plane_y,
                        float* x0, float* x1, float* z0, float* z1) {
  float lo_x = 1e9f, hi_x = -1e9f, lo_z = 1e9f, hi_z = -1e9f;
  auto visit = [&](int x, int y) {
    const RayF& r = rays.at(x, y);
    float px, pz;
    if (r.y > 1e-3f) {
      const float t = static_cast<float>(plane_y - c.y()) / r.y;
      px = static_cast<float>(c.x()) + t * r.x;
      pz = static_cast<float>(c.z()) + t * r.z;
    } else {
      return;  // parallel or away: the far clip below bounds it
    }
    lo_x = std::min(lo_x, px);
    hi_x = std::max(hi_x, px);
    lo_z = std::min(lo_z, pz);
    hi_z = std::max(hi_z, pz);
  };
  for (int x = 0; x < rays.width(); x += 8) {
    visit(x, 0);
    visit(x, rays.height() - 1);
  }
  for (int y = 0; y < rays.height(); y += 8) {
    visit(0, y);
    visit(rays.width() - 1, y);
  }
  constexpr float kMargin = 0.3f;
  constexpr float kFar = 6.0f;
  *x0 = std::max(lo_x - kMargin, static_cast<float>(c.x()) - kFar);
  *x1 = std::min(hi_x + kMargin, static_cast<float>(c.x()) + kFar);
  *z0 = std::max(lo_z - kMargin, static_cast<float>(c.z()) - kFar);
  *z1 = std::min(hi_z + kMargin, static_cast<float>(c.z()) + kFar);
}

}  // namespace

uint32_t HashU32(uint32_t a, uint32_t b, uint32_t c) {
  // Murmur3-style finaliser over a simple combination: cheap, well mixed, platform independent.
  uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u ^ (c + 0x165667B1u) * 0xC2B2AE3Du;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

float ValueNoise(float x, float y, uint32_t seed) {
  const float fx = std::floor(x);
  const float fy = std::floor(y);
  const auto ix = static_cast<uint32_t>(static_cast<int32_t>(fx));
  const auto iy = static_cast<uint32_t>(static_cast<int32_t>(fy));
  float tx = x - fx;
  float ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  constexpr float kScale = 1.0f / 4294967295.0f;
  const float v00 = HashU32(ix, iy, seed) * kScale;
  const float v10 = HashU32(ix + 1, iy, seed) * kScale;
  const float v01 = HashU32(ix, iy + 1, seed) * kScale;
  const float v11 = HashU32(ix + 1, iy + 1, seed) * kScale;
  return Lerp(Lerp(v00, v10, tx), Lerp(v01, v11, tx), ty);
}

// ---------------------------------------------------------------------------------------------
// Shadow maps

ShadowMaps::ShadowMaps(const Scene& scene, const std::vector<Segment>& segments,
                       const RenderOptions& options, const Eigen::Vector3d& camera_centre,
                       const RayTable& rays)
    : backdrop_y_(static_cast<float>(scene.backdrop_y_m)),
      light_radius_(static_cast<float>(options.light_radius_m)),
      depth_scale_(0.0f) {
  maps_.resize(scene.lights.size());
  float x0, x1, z0, z1;
  VisiblePlaneRegion(rays, camera_centre, scene.backdrop_y_m, &x0, &x1, &z0, &z1);
  if (!(x1 > x0 && z1 > z0)) return;
  grid_.x0 = x0;
  grid_.z0 = z0;
  grid_.cell = kCell;
  grid_.nx = static_cast<int>((x1 - x0) / kCell) + 1;
  grid_.nz = static_cast<int>((z1 - z0) / kCell) + 1;
  if (!options.shadows) return;
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    Map& m = maps_[i];
    const Eigen::Vector3d& l = scene.lights[i].position_in_platform;
    m.lx = static_cast<float>(l.x());
    m.ly = static_cast<float>(l.y());
    m.lz = static_cast<float>(l.z());
    if (!(backdrop_y_ - m.ly > 0.05f)) continue;  // a light at or behind the backdrop casts none
    m.x0 = x0;
    m.z0 = z0;
    m.nx = grid_.nx;
    m.nz = grid_.nz;
    m.cells.assign(static_cast<size_t>(m.nx) * m.nz, 0xFF00);
    depth_scale_ = 254.0f / (backdrop_y_ - m.ly);
    for (const Segment& s : segments) Rasterise(s, &m);
  }
}

void ShadowMaps::Rasterise(const Segment& s, Map* m) const {
  const float ay = static_cast<float>(s.a.y()), by = static_cast<float>(s.b.y());
  // Only casters strictly between the light and the backdrop throw a shadow onto it.
  if (ay < m->ly + 0.02f || by < m->ly + 0.02f || ay >= backdrop_y_ || by >= backdrop_y_) return;
  const float ka = (backdrop_y_ - m->ly) / (ay - m->ly);
  const float kb = (backdrop_y_ - m->ly) / (by - m->ly);
  const float pax = m->lx + (static_cast<float>(s.a.x()) - m->lx) * ka;
  const float paz = m->lz + (static_cast<float>(s.a.z()) - m->lz) * ka;
  const float pbx = m->lx + (static_cast<float>(s.b.x()) - m->lx) * kb;
  const float pbz = m->lz + (static_cast<float>(s.b.z()) - m->lz) * kb;
  const float ra = static_cast<float>(s.ra) * ka;
  const float rb = static_cast<float>(s.rb) * kb;
  // Penumbra half-width by similar triangles: light disc radius scaled caster->plane / light->caster.
  const float ymid = 0.5f * (ay + by);
  const float pen = std::max(light_radius_ * (backdrop_y_ - ymid) / (ymid - m->ly), 0.5f * kCell);
  const float pad = std::max(ra, rb) + pen + kCell;
  const int cx0 = std::max(0, static_cast<int>((std::min(pax, pbx) - pad - m->x0) / kCell));
  const int cx1 = std::min(m->nx - 1, static_cast<int>((std::max(pax, pbx) + pad - m->x0) / kCell) + 1);
  const int cz0 = std::max(0, static_cast<int>((std::min(paz, pbz) - pad - m->z0) / kCell));
  const int cz1 = std::min(m->nz - 1, static_cast<int>((std::max(paz, pbz) + pad - m->z0) / kCell) + 1);
  if (cx0 > cx1 || cz0 > cz1) return;
  const float dx = pbx - pax, dz = pbz - paz;
  const float len2 = dx * dx + dz * dz;
  const float inv_len2 = len2 > 1e-12f ? 1.0f / len2 : 0.0f;
  const float inv_width = 1.0f / (2.0f * pen);
  for (int iz = cz0; iz <= cz1; ++iz) {
    const float qz = m->z0 + iz * kCell;
    uint16_t* cells = &m->cells[static_cast<size_t>(iz) * m->nx];
    for (int ix = cx0; ix <= cx1; ++ix) {
      const float qx = m->x0 + ix * kCell;
      const float t = Clamp01(((qx - pax) * dx + (qz - paz) * dz) * inv_len2);
      const float ex = qx - (pax + t * dx), ez = qz - (paz + t * dz);
      const float d = std::sqrt(ex * ex + ez * ez);
      const float c = Clamp01((Lerp(ra, rb, t) + pen - d) * inv_width);
      if (c <= 0.0f) continue;
      const auto c8 = static_cast<unsigned>(c * 255.0f + 0.5f);
      const auto y8 = static_cast<unsigned>(std::clamp((Lerp(ay, by, t) - m->ly) * depth_scale_, 0.0f, 254.0f));
      const unsigned old = cells[ix];
      cells[ix] = static_cast<uint16_t>(std::max(old & 0xFFu, c8) | (std::min(old >> 8, y8) << 8));
    }
  }
}

float ShadowMaps::Blocked(int light, float x, float y, float z) const {
  const Map& m = maps_[light];
  if (m.cells.empty() || y <= m.ly + 0.02f) return 0.0f;
  const float k = (backdrop_y_ - m.ly) / (y - m.ly);
  const float u = (m.lx + (x - m.lx) * k - m.x0) * (1.0f / kCell);
  const float v = (m.lz + (z - m.lz) * k - m.z0) * (1.0f / kCell);
  if (!(u >= 0.0f && v >= 0.0f && u < m.nx - 1 && v < m.nz - 1)) return 0.0f;
  const int iu = static_cast<int>(u), iv = static_cast<int>(v);
  const float fu = u - iu, fv = v - iv;
  const size_t i00 = static_cast<size_t>(iv) * m.nx + iu;
  const size_t idx[4] = {i00, i00 + 1, i00 + m.nx, i00 + m.nx + 1};
  const float w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
  // Casters count only if nearer the light than the point itself (minus a bias against
  // self-shadowing, which the Lambertian term already handles).
  const float limit = (y - kShadowBias - m.ly) * (254.0f / (backdrop_y_ - m.ly));
  float sum = 0.0f;
  for (int j = 0; j < 4; ++j) {
    const unsigned cell = m.cells[idx[j]];
    if ((cell & 0xFFu) != 0 && static_cast<float>(cell >> 8) < limit) sum += w[j] * static_cast<float>(cell & 0xFFu);
  }
  return sum * (1.0f / 255.0f);
}

}  // namespace vb::sim::render
