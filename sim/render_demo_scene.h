// SPDX-License-Identifier: Apache-2.0
// A hand-built, deterministic scene of typical complexity for renderer tests and benchmarks,
// independent of the vine generator: a trunk, a head of spheres, canes of ~60 segments, four
// wires, a post, neighbours' canes intruding from both sides, and three LED flashes at the rig.
// Thread-safe (pure function).
#pragma once

#include <cstdint>

#include "sim/scene.h"

namespace vb::sim {

struct DemoSceneOptions {
  int cane_count = 20;           // canes growing from the head
  int segments_per_cane = 60;
  int head_spheres = 10;
  int neighbour_canes = 15;      // split between the two neighbours
  double vine_plane_y_m = 0.8;
  uint64_t seed = 1;
};

Scene MakeDemoScene(const DemoSceneOptions& options = {});

}  // namespace vb::sim
