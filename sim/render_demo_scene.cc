// SPDX-License-Identifier: Apache-2.0
#include "sim/render_demo_scene.h"

#include <cmath>

namespace vb::sim {
namespace {

class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  double Uniform(double lo, double hi) {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * (static_cast<double>(z >> 11) * 0x1.0p-53);
  }

 private:
  uint64_t state_;
};

// A cane as a gently curving path: starts at `base` heading `dir`, bending with random curvature.
Polyline3 GrowCane(Rng& rng, Eigen::Vector3d base, Eigen::Vector3d dir, double length, double r0,
                   double r1, int segments, double plane_y) {
  Polyline3 line;
  const double step = length / segments;
  Eigen::Vector3d bend(rng.Uniform(-1, 1), rng.Uniform(-0.3, 0.3), rng.Uniform(-1, 1));
  for (int i = 0; i <= segments; ++i) {
    const double f = static_cast<double>(i) / segments;
    line.points.push_back(base);
    line.radii.push_back(r0 + (r1 - r0) * f);
    dir = (dir + step * 1.8 * bend + Eigen::Vector3d(0, 0, -step * 0.6)).normalized();
    // Canes are tied down roughly in the vine plane; keep them within a few cm of it.
    dir.y() -= 2.0 * step * (base.y() - plane_y) / 0.05;
    dir.normalize();
    base += step * dir;
    if (i % 10 == 0) bend = Eigen::Vector3d(rng.Uniform(-1, 1), rng.Uniform(-0.3, 0.3), rng.Uniform(-1, 1));
  }
  return line;
}

}  // namespace

Scene MakeDemoScene(const DemoSceneOptions& o) {
  Rng rng(o.seed);
  Scene scene;
  scene.seed = o.seed;
  const double y = o.vine_plane_y_m;

  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  for (int i = 0; i <= 20; ++i) {
    const double z = 0.95 * i / 20.0;
    trunk.polyline.points.emplace_back(0.02 * std::sin(7.0 * z), y + 0.01 * std::cos(5.0 * z), z);
    trunk.polyline.radii.push_back(0.028 - 0.006 * z);
  }
  scene.vine.canes.push_back(trunk);
  const Eigen::Vector3d head(0.02 * std::sin(6.65), y, 1.0);
  for (int i = 0; i < o.head_spheres; ++i) {
    scene.vine.head.spheres.push_back(
        {head + Eigen::Vector3d(rng.Uniform(-0.05, 0.05), rng.Uniform(-0.02, 0.02), rng.Uniform(-0.04, 0.03)),
         rng.Uniform(0.018, 0.034)});
  }
  for (int i = 0; i < o.cane_count; ++i) {
    Cane cane;
    cane.id = CaneId(2 + i);
    cane.parent_id = CaneId(1);
    const double angle = rng.Uniform(0.15, 2.99);  // upward fan, left to right
    const Eigen::Vector3d dir(std::cos(angle), rng.Uniform(-0.1, 0.1), std::sin(angle) + 0.2);
    const Eigen::Vector3d base = head + Eigen::Vector3d(rng.Uniform(-0.04, 0.04), 0.0, rng.Uniform(-0.02, 0.03));
    cane.polyline = GrowCane(rng, base, dir.normalized(), rng.Uniform(0.35, 1.2),
                             rng.Uniform(0.004, 0.0075), 0.0015, o.segments_per_cane, y);
    scene.vine.canes.push_back(cane);
  }
  const double wire_z[] = {0.95, 1.2, 1.45, 1.75};
  for (int i = 0; i < 4; ++i) {
    Wire w;
    w.id = WireId(i + 1);
    w.points = {{-3.0, y + (i == 0 ? 0.0 : (i % 2 ? -0.03 : 0.03)), wire_z[i]},
                {3.0, y + (i == 0 ? 0.0 : (i % 2 ? -0.03 : 0.03)), wire_z[i] - 0.01}};
    w.radius = 0.0015;
    scene.vine.wires.push_back(w);
  }
  Post post;
  post.id = PostId(1);
  post.base = {0.75, y + 0.02, 0.0};
  post.top = {0.75, y + 0.02, 1.9};
  post.radius = 0.04;
  scene.vine.posts.push_back(post);

  for (int side = 0; side < 2; ++side) {
    VineModel n;
    const double sign = side == 0 ? -1.0 : 1.0;
    const Eigen::Vector3d nhead(sign * 1.8, y, 1.0);
    n.head.spheres.push_back({nhead, 0.04});
    const int count = side == 0 ? o.neighbour_canes / 2 : o.neighbour_canes - o.neighbour_canes / 2;
    for (int i = 0; i < count; ++i) {
      Cane cane;
      cane.id = CaneId(1 + i);
      const double angle = side == 0 ? rng.Uniform(0.1, 1.3) : rng.Uniform(1.85, 3.05);
      const Eigen::Vector3d dir(std::cos(angle), 0.0, std::sin(angle) + 0.2);
      cane.polyline = GrowCane(rng, nhead, dir.normalized(), rng.Uniform(0.6, 1.3), 0.006, 0.0015,
                               o.segments_per_cane, y);
      n.canes.push_back(cane);
    }
    scene.neighbours.push_back(n);
  }
  // Three flashes around the trinocular rig.
  scene.lights = {{{-0.2, 0.0, 0.95}, 0.4}, {{0.2, 0.0, 0.95}, 0.4}, {{0.0, 0.0, 1.3}, 0.4}};
  return scene;
}

}  // namespace vb::sim
