// SPDX-License-Identifier: Apache-2.0
// The trellis of a vineyard row: posts every ~post_spacing_m and 3-4 horizontal wires (the
// fruiting wire, 0.9-1.0 m, and foliage wires above it) strung between them. The trellis is a
// property of the row, a pure function of the vineyard seed, so every stop sees the same posts and
// wires shifted by its position. Row coordinates: x_row along the row (vine k stands near
// x_row = k * vine_spacing_m); y, z as in the platform frame. Thread-safe (pure functions).
#pragma once

#include <cstdint>
#include <vector>

#include "core/vine_model.h"
#include "sim/vine_generator.h"

namespace vb::sim {

struct TrellisWire {
  WireId id;
  double height_m = 0.0;  // z at the posts (where the wire is fixed)
  double y_m = 0.0;       // across-row position
  double sag_m = 0.0;     // extra drop midway between two posts
};

struct TrellisRow {
  double post_offset_m = 0.0;        // posts stand at x_row = j * post_spacing_m + post_offset_m
  std::vector<TrellisWire> wires;    // wires[0] is the fruiting wire; the rest are higher
};

// The trellis of the row generated from `seed`. `options` must be valid.
TrellisRow MakeTrellisRow(uint64_t seed, const VineGeneratorOptions& options);

// Height of `wire` at row position x_row: a parabolic sag between neighbouring posts.
double WireHeightAt(const TrellisRow& row, const TrellisWire& wire, double x_row,
                    const VineGeneratorOptions& options);

// Half-width of the trellis span put into a scene: wires cover platform x in [-kTrellisHalfSpanM,
// +kTrellisHalfSpanM], and every post with |x| <= kTrellisHalfSpanM is included.
inline constexpr double kTrellisHalfSpanM = 2.5;

// Appends the wires and posts in view from a stop whose platform origin is at row position
// `origin_x_row` to `model`, in the platform frame. Wire ids follow `row`; post ids count from 1
// in increasing x. Wires get a point every 0.25 m plus a point at each post, so their sag shows.
void AddTrellisToModel(const TrellisRow& row, double origin_x_row,
                       const VineGeneratorOptions& options, VineModel* model);

}  // namespace vb::sim
