// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/skeleton.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

namespace vb::reconstruct {
namespace {

// Neighbour bits, clockwise from north: bit k is ring position k.
//   7 0 1
//   6 . 2
//   5 4 3
constexpr int kN = 0, kE = 2, kS = 4, kW = 6;

bool Bit(int code, int k) { return ((code >> k) & 1) != 0; }

// Ring offsets in a padded buffer of row stride `stride`, in bit order.
std::array<int, 8> RingOffsets(int stride) {
  return {-stride, -stride + 1, 1, stride + 1, stride, stride - 1, -1, -stride - 1};
}

int NeighbourCode(const uint8_t* p, const std::array<int, 8>& ring) {
  int code = 0;
  for (int k = 0; k < 8; ++k) code |= (p[ring[k]] != 0) << k;
  return code;
}

// Zhang-Suen deletion tables for the two sub-iterations, with Lu-Wang's 3 <= B <= 6.
struct ThinningTables {
  std::array<std::array<uint8_t, 256>, 2> deletable{};
  std::array<uint8_t, 256> staircase{};

  ThinningTables() {
    for (int code = 0; code < 256; ++code) {
      const int b = __builtin_popcount(static_cast<unsigned>(code));
      int a = 0;  // 0 -> 1 transitions around the ring
      for (int k = 0; k < 8; ++k) a += !Bit(code, k) && Bit(code, (k + 1) % 8);
      const bool n = Bit(code, kN), e = Bit(code, kE), s = Bit(code, kS), w = Bit(code, kW);
      const bool base = b >= 3 && b <= 6 && a == 1;
      deletable[0][code] = base && !(n && e && s) && !(e && s && w);
      deletable[1][code] = base && !(n && e && w) && !(n && s && w);
      // Yokoi's 8-connectivity number (1 = simple point: removal changes no topology).
      const auto x = [&](int k) { return Bit(code, k % 8) ? 0 : 1; };  // complement
      int yokoi = 0;
      for (int k : {kN, kE, kS, kW}) yokoi += x(k) - x(k) * x(k + 1) * x(k + 2);
      const bool corner = (n && e) || (e && s) || (s && w) || (w && n);
      staircase[code] = yokoi == 1 && b >= 2 && corner;
    }
  }
};

const ThinningTables& Tables() {
  static const ThinningTables tables;
  return tables;
}

// Copy of a binary image with a one-pixel zero border, so neighbours never leave the buffer.
std::vector<uint8_t> Padded(const BinaryImage& image) {
  const int stride = image.width + 2;
  std::vector<uint8_t> out(static_cast<size_t>(stride) * (image.height + 2), 0);
  for (int y = 0; y < image.height; ++y) {
    std::copy_n(&image.data[static_cast<size_t>(y) * image.width], image.width,
                &out[static_cast<size_t>(y + 1) * stride + 1]);
  }
  return out;
}

void RemovePath(SkeletonGraph* graph, int path_index) {
  SkeletonGraph::Path& path = graph->paths[path_index];
  path.alive = false;
  for (int node : {path.node_begin, path.node_end}) {
    std::vector<int>& list = graph->nodes[node].paths;
    const auto it = std::find(list.begin(), list.end(), path_index);
    if (it != list.end()) list.erase(it);
  }
}

void Reverse(SkeletonGraph::Path* path) {
  std::reverse(path->pixels.begin(), path->pixels.end());
  std::swap(path->node_begin, path->node_end);
}

// Joins the two distinct paths meeting at degree-2 node `node` into the first of them.
void JoinAt(SkeletonGraph* graph, int node) {
  SkeletonGraph::Node& n = graph->nodes[node];
  const int a = n.paths[0];
  const int b = n.paths[1];
  SkeletonGraph::Path& pa = graph->paths[a];
  SkeletonGraph::Path& pb = graph->paths[b];
  if (pa.node_end != node) Reverse(&pa);
  if (pb.node_begin != node) Reverse(&pb);
  const Eigen::Vector2i hub = n.position.array().round().cast<int>();
  if ((pa.pixels.back() - hub).cwiseAbs().maxCoeff() > 1 &&
      (pb.pixels.front() - hub).cwiseAbs().maxCoeff() > 1) {
    pa.pixels.push_back(hub);  // the junction cluster's pixels are not on either path
  }
  pa.pixels.insert(pa.pixels.end(), pb.pixels.begin(), pb.pixels.end());
  pa.node_end = pb.node_end;
  pb.alive = false;
  std::vector<int>& far = graph->nodes[pa.node_end].paths;
  std::replace(far.begin(), far.end(), b, a);
  n.paths.clear();
  n.alive = false;
}

}  // namespace

double SkeletonGraph::Path::Length() const {
  double length = 0.0;
  for (size_t i = 1; i < pixels.size(); ++i) {
    const Eigen::Vector2i d = (pixels[i] - pixels[i - 1]).cwiseAbs();
    length += (d.x() + d.y() == 2) ? M_SQRT2 : (d.x() + d.y() == 1 ? 1.0 : (pixels[i] - pixels[i - 1]).cast<double>().norm());
  }
  return length;
}

void SkeletonGraph::Compact() {
  std::vector<int> node_index(nodes.size(), -1);
  std::vector<int> path_index(paths.size(), -1);
  std::vector<Node> new_nodes;
  std::vector<Path> new_paths;
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].alive && !nodes[i].paths.empty()) {
      node_index[i] = static_cast<int>(new_nodes.size());
      new_nodes.push_back(std::move(nodes[i]));
    }
  }
  for (size_t i = 0; i < paths.size(); ++i) {
    if (paths[i].alive) {
      path_index[i] = static_cast<int>(new_paths.size());
      new_paths.push_back(std::move(paths[i]));
    }
  }
  for (Node& node : new_nodes) {
    for (int& p : node.paths) p = path_index[p];
  }
  for (Path& path : new_paths) {
    path.node_begin = node_index[path.node_begin];
    path.node_end = node_index[path.node_end];
  }
  nodes = std::move(new_nodes);
  paths = std::move(new_paths);
}

