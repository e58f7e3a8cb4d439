// SPDX-License-Identifier: Apache-2.0
// Test support for correspondence: simulated stops drawn by SyntheticViews and degraded roughly
// as a real 2D stage would degrade them. Header-only; tests and training only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/deadline.h"
#include "core/geometry.h"
#include "sim/fiducials.h"
#include "sim/renderer.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "workers/reconstruct/fiducials.h"
#include "workers/reconstruct/match_classifier.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/strand_halves.h"
#include "workers/reconstruct/structure2d.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {

// Portable noise for the simulated stops (std distributions differ between libraries).
class Noise {
 public:
  explicit Noise(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ull + 1) {}
  double Uniform() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  }
  double Gaussian() {
    const double u = std::max(Uniform(), 1e-300);
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * Uniform());
  }

 private:
  uint64_t state_;
};

// What a real 2D stage does to perfect segments, roughly: smooth sub-pixel wobble of the
// skeleton, noisy widths, and canes broken into pieces (at junctions, crossings, occlusions).
inline void Degrade(View2D* view, Noise* noise, double break_px = 100.0) {
  std::vector<Segment2D> out;
  for (const Segment2D& s : view->segments) {
    Segment2D current;
    double wobble_x = 0.0, wobble_y = 0.0, width_scale = 1.0 + 0.1 * noise->Gaussian();
    double next_break = break_px * (1.0 + 4.0 * noise->Uniform()), arc = 0.0;
    for (size_t i = 0; i < s.points.size(); ++i) {
      if (i > 0) arc += (s.points[i] - s.points[i - 1]).norm();
      wobble_x = 0.9 * wobble_x + 0.13 * noise->Gaussian();
      wobble_y = 0.9 * wobble_y + 0.13 * noise->Gaussian();
      if (arc > next_break) {
        if (current.points.size() >= 2) out.push_back(current);
        current = {};
        next_break = arc + break_px * (1.0 + 4.0 * noise->Uniform());
        width_scale = 1.0 + 0.1 * noise->Gaussian();
        i += 2;  // a small gap where the cane was broken
        continue;
      }
      current.points.push_back(s.points[i] + Eigen::Vector2d(wobble_x, wobble_y));
      current.widths_px.push_back(
          std::max(1.0, s.widths_px[i] * width_scale * (1.0 + 0.05 * noise->Gaussian())));
    }
    if (current.points.size() >= 2) out.push_back(current);
  }
  view->segments = std::move(out);
  view->nodes.clear();
}

struct SimulatedStop {
  sim::Scene scene;
  VineModel drawn;             // the vine plus its neighbours' canes and heads
  RigCalibration true_rig;     // drew the views
  RigCalibration rig;          // the 1 px-perturbed calibration the matching is given
  std::vector<View2D> views;   // degraded
};

// The stop at vine 0 of vineyard `seed`: vine and neighbours drawn by SyntheticViews through
// the true rig, then degraded (Degrade, canes broken every 1-5 x break_px); matching uses PerturbCalibration(rig, 1 px, seed).
inline SimulatedStop MakeSimulatedStop(uint64_t seed, double break_px = 100.0) {
  SimulatedStop stop;
  stop.scene = sim::GenerateScene(seed, 0).value();
  stop.drawn = stop.scene.vine;
  for (const VineModel& neighbour : stop.scene.neighbours) {
    for (const Cane& cane : neighbour.canes) stop.drawn.canes.push_back(cane);
    for (const Sphere& s : neighbour.head.spheres) stop.drawn.head.spheres.push_back(s);
  }
  stop.true_rig = sim::MakeRig().value();
  stop.views = SyntheticViews(stop.drawn, stop.true_rig);
  Noise noise(seed);
  for (View2D& view : stop.views) Degrade(&view, &noise, break_px);
  stop.rig = sim::PerturbCalibration(stop.true_rig, 1.0, seed);
  return stop;
}

// The noise seed of vine 1 of vineyard `seed`, as app/bench_command.cc derives it.
inline uint64_t StopNoiseSeed(uint64_t seed) { return seed * 1000003 + 1; }

// The stop at vine 1 of vineyard `seed` without images: the scene, the vine and its neighbours'
// canes and heads as `drawn`, the true rig placed by `rig_options` (with the platform's fiducials
// listed when `fiducials`) and the calibration the bench reports, 1 px off (as
// capture::MakeSimRig). No views: MakeRenderedStop renders them; the oracles of the diagnosis
// reports draw them (SyntheticViews).
inline SimulatedStop MakeStopGeometry(uint64_t seed, bool fiducials = false,
                                      const sim::RigOptions& rig_options = {}) {
  SimulatedStop stop;
  const uint64_t noise_seed = StopNoiseSeed(seed);
  stop.scene = sim::GenerateScene(seed, 1).value();
  stop.drawn = stop.scene.vine;
  for (const VineModel& neighbour : stop.scene.neighbours) {
    for (const Cane& cane : neighbour.canes) stop.drawn.canes.push_back(cane);
    for (const Sphere& s : neighbour.head.spheres) stop.drawn.head.spheres.push_back(s);
  }
  stop.true_rig = sim::MakeRig(rig_options).value();
  if (fiducials) {
    stop.true_rig.fiducials = sim::PlatformFiducials().value();
    stop.scene.fiducials = stop.true_rig.fiducials;
  }
  // As capture::MakeSimRig.
  stop.rig = sim::PerturbCalibration(stop.true_rig, 1.0, noise_seed ^ 0xCA11B4A7Eull);
  return stop;
}

