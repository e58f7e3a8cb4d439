// SPDX-License-Identifier: Apache-2.0
#include "sim/vine_plant.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "sim/vine_cane_growth.h"
#include "sim/vine_random.h"

namespace vb::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr uint64_t kPlantStream = 0x7A17;
constexpr double kTrunkStepM = 0.05;
constexpr double kMaxJitterM = 0.1;  // planting error of the trunk along the row
constexpr double kPostClearanceM = 0.005;  // least gap between the trunk or head and a post
// The head top sits at most this far below the fruiting wire (the head is grown up to the wire).
constexpr double kHeadBelowWireMaxM = 0.08;

Eigen::Vector3d Normalized(const Eigen::Vector3d& v) {
  const double n = v.norm();
  return n > 1e-12 ? Eigen::Vector3d(v / n) : Eigen::Vector3d::UnitZ();
}

class PlantBuilder {
 public:
  PlantBuilder(uint64_t seed, int vine_index, const VineGeneratorOptions& options,
               const TrellisRow& row)
      : options_(options), row_(row), rng_(MixSeed(seed, vine_index, kPlantStream)) {
    const double nominal = vine_index * options.vine_spacing_m;
    plant_.position_m = nominal + KeepClearOfPost(nominal, std::clamp(rng_.Normal(0.0, 0.04),
                                                                    -kMaxJitterM, kMaxJitterM));
    post_x_ = NearestPostX(plant_.position_m);
  }

  VinePlant Build() {
    GrowTrunkAndHead();
    const int total = rng_.UniformInt(options_.canes_min, options_.canes_max);
    const double w = rng_.Uniform();
    int water_shoots = std::min(w < 0.5 ? 0 : (w < 0.85 ? 1 : 2), total - 1);
    int forks = 0;
    for (int i = 0; i < total - water_shoots; ++i) forks += rng_.Bernoulli(options_.fork_probability);
    forks = std::min(forks, (total - water_shoots - 1) / 2);
    const int head_canes = total - water_shoots - forks;
    for (int i = 0; i < head_canes; ++i) AddHeadCane();
    for (int i = 0; i < water_shoots; ++i) AddWaterShoot();
    for (int i = 0; i < forks; ++i) AddFork();
    const int spurs = rng_.UniformInt(options_.old_spurs_min, options_.old_spurs_max);
    for (int i = 0; i < spurs; ++i) AddSpur();
    return std::move(plant_);
  }

 private:
  const Cane& trunk() const { return plant_.model.canes.front(); }

  // Row position of the post nearest row position x.
  double NearestPostX(double x) const {
    const double spacing = options_.post_spacing_m;
    return std::round((x - row_.post_offset_m) / spacing) * spacing + row_.post_offset_m;
  }

  // Keeps a body of radius r centred at x on the vine's side of the nearest post, clear of it by
  // kPostClearanceM (in x alone, which is stricter than the distance to the post's axis): the
  // trunk's lean and bends and the head's spread must not put wood inside the post (tuning stop
  // 1353 had its head inside one before session 24).
  double ClearOfPost(double x, double r) const {
    const double side = plant_.position_m >= post_x_ ? 1.0 : -1.0;
    const double least = options_.post_radius_m + r + kPostClearanceM;
    return side * (x - post_x_) >= least ? x : post_x_ + side * least;
  }

  // A vine is never planted through a post: if the nearest post would stand within kMaxJitterM of
  // the trunk, the jitter moves the trunk to kMaxJitterM beside it (still within the jitter range).
  double KeepClearOfPost(double nominal, double jitter) const {
    const double post = NearestPostX(nominal) - nominal;  // relative to nominal
    if (std::abs(jitter - post) >= kMaxJitterM) return jitter;
    double best = jitter;
    double best_change = std::numeric_limits<double>::infinity();
    for (double candidate : {post + kMaxJitterM, post - kMaxJitterM}) {
      if (std::abs(candidate) <= kMaxJitterM + 1e-12 &&
          std::abs(candidate - jitter) < best_change) {
        best = candidate;
        best_change = std::abs(candidate - jitter);
      }
    }
    return best;
  }

