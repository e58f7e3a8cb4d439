// SPDX-License-Identifier: Apache-2.0
// One dormant vine of a row (trunk, head, canes, water shoots, forks, old spurs) in row
// coordinates, as a pure function of (seed, vine index, options, trellis). Structure after
// Botterill et al., "A Robot System for Pruning Grape Vines", J. Field Robotics 2017: a trunk
// topped by a gnarled head just below the fruiting wire, 8-25 canes from the head (a few from the
// trunk), canes 4-15 mm thick at the base, some forked, 1-4 short thick spurs left by last year's
// pruning. Thread-safe (pure function).
#pragma once

#include <cstdint>

#include "core/vine_model.h"
#include "sim/trellis.h"
#include "sim/vine_generator.h"

namespace vb::sim {

struct VinePlant {
  double position_m = 0.0;  // x_row of the trunk base: vine_index * spacing + jitter
  VineModel model;          // canes (trunk id 1) and head; no wires or posts; row coordinates
};

// Grows vine `vine_index` of the row `seed`. `options` must be valid; `row` is the row's trellis
// (MakeTrellisRow(seed, options)). Cane ids: trunk 1, then 2, 3, ... (parents before children).
VinePlant GrowVine(uint64_t seed, int vine_index, const VineGeneratorOptions& options,
                   const TrellisRow& row);

// Adds `dx` to every x coordinate of the canes and head of `model`.
void ShiftModelX(double dx, VineModel* model);

}  // namespace vb::sim