// The stop at vine 1 of vineyard `seed` as `vinebot bench reconstruct` renders it (sensor noise,
// reported calibration 1 px off), its views from the real 2D stage (ExtractStructure) run on
// the renderer's label images (`segment` false) or on the segmenter's classes of the rendered
// image (`segment` true; rendered as rgb8, where the bench demosaics a Bayer mosaic: vb_capture
// is not linked here). With `fiducials`, as the bench by default: the platform's fiducials are
// drawn and listed in both rigs, found in each image (DetectFiducials) and cleared from the
// classes (ClearFiducials), and each view carries its detections for the rig refinement. Each
// view's strand halves are found from the rendered image with the default options (none, as
// they are off by default; VB_STRAND_HALVES=1 switches them on for the diagnosis reports).
// `rig_options` place the rig (the simulator's default rig unless given). Returns a stop
// without views if rendering or the 2D stage fails.
inline SimulatedStop MakeRenderedStop(uint64_t seed, bool segment, bool fiducials = false,
                                      const sim::RigOptions& rig_options = {}) {
  SimulatedStop stop = MakeStopGeometry(seed, fiducials, rig_options);
  const uint64_t noise_seed = StopNoiseSeed(seed);
  for (size_t i = 0; i < stop.true_rig.cameras.size(); ++i) {
    const auto view = sim::Render(stop.scene, stop.true_rig.cameras[i], sim::RenderOptions{},
                                  noise_seed + 7919 * (i + 1));
    if (!view.ok()) return {};
    ClassImage classes = ClassesOfSimLabels(view->labels);
    if (segment) {
      auto segmented = Segment(view->image, BuiltinSegmenterModel());
      if (!segmented.ok()) return {};
      classes = std::move(*segmented);
    }
    std::vector<FiducialObservation> found;
    if (fiducials) {
      auto detected = DetectFiducials(view->image, stop.rig.cameras[i], stop.rig.fiducials,
                                      FiducialDetectOptions{});
      if (!detected.ok()) return {};
      found = std::move(*detected);
      ClearFiducials(found, stop.rig.cameras[i], stop.rig.fiducials, &classes);
    }
    auto view2d = ExtractStructure(classes, stop.rig.cameras[i], Structure2DOptions{},
                                   Deadline::Infinite());
    if (!view2d.ok()) return {};
    view2d->fiducials = std::move(found);
    // As Reconstruct (and the bench's label input) do after the 2D structure.
    StrandHalfOptions halves_options;
    if (const char* env = std::getenv("VB_STRAND_HALVES")) {
      halves_options.enabled = std::string(env) == "1";
    }
    auto halves = FindStrandHalves(*view2d, view->image, halves_options);
    if (!halves.ok()) return {};
    view2d->strand_halves = std::move(*halves);
    stop.views.push_back(std::move(*view2d));
  }
  return stop;
}

// Distance from p to the nearest of `wires` (polylines); `error`, if given, gets the vector
// from p to that nearest point.
inline double DistanceToWires(const Eigen::Vector3d& p, const std::vector<Wire>& wires,
                       Eigen::Vector3d* error = nullptr) {
  double best = 1e9;
  for (const Wire& w : wires)
    for (size_t i = 0; i + 1 < w.points.size(); ++i) {
      double t = 0;
      const double d = PointSegmentDistance(p, w.points[i], w.points[i + 1], &t);
      if (d < best) {
        best = d;
        if (error) *error = w.points[i] + t * (w.points[i + 1] - w.points[i]) - p;
      }
    }
  return best;
}

// Whether `view` shows foreground within `r` px (a square) of pixel (x, y), inside the image.
inline bool ForegroundWithin(const View2D& view, int x, int y, int r) {
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx < 0 || yy < 0 || xx >= view.width || yy >= view.height) continue;
      if (view.IsForeground(xx, yy)) return true;
    }
  return false;
}

// Points of a piece, sampled along its polyline every 2 mm.
inline std::vector<Eigen::Vector3d> PiecePoints(const Piece3D& piece) { return piece.polyline.Sample(0.002); }