  void GrowTrunkAndHead() {
    const double x0 = plant_.position_m;
    const double wire_z = WireHeightAt(row_, row_.wires.front(), x0, options_);
    const double hr = options_.head_radius_m;
    const double core_r = hr * rng_.Uniform(0.55, 0.8);
    double head_top = wire_z - rng_.Uniform(0.0, kHeadBelowWireMaxM);
    const double top_z =
        std::clamp(head_top - core_r, options_.trunk_height_min_m, options_.trunk_height_max_m);
    head_top = top_z + core_r;

    const Eigen::Vector3d base(x0, options_.vine_plane_y_m + rng_.Normal(0.0, 0.015), 0.0);
    Eigen::Vector3d top(x0 + std::clamp(rng_.Normal(0.0, 0.04), -0.1, 0.1),
                        base.y() + rng_.Normal(0.0, 0.015), top_z);
    top.x() = ClearOfPost(top.x(), core_r);
    // Old trunks are bent and knobbly: two smooth bends that vanish at both ends, and a radius
    // that tapers a little with a slow swelling.
    const double bend1_x = rng_.Normal(0.0, 0.03), bend2_x = rng_.Normal(0.0, 0.012);
    const double bend1_y = rng_.Normal(0.0, 0.012), bend2_y = rng_.Normal(0.0, 0.006);
    const double r_base = 0.5 * rng_.Uniform(options_.trunk_diameter_min_m,
                                             options_.trunk_diameter_max_m);
    const double r_top = r_base * rng_.Uniform(0.8, 0.92);
    const double knob = rng_.Uniform(0.0, 0.04), knob_phase = rng_.Uniform(0.0, 2.0 * kPi);
    const int n = std::max(2, static_cast<int>(std::ceil(top_z / kTrunkStepM)));
    Cane cane;
    cane.id = CaneId(1);
    cane.kind = CaneKind::kTrunk;
    for (int i = 0; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      Eigen::Vector3d p = base + t * (top - base);
      p.x() += bend1_x * std::sin(kPi * t) + bend2_x * std::sin(2.0 * kPi * t);
      p.y() += bend1_y * std::sin(kPi * t) + bend2_y * std::sin(2.0 * kPi * t);
      const double swell = 1.0 + knob * std::sin(5.0 * t + knob_phase) * std::sin(kPi * t);
      const double radius = (r_base + (r_top - r_base) * t) * swell;
      p.x() = ClearOfPost(p.x(), radius);
      cane.polyline.points.push_back(p);
      cane.polyline.radii.push_back(radius);
    }
    plant_.model.canes.push_back(std::move(cane));

    // The head: a connected clump of spheres around the trunk top, wider along the row (the old
    // arms), none reaching above head_top.
    std::vector<Sphere>& spheres = plant_.model.head.spheres;
    spheres.push_back({top, core_r});
    const int count = rng_.UniformInt(5, 15);
    for (int i = 1; i < count; ++i) {
      const Sphere& anchor = spheres[rng_.UniformInt(0, static_cast<int>(spheres.size()) - 1)];
      const double r = hr * rng_.Uniform(0.3, 0.7);
      const Eigen::Vector3d dir =
          Normalized({rng_.Normal(0.0, 1.0), 0.4 * rng_.Normal(), 0.6 * rng_.Normal() - 0.2});
      Eigen::Vector3d c = anchor.center + rng_.Uniform(0.4, 0.9) * (anchor.radius + r) * dir;
      c.x() = ClearOfPost(std::clamp(c.x(), top.x() - 2.2 * hr, top.x() + 2.2 * hr), r);
      c.z() = std::min(c.z(), head_top - r);
      spheres.push_back({c, r});
    }
  }