int ThinMask(BinaryImage* mask) {
  const ThinningTables& tables = Tables();
  const int stride = mask->width + 2;
  const std::array<int, 8> ring = RingOffsets(stride);
  std::vector<uint8_t> image = Padded(*mask);
  // stamp[p]: the last sub-iteration that queued p; calm[p]: how many sub-iterations in a row p
  // has survived with an unchanged neighbourhood (after two it can never go, until a neighbour
  // does).
  std::vector<int> stamp(image.size(), -1);
  std::vector<uint8_t> calm(image.size(), 0);
  std::vector<int> queue;
  for (int y = 1; y <= mask->height; ++y) {
    for (int x = 1; x <= mask->width; ++x) {
      const int p = y * stride + x;
      if (image[p] && NeighbourCode(&image[p], ring) != 255) queue.push_back(p);
    }
  }
  std::vector<int> deleted;
  std::vector<int> next;
  int t = 0;
  for (; !queue.empty(); ++t) {
    const int sub = t & 1;
    deleted.clear();
    for (int p : queue) {
      if (image[p] && tables.deletable[sub][NeighbourCode(&image[p], ring)]) deleted.push_back(p);
    }
    for (int p : deleted) image[p] = 0;
    next.clear();
    for (int p : deleted) {
      for (int k = 0; k < 8; ++k) {
        const int q = p + ring[k];
        if (image[q] && stamp[q] != t) {
          stamp[q] = t;
          calm[q] = 0;
          next.push_back(q);
        }
      }
    }
    for (int p : queue) {
      if (image[p] && stamp[p] != t && ++calm[p] < 2) {
        stamp[p] = t;
        next.push_back(p);
      }
    }
    std::swap(queue, next);
  }

  // Staircase corners: raster order so each removal is seen by the next test.
  for (int y = 1; y <= mask->height; ++y) {
    for (int x = 1; x <= mask->width; ++x) {
      const int p = y * stride + x;
      if (image[p] && tables.staircase[NeighbourCode(&image[p], ring)]) image[p] = 0;
    }
  }
  for (int y = 0; y < mask->height; ++y) {
    std::copy_n(&image[static_cast<size_t>(y + 1) * stride + 1], mask->width,
                &mask->data[static_cast<size_t>(y) * mask->width]);
  }
  return (t + 1) / 2;
}

