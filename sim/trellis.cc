// SPDX-License-Identifier: Apache-2.0
#include "sim/trellis.h"

#include <algorithm>
#include <cmath>

#include "sim/vine_random.h"

namespace vb::sim {
namespace {

constexpr uint64_t kTrellisStream = 0x7E11;
// Foliage wires are spread over the height between the fruiting wire and the post top; keep the
// top wire this far below the post top (it is stapled a little below the end).
constexpr double kTopWireClearanceM = 0.06;

}  // namespace

TrellisRow MakeTrellisRow(uint64_t seed, const VineGeneratorOptions& options) {
  VineRng rng(MixSeed(seed, 0, kTrellisStream));
  TrellisRow row;
  row.post_offset_m = rng.Uniform(0.0, options.post_spacing_m);
  const double fruiting = rng.Uniform(options.fruiting_wire_min_m, options.fruiting_wire_max_m);
  const int foliage = rng.UniformInt(options.foliage_wires_min, options.foliage_wires_max);
  // The fruiting wire carries the canes' weight and sags more than the foliage wires.
  row.wires.push_back({WireId(1), fruiting, options.vine_plane_y_m + rng.Normal(0.0, 0.004),
                       rng.Uniform(0.01, 0.035)});
  const double top = options.post_height_m - kTopWireClearanceM;
  if (foliage > 0) {
    // Typical vertical-shoot-positioning spacing is 0.2-0.35 m; squeeze if the posts are short.
    const double room = std::max(0.0, top - fruiting);
    const double gap = std::min(rng.Uniform(0.22, 0.34), room / foliage);
    for (int k = 1; k <= foliage; ++k) {
      const double height = fruiting + k * gap + rng.Normal(0.0, 0.01) * (gap > 0.05 ? 1.0 : 0.0);
      row.wires.push_back({WireId(k + 1), std::min(height, top),
                           options.vine_plane_y_m + rng.Uniform(-0.04, 0.04),
                           rng.Uniform(0.004, 0.02)});
    }
  }
  return row;
}

double WireHeightAt(const TrellisRow& row, const TrellisWire& wire, double x_row,
                    const VineGeneratorOptions& options) {
  const double spacing = options.post_spacing_m;
  const double u = (x_row - row.post_offset_m) / spacing;
  const double frac = u - std::floor(u);  // position between the posts on either side, [0, 1)
  return wire.height_m - wire.sag_m * 4.0 * frac * (1.0 - frac);
}

void AddTrellisToModel(const TrellisRow& row, double origin_x_row,
                       const VineGeneratorOptions& options, VineModel* model) {
  const double spacing = options.post_spacing_m;
  // Posts in view, in increasing x.
  std::vector<double> post_x;
  const double lo = (origin_x_row - kTrellisHalfSpanM - row.post_offset_m) / spacing;
  const double hi = (origin_x_row + kTrellisHalfSpanM - row.post_offset_m) / spacing;
  for (int64_t j = static_cast<int64_t>(std::floor(lo)); j <= static_cast<int64_t>(std::ceil(hi));
       ++j) {
    const double x = j * spacing + row.post_offset_m - origin_x_row;
    if (std::abs(x) <= kTrellisHalfSpanM) post_x.push_back(x);
  }
  for (size_t i = 0; i < post_x.size(); ++i) {
    Post post;
    post.id = PostId(static_cast<int64_t>(i) + 1);
    post.base = Eigen::Vector3d(post_x[i], options.vine_plane_y_m, 0.0);
    post.top = Eigen::Vector3d(post_x[i], options.vine_plane_y_m, options.post_height_m);
    post.radius = options.post_radius_m;
    model->posts.push_back(post);
  }
  // Wire sample positions: a regular grid plus the posts (where the sag parabola has a kink).
  std::vector<double> xs;
  constexpr double kStepM = 0.25;
  for (double x = -kTrellisHalfSpanM; x <= kTrellisHalfSpanM + 1e-9; x += kStepM) xs.push_back(x);
  xs.insert(xs.end(), post_x.begin(), post_x.end());
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end(),
                       [](double a, double b) { return std::abs(a - b) < 1e-6; }),
           xs.end());
  for (const TrellisWire& tw : row.wires) {
    Wire wire;
    wire.id = tw.id;
    wire.radius = options.wire_radius_m;
    for (double x : xs) {
      wire.points.emplace_back(x, tw.y_m, WireHeightAt(row, tw, x + origin_x_row, options));
    }
    model->wires.push_back(std::move(wire));
  }
}

}  // namespace vb::sim