  // A point on the surface of a random head sphere, facing roughly `side` along the row and up.
  Eigen::Vector3d HeadSurfacePoint(double side) {
    const auto& spheres = plant_.model.head.spheres;
    const Sphere& s = spheres[rng_.UniformInt(0, static_cast<int>(spheres.size()) - 1)];
    const Eigen::Vector3d u = Normalized(
        {side * rng_.Uniform(0.1, 1.0), rng_.Normal(0.0, 0.3), rng_.Uniform(-0.1, 1.0)});
    return s.center + s.radius * u;
  }

  double SampleLength(double max_m) {
    const double lo = options_.cane_length_min_m;
    const double hi = std::max(lo, std::min(max_m, options_.cane_length_max_m));
    // Mostly mid-length canes (triangular), sometimes anything in range.
    const double u = rng_.Bernoulli(0.25) ? rng_.Uniform() : 0.5 * (rng_.Uniform() + rng_.Uniform());
    return lo + (hi - lo) * u;
  }

  // Long canes are thick ones (vigour), with scatter.
  double BaseRadiusForLength(double length) {
    const double lo = options_.cane_length_min_m, hi = options_.cane_length_max_m;
    const double rel = hi > lo ? (length - lo) / (hi - lo) : 0.5;
    // In [0, 1] by construction (no clamping, so the range ends are not over-represented).
    const double frac = 0.3 * rng_.Uniform() + 0.7 * rel * rng_.Uniform(0.6, 1.0);
    return 0.5 * (options_.cane_diameter_min_m +
                  frac * (options_.cane_diameter_max_m - options_.cane_diameter_min_m));
  }

  CaneGrowth CommonGrowth(double length, double side) {
    CaneGrowth g;
    g.length_m = length;
    g.tip_ratio = rng_.Uniform(0.4, 0.6);
    g.taper_exponent = rng_.Uniform(0.8, 1.4);
    // Last summer's shoots were trained upward between the foliage wires: most canes stay
    // upright-ish, a minority arch over under their weight and hang.
    const bool arching = rng_.Bernoulli(0.35);
    g.arch_rad_per_m = rng_.Bernoulli(0.8) ? side * rng_.Uniform(0.0, arching ? 1.8 : 0.8)
                                           : -side * rng_.Uniform(0.0, 0.8);
    g.droop_rad_per_m = (arching ? rng_.Uniform(0.8, 2.0) : rng_.Uniform(0.05, 0.6)) *
                        (0.5 + length / options_.cane_length_max_m);
    g.wander_rad_per_m = rng_.Uniform(0.8, 2.2);
    g.drape_probability = rng_.Uniform(0.3, 0.8);
    g.elevation_rad = rng_.Normal(0.0, 0.2);
    return g;
  }

  void AddCane(CaneId parent, CaneKind kind, const CaneGrowth& g) {
    Cane cane;
    cane.id = CaneId(static_cast<int64_t>(plant_.model.canes.size()) + 1);
    cane.parent_id = parent;
    cane.kind = kind;
    cane.polyline = GrowCane(g, row_, options_, rng_);
    plant_.model.canes.push_back(std::move(cane));
  }

  void AddHeadCane() {
    const double side = rng_.Sign();
    const double length = SampleLength(options_.cane_length_max_m);
    CaneGrowth g = CommonGrowth(length, side);
    g.base = HeadSurfacePoint(side);
    g.heading_rad = side * rng_.Uniform(0.05, 1.2);
    g.base_radius_m = BaseRadiusForLength(length);
    AddCane(CaneId(1), CaneKind::kCane, g);
  }

  // Water shoots grow from dormant buds on the trunk itself.
  void AddWaterShoot() {
    const double side = rng_.Sign();
    const double length = SampleLength(1.0);
    CaneGrowth g = CommonGrowth(length, side);
    const double s = rng_.Uniform(0.25, 0.8) * trunk().polyline.Length();
    g.base = trunk().polyline.PointAt(s);
    g.heading_rad = side * rng_.Uniform(0.5, 1.3);
    g.base_radius_m = std::min(
        0.5 * (options_.cane_diameter_min_m +
               rng_.Uniform(0.05, 0.5) * (options_.cane_diameter_max_m - options_.cane_diameter_min_m)),
        0.8 * trunk().polyline.RadiusAt(s));
    AddCane(CaneId(1), CaneKind::kCane, g);
  }