SkeletonGraph TraceSkeleton(const BinaryImage& skeleton) {
  SkeletonGraph graph;
  const int stride = skeleton.width + 2;
  const std::array<int, 8> ring = RingOffsets(stride);
  const std::vector<uint8_t> image = Padded(skeleton);
  const auto pixel_of = [stride](int p) { return Eigen::Vector2i(p % stride - 1, p / stride - 1); };

  std::vector<int> pixels;  // skeleton pixels, padded indices
  for (int y = 1; y <= skeleton.height; ++y) {
    const uint8_t* row = &image[static_cast<size_t>(y) * stride];
    for (int x = 1; x <= skeleton.width; ++x) {
      if (row[x]) pixels.push_back(y * stride + x);
    }
  }
  const auto count = [&](int p) { return __builtin_popcount(NeighbourCode(&image[p], ring)); };

  // node_of: node index of junction-cluster and end pixels; visited: pixels on a traced path.
  std::vector<int> node_of(image.size(), -1);
  std::vector<uint8_t> visited(image.size(), 0);
  std::vector<std::vector<int>> node_pixels;
  const auto add_node = [&](const std::vector<int>& members) {
    const int id = static_cast<int>(graph.nodes.size());
    SkeletonGraph::Node node;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (int p : members) {
      node_of[p] = id;
      sum += pixel_of(p).cast<double>();
    }
    node.position = sum / static_cast<double>(members.size());
    graph.nodes.push_back(node);
    node_pixels.push_back(members);
    return id;
  };
  for (int p : pixels) {
    const int c = count(p);
    if (c >= 3 && node_of[p] < 0) {
      std::vector<int> cluster = {p};
      node_of[p] = -2;  // queued
      for (size_t i = 0; i < cluster.size(); ++i) {
        for (int k = 0; k < 8; ++k) {
          const int q = cluster[i] + ring[k];
          if (image[q] && node_of[q] == -1 && count(q) >= 3) {
            node_of[q] = -2;
            cluster.push_back(q);
          }
        }
      }
      add_node(cluster);
    } else if (c == 1) {
      add_node({p});
    }
  }

  // Walks from `start` (next to, or the end pixel of, node `from`) to the next node.
  const auto trace = [&](int from, int start) {
    SkeletonGraph::Path path;
    path.node_begin = from;
    path.pixels.push_back(pixel_of(start));
    visited[start] = 1;
    int current = start;
    while (true) {
      int next = -1;
      for (int k : {0, 2, 4, 6, 1, 3, 5, 7}) {  // 4-neighbours first
        const int q = current + ring[k];
        if (image[q] && node_of[q] == -1 && !visited[q]) {
          next = q;
          break;
        }
      }
      if (next >= 0) {
        visited[next] = 1;
        path.pixels.push_back(pixel_of(next));
        current = next;
        continue;
      }
      // Arrived: the adjacent node, preferring one other than where the walk began.
      int end = -1;
      int end_pixel = -1;
      for (int k = 0; k < 8; ++k) {
        const int q = current + ring[k];
        if (q == start || node_of[q] < 0) continue;
        if (end < 0 || (end == from && node_of[q] != from)) {
          end = node_of[q];
          end_pixel = q;
        }
      }
      if (end < 0) end = add_node({current});  // a dead end (cannot happen on a thin skeleton)
      else if (node_pixels[end].size() == 1 && count(end_pixel) == 1 && !visited[end_pixel]) {
        visited[end_pixel] = 1;  // end pixels belong to their path
        path.pixels.push_back(pixel_of(end_pixel));
      }
      path.node_end = end;
      break;
    }
    const int id = static_cast<int>(graph.paths.size());
    graph.nodes[path.node_begin].paths.push_back(id);
    graph.nodes[path.node_end].paths.push_back(id);
    graph.paths.push_back(std::move(path));
  };
  const auto trace_from = [&](int node) {
    for (int member : std::vector<int>(node_pixels[node])) {
      if (node_pixels[node].size() == 1 && count(member) == 1) {
        if (!visited[member]) trace(node, member);  // an end: its pixel starts the path
        continue;
      }
      for (int k = 0; k < 8; ++k) {
        const int q = member + ring[k];
        if (image[q] && node_of[q] == -1 && !visited[q]) trace(node, q);
      }
    }
  };
  for (int node = 0; node < static_cast<int>(graph.nodes.size()); ++node) trace_from(node);
  // Closed loops without a junction.
  for (int p : pixels) {
    if (node_of[p] == -1 && !visited[p] && count(p) == 2) trace_from(add_node({p}));
  }
  graph.Compact();
  return graph;
}

