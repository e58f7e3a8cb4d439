// SPDX-License-Identifier: Apache-2.0
// Binary skeletons for the 2D structure stage (structure2d.h): thinning of a foreground mask to a
// one-pixel-wide skeleton, tracing it into a graph of nodes (ends, junctions) and pixel paths,
// and pruning the graph. Plain C++ (no OpenCV) so it can be tested on hand-made masks.
// Thread-safe (pure functions on caller-owned data).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "Eigen/Core"
#include "workers/reconstruct/mask_ops.h"

namespace vb::reconstruct {

// Thins `mask` in place to an 8-connected skeleton one pixel wide. Zhang & Suen, "A fast parallel
// algorithm for thinning digital patterns" (CACM 1984), with the B >= 3 end condition of Lu & Wang
// (CACM 1986) so two-pixel-wide diagonal lines survive, run over a queue of border pixels so each
// pass only visits pixels next to the last deletions (cost ~ foreground area, not image area
// times passes); then staircase corners (pixels whose removal keeps their neighbours
// 8-connected) are removed so line pixels have exactly two neighbours. Returns the number of
// thinning passes.
int ThinMask(BinaryImage* mask);

// A skeleton as a graph. Nodes are ends (one path) or junctions (a cluster of 8-connected
// skeleton pixels with >= 3 neighbours, at the cluster's centroid). Paths run between nodes;
// their pixels exclude junction-cluster pixels but include end pixels.
struct SkeletonGraph {
  struct Node {
    Eigen::Vector2d position = Eigen::Vector2d::Zero();  // pixels
    std::vector<int> paths;  // indices into `paths`; a loop path appears twice
    bool alive = true;
  };
  struct Path {
    std::vector<Eigen::Vector2i> pixels;  // ordered from node_begin to node_end, >= 1 pixel
    int node_begin = -1;
    int node_end = -1;
    bool alive = true;
    double Length() const;  // sum of pixel steps (1 or sqrt 2)
  };
  std::vector<Node> nodes;
  std::vector<Path> paths;

  int Degree(int node) const { return static_cast<int>(nodes[node].paths.size()); }
  // Drops dead nodes and paths and renumbers the indices.
  void Compact();
};

// Traces a thinned mask (ThinMask) into a graph. Isolated pixels are dropped; closed loops
// without a junction get a node of degree 2 at one of their pixels.
SkeletonGraph TraceSkeleton(const BinaryImage& skeleton);

struct PruneOptions {
  double spur_width_factor = 1.0;   // end paths reaching less than this * their width beyond
                                    // their junction's inscribed disc go
  double min_spur_px = 3.0;         // ... and always those shorter than this
  double merge_width_factor = 0.6;  // junctions joined by a path shorter than this * the
                                    // narrower junction's width merge
  double min_isolated_px = 6.0;     // paths with two free ends shorter than this go
};

// Prunes the spurs that thinning leaves on thick regions and at corners, merges junctions that
// are one (the two junctions a crossing of two canes thins to when they are close), removes
// short isolated paths, and joins the two paths of every node left with degree 2 (except loops).
// `radius_px(x, y)` is the distance from pixel (x, y) to the background (the radius of the
// inscribed disc there). A spur (a path from a junction to a free end) goes if it is shorter than
// min_spur_px or reaches less than spur_width_factor * w beyond the junction's inscribed disc,
// w being the foreground width where it leaves the disc: thinning's spurs run into corners of
// thick regions and end soon after leaving the disc, real branches reach further (and a cane
// leaving the head survives however wide the head). Leaves the graph compacted.
void PruneSkeleton(const PruneOptions& options, const std::function<double(int, int)>& radius_px,
                   SkeletonGraph* graph);

}  // namespace vb::reconstruct