  // A secondary cane from a lateral bud of a vigorous cane (Botterill et al. call these forks;
  // they make the structure a tree rather than a star).
  void AddFork() {
    std::vector<size_t> eligible;
    for (size_t i = 1; i < plant_.model.canes.size(); ++i) {
      const Cane& c = plant_.model.canes[i];
      if (c.kind == CaneKind::kCane && c.polyline.radii.front() >= 0.0035 &&
          c.polyline.Length() >= 0.4) {
        eligible.push_back(i);
      }
    }
    if (eligible.empty()) {
      AddHeadCane();
      return;
    }
    const size_t pi = eligible[rng_.UniformInt(0, static_cast<int>(eligible.size()) - 1)];
    const Polyline3& parent = plant_.model.canes[pi].polyline;
    const CaneId parent_id = plant_.model.canes[pi].id;
    const double s = rng_.Uniform(0.12, 0.5) * parent.Length();
    const Eigen::Vector3d t = parent.TangentAt(s);
    const double side = rng_.Sign();
    const double length = SampleLength(std::max(0.8 * parent.Length(), options_.cane_length_min_m));
    CaneGrowth g = CommonGrowth(length, side);
    g.base = parent.PointAt(s);
    g.heading_rad = std::atan2(t.x(), t.z()) + side * rng_.Uniform(0.35, 0.9);
    g.elevation_rad = std::asin(std::clamp(t.y(), -1.0, 1.0)) + rng_.Normal(0.0, 0.15);
    const double r_parent = parent.RadiusAt(s);
    g.base_radius_m = std::clamp(rng_.Uniform(0.5, 0.85) * r_parent,
                                 std::min(0.5 * options_.cane_diameter_min_m, r_parent), r_parent);
    AddCane(parent_id, CaneKind::kCane, g);
  }

  // Old spurs: short, thick, nearly straight stubs left on the head by earlier pruning.
  void AddSpur() {
    const double side = rng_.Sign();
    CaneGrowth g;
    g.base = HeadSurfacePoint(side);
    g.heading_rad = side * rng_.Uniform(0.1, 1.2);
    g.elevation_rad = rng_.Normal(0.0, 0.3);
    g.length_m = rng_.Uniform(0.03, 0.10);
    g.base_radius_m = rng_.Uniform(0.005, 0.009);
    g.tip_ratio = rng_.Uniform(0.8, 0.95);
    g.droop_rad_per_m = 0.0;
    g.wander_rad_per_m = 0.5;
    g.drape_probability = 0.0;
    g.step_min_m = 0.008;
    g.step_max_m = 0.012;
    AddCane(CaneId(1), CaneKind::kSpur, g);
  }

  const VineGeneratorOptions& options_;
  const TrellisRow& row_;
  VineRng rng_;
  VinePlant plant_;
  double post_x_ = 0.0;  // row position of the post nearest the trunk's base
};

}  // namespace

VinePlant GrowVine(uint64_t seed, int vine_index, const VineGeneratorOptions& options,
                   const TrellisRow& row) {
  return PlantBuilder(seed, vine_index, options, row).Build();
}

void ShiftModelX(double dx, VineModel* model) {
  for (Cane& cane : model->canes) {
    for (Eigen::Vector3d& p : cane.polyline.points) p.x() += dx;
  }
  for (Sphere& s : model->head.spheres) s.center.x() += dx;
  for (Wire& w : model->wires) {
    for (Eigen::Vector3d& p : w.points) p.x() += dx;
  }
  for (Post& p : model->posts) {
    p.base.x() += dx;
    p.top.x() += dx;
  }
}

}  // namespace vb::sim