void PruneSkeleton(const PruneOptions& options, const std::function<double(int, int)>& radius_px,
                   SkeletonGraph* graph) {
  const auto radius_at = [&](const Eigen::Vector2d& p) {
    return radius_px(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
  };
  std::vector<double> radius;  // per node
  radius.reserve(graph->nodes.size());
  for (const SkeletonGraph::Node& node : graph->nodes) radius.push_back(radius_at(node.position));
  // Length of a spur beyond its hub's inscribed disc, and the width where it leaves the disc
  // (0 and 0 if it never does).
  const auto beyond_hub = [&](const SkeletonGraph::Path& path, int hub) {
    const Eigen::Vector2d centre = graph->nodes[hub].position;
    const double r = radius[hub];
    const int n = static_cast<int>(path.pixels.size());
    const bool forward = path.node_begin == hub;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2i& p = path.pixels[forward ? k : n - 1 - k];
      if ((p.cast<double>() - centre).norm() > r) {
        SkeletonGraph::Path rest;
        rest.pixels.assign(path.pixels.begin() + (forward ? k : 0),
                           path.pixels.begin() + (forward ? n : n - k));
        return std::make_pair(rest.Length() + 1.0, 2.0 * radius_px(p.x(), p.y()));
      }
    }
    return std::make_pair(0.0, 0.0);
  };
  const auto kill_lonely = [&](int node) {
    if (graph->nodes[node].paths.empty()) graph->nodes[node].alive = false;
  };
  for (int round = 0; round < 100; ++round) {
    bool changed = false;
    // Spurs, shortest first, at most down to degree 2 at any junction.
    std::vector<std::pair<double, int>> spurs;
    for (int i = 0; i < static_cast<int>(graph->paths.size()); ++i) {
      const SkeletonGraph::Path& path = graph->paths[i];
      if (!path.alive || path.node_begin == path.node_end) continue;
      const int db = graph->Degree(path.node_begin);
      const int de = graph->Degree(path.node_end);
      if ((db == 1) == (de == 1)) continue;
      const int hub = db == 1 ? path.node_end : path.node_begin;
      const double length = path.Length();
      if (length >= options.min_spur_px) {
        const auto [beyond, exit_width] = beyond_hub(path, hub);
        if (beyond > 0.0 && beyond >= options.spur_width_factor * exit_width) continue;
      }
      spurs.emplace_back(length, i);
    }
    std::sort(spurs.begin(), spurs.end());
    for (const auto& [length, i] : spurs) {
      const SkeletonGraph::Path& path = graph->paths[i];
      const int db = graph->Degree(path.node_begin);
      const int hub = db == 1 ? path.node_end : path.node_begin;
      const int tip = db == 1 ? path.node_begin : path.node_end;
      if (graph->Degree(hub) < 3) continue;
      RemovePath(graph, i);
      kill_lonely(tip);
      changed = true;
    }
    // Junctions that are one: contract short paths between two junctions.
    for (int i = 0; i < static_cast<int>(graph->paths.size()); ++i) {
      SkeletonGraph::Path& path = graph->paths[i];
      if (!path.alive) continue;
      const int a = path.node_begin;
      const int b = path.node_end;
      if (a == b) {
        // A small loop left by a contraction or a pinhole: drop it.
        if (path.Length() < std::max(options.min_spur_px, 2.0 * radius[a])) {
          RemovePath(graph, i);
          changed = true;
        }
        continue;
      }
      if (graph->Degree(a) < 3 || graph->Degree(b) < 3) continue;
      if (path.Length() >= options.merge_width_factor * 2.0 * std::min(radius[a], radius[b])) {
        continue;
      }
      RemovePath(graph, i);
      SkeletonGraph::Node& na = graph->nodes[a];
      SkeletonGraph::Node& nb = graph->nodes[b];
      const double wa = static_cast<double>(na.paths.size());
      const double wb = static_cast<double>(nb.paths.size());
      na.position = (wa * na.position + wb * nb.position) / (wa + wb);
      radius[a] = std::max(radius[a], radius[b]);
      for (int p : nb.paths) {
        SkeletonGraph::Path& other = graph->paths[p];
        if (other.node_begin == b) other.node_begin = a;
        if (other.node_end == b) other.node_end = a;
        na.paths.push_back(p);
      }
      nb.paths.clear();
      nb.alive = false;
      changed = true;
    }
    // Short pieces with two free ends.
    for (int i = 0; i < static_cast<int>(graph->paths.size()); ++i) {
      const SkeletonGraph::Path& path = graph->paths[i];
      if (!path.alive || path.node_begin == path.node_end) continue;
      if (graph->Degree(path.node_begin) != 1 || graph->Degree(path.node_end) != 1) continue;
      if (path.Length() >= options.min_isolated_px) continue;
      const int a = path.node_begin;
      const int b = path.node_end;
      RemovePath(graph, i);
      kill_lonely(a);
      kill_lonely(b);
      changed = true;
    }
    // Nodes left with two distinct paths are not nodes.
    for (int n = 0; n < static_cast<int>(graph->nodes.size()); ++n) {
      SkeletonGraph::Node& node = graph->nodes[n];
      if (!node.alive) continue;
      if (node.paths.empty()) {
        node.alive = false;
        continue;
      }
      if (node.paths.size() == 2 && node.paths[0] != node.paths[1]) {
        JoinAt(graph, n);
        changed = true;
      }
    }
    if (!changed) break;
  }
  graph->Compact();
}

}  // namespace vb::reconstruct