// Fraction of `truth` (sampled every 5 mm) within `tolerance_m` of some piece.
inline double Coverage(const Polyline3& truth, const std::vector<Piece3D>& pieces, double tolerance_m) {
  const std::vector<Eigen::Vector3d> samples = truth.Sample(0.005);
  int covered = 0;
  for (const Eigen::Vector3d& s : samples) {
    for (const Piece3D& piece : pieces) {
      if (DistanceToPolyline(s, piece.polyline) <= tolerance_m) {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / samples.size();
}

// Part of each true cane seen by at least two cameras, as polylines (split where it is not).
inline std::vector<Polyline3> SeenByTwo(const Polyline3& cane, const RigCalibration& rig) {
  std::vector<Polyline3> parts;
  Polyline3 current;
  for (const Eigen::Vector3d& p : cane.Sample(0.005)) {
    int seen = 0;
    for (const CameraCalibration& camera : rig.cameras) {
      const auto uv = camera.Project(p);
      seen += uv && camera.InImage(*uv) ? 1 : 0;
    }
    if (seen >= 2) {
      current.points.push_back(p);
      current.radii.push_back(0.001);
    } else if (!current.points.empty()) {
      if (current.points.size() >= 2) parts.push_back(current);
      current = {};
    }
  }
  if (current.points.size() >= 2) parts.push_back(current);
  return parts;
}

struct Metrics {
  double coverage = 0.0;   // of the vine's cane length seen by two cameras, within 1 cm of a piece
  double precision = 0.0;  // of piece length, within 1 cm of a true cane
  double truth_m = 0.0;
  double pieces_m = 0.0;
};

inline Metrics Evaluate(const std::vector<Piece3D>& pieces, const VineModel& vine,
                 const VineModel& drawn, const RigCalibration& rig) {
  Metrics m;
  double covered = 0.0;
  for (const Cane& cane : vine.canes) {
    for (const Polyline3& part : SeenByTwo(cane.polyline, rig)) {
      m.truth_m += part.Length();
      covered += part.Length() * Coverage(part, pieces, 0.01);
    }
  }
  double precise = 0.0;
  for (const Piece3D& piece : pieces) {
    const std::vector<Eigen::Vector3d> points = PiecePoints(piece);
    int near = 0;
    for (const Eigen::Vector3d& p : points) {
      for (const Cane& cane : drawn.canes) {
        if (DistanceToPolyline(p, cane.polyline) <= 0.01) {
          ++near;
          break;
        }
      }
    }
    m.pieces_m += piece.polyline.Length();
    precise += piece.polyline.Length() * near / std::max<size_t>(1, points.size());
  }
  m.coverage = covered / std::max(m.truth_m, 1e-9);
  m.precision = precise / std::max(m.pieces_m, 1e-9);
  return m;
}

// The stops a disabled diagnosis report runs on, from the environment: VB_SEED (the first seed),
// VB_STOPS (how many), VB_INPUT (images: rendered and segmented, as MakeRenderedStop's `segment`;
// anything else: the renderer's labels; unset: `images_by_default`) and VB_FIDUCIALS (0: without
// the platform's fiducials).
struct ReportStops {
  uint64_t first;
  int count;
  bool images;
  bool fiducials;
};
inline ReportStops ReportStopsFromEnv(uint64_t default_first, int default_count,
                                      bool images_by_default = false) {
  const char* seed = std::getenv("VB_SEED");
  const char* stops = std::getenv("VB_STOPS");
  const char* input = std::getenv("VB_INPUT");
  const char* fiducials = std::getenv("VB_FIDUCIALS");
  return {seed ? static_cast<uint64_t>(std::atoi(seed)) : default_first,
          stops ? std::atoi(stops) : default_count,
          input ? std::string(input) == "images" : images_by_default,
          !fiducials || std::string(fiducials) != "0"};
}

// Points in a 1 cm hash grid, each with a value; query: largest value within 10 mm.
class PointGrid {
 public:
  void Add(const Eigen::Vector3d& p, double value) {
    cells_[Key(Cell(p))].push_back({p, value});
  }
  double MaxNear(const Eigen::Vector3d& p, double radius = 0.01) const {
    double best = -1;
    const Eigen::Vector3i c = Cell(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(Key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const auto& [q, v] : it->second)
            if ((q - p).norm() <= radius) best = std::max(best, v);
        }
    return best;
  }
  void AddLine(const std::vector<Eigen::Vector3d>& pts, double value) {
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
      const int n = std::max(1, static_cast<int>((pts[i + 1] - pts[i]).norm() / 0.004));
      for (int k = 0; k < n; ++k) Add(pts[i] + (pts[i + 1] - pts[i]) * (double(k) / n), value);
    }
    if (!pts.empty()) Add(pts.back(), value);
  }

 private:
  static Eigen::Vector3i Cell(const Eigen::Vector3d& p) {
    return (p / 0.01).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (int64_t(c.x() + 100000) * 200003 + (c.y() + 100000)) * 200003 + (c.z() + 100000);
  }
  std::unordered_map<int64_t, std::vector<std::pair<Eigen::Vector3d, double>>> cells_;
};

}  // namespace vb::reconstruct
