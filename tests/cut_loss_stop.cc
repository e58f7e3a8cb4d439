// SPDX-License-Identifier: Apache-2.0
#include "tests/cut_loss_stop.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/vine_model_json.h"
#include "sim/vine_generator.h"
#include "workers/capture/sim_capture.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/structure2d.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::cutloss {

absl::StatusOr<std::optional<double>> EnvNumber(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr) return std::nullopt;
  char* end = nullptr;
  const double x = std::strtod(v, &end);
  if (end == v || *end != '\0' || !std::isfinite(x))
    return absl::InvalidArgumentError(
        absl::StrCat(name, " must be one finite number, is \"", v, "\""));
  return x;
}

namespace {

// *field from the environment variable `name` when it is set (EnvNumber's errors).
absl::Status OverrideNumber(const char* name, double* field) {
  auto x = EnvNumber(name);
  if (!x.ok()) return x.status();
  if (x->has_value()) *field = **x;
  return absl::OkStatus();
}

// *field from the environment variable `name` when it is set: 0 or 1, else INVALID_ARGUMENT
// naming it.
absl::Status OverrideSwitch(const char* name, bool* field) {
  auto x = EnvNumber(name);
  if (!x.ok()) return x.status();
  if (!x->has_value()) return absl::OkStatus();
  if (**x != 0.0 && **x != 1.0)
    return absl::InvalidArgumentError(absl::StrCat(name, " must be 0 or 1, is ", **x));
  *field = **x == 1.0;
  return absl::OkStatus();
}

}  // namespace

// The stop as the bench renders and reconstructs it.
absl::StatusOr<Stop> MakeStop(uint64_t seed, const std::string& input, const std::string& cache) {
  const std::string model_path = cache + "/model_" + std::to_string(seed) + "_" + input + ".json";
  const std::string truth_path = cache + "/truth_" + std::to_string(seed) + ".json";
  if (!cache.empty() && std::filesystem::exists(model_path) &&
      std::filesystem::exists(truth_path)) {
    Stop stop;
    auto truth = ReadVineModel(truth_path);
    auto model = ReadVineModel(model_path);
    if (!truth.ok()) return truth.status();
    if (!model.ok()) return model.status();
    stop.truth = *std::move(truth);
    stop.model = *std::move(model);
    return stop;
  }
  reconstruct::ReconstructOptions options;
  // Head variants (docs/reconstruction.md step 5, s19), for the head oracles; give each variant
  // its own VB_CACHE: VB_HEAD_DEPTH_FACTOR, VB_HEAD_LEAF_FRACTION, VB_HEAD_MIN_CELL (numbers),
  // VB_HEAD_CENTRE_ON_TRUNK, VB_HEAD_PEEL (0 or 1).
  for (const auto& [name, field] :
       {std::pair{"VB_HEAD_DEPTH_FACTOR", &options.head.head_depth_factor},
        std::pair{"VB_HEAD_LEAF_FRACTION", &options.head.leaf_radius_fraction},
        std::pair{"VB_HEAD_MIN_CELL", &options.head.min_cell_m}}) {
    if (auto s = OverrideNumber(name, field); !s.ok()) return s;
  }
  if (auto s = OverrideSwitch("VB_HEAD_CENTRE_ON_TRUNK", &options.head.head_centre_on_trunk);
      !s.ok())
    return s;
  if (auto s = OverrideSwitch("VB_HEAD_PEEL", &options.head.peel_canes); !s.ok()) return s;
  if (auto s = options.head.Validate(); !s.ok()) return s;
  // VB_HEAD_BASES (0 or 1): the cane bases at the head (head_bases.h; give each its own VB_CACHE);
  // VB_HEAD_BASES_CURVE=G: their course's curvature as a fraction of the end's (curve_gain);
  // VB_HEAD_BASES_SKELETON=PX: their max_skeleton_px.
  if (auto s = OverrideSwitch("VB_HEAD_BASES", &options.head_bases.enabled); !s.ok()) return s;
  if (auto s = OverrideNumber("VB_HEAD_BASES_CURVE", &options.head_bases.curve_gain); !s.ok())
    return s;
  if (auto s = OverrideNumber("VB_HEAD_BASES_SKELETON", &options.head_bases.max_skeleton_px);
      !s.ok())
    return s;
  if (auto s = options.head_bases.Validate(); !s.ok()) return s;
  const int vine = 1;
  auto scene = sim::GenerateScene(seed, vine);
  if (!scene.ok()) return scene.status();
  capture::SimCaptureOptions sim_options;
  sim_options.calibration_error_px = 1.0;
  sim_options.render.pixel_format = PixelFormat::kBayerRg8;
  // VB_RIG_BASELINE=M: the simulated rig's triangle side (a rig study; its own VB_CACHE).
  if (auto s = OverrideNumber("VB_RIG_BASELINE", &sim_options.rig.baseline_m); !s.ok()) return s;
  if (auto s = sim_options.Validate(); !s.ok()) return s;
  auto capture = capture::RenderSimCapture(*scene, sim_options, seed * 1000003 + vine);
  if (!capture.ok()) return capture.status();
  RigCalibration rig;
  for (size_t c = 0; c < capture->bundle.images.size(); ++c)
    rig.cameras.push_back(capture->bundle.CalibrationOf(c));
  rig.fiducials = capture->bundle.calibration.fiducials;
  absl::StatusOr<reconstruct::ReconstructResult> result;
  if (input == "images") {
    std::vector<Image> images;
    for (const Image& image : capture->bundle.images) {
      auto rgb = capture::ToRgb(image);
      if (!rgb.ok()) return rgb.status();
      images.push_back(*std::move(rgb));
    }
    result = reconstruct::Reconstruct(images, rig, reconstruct::BuiltinSegmenterModel(), options,
                                      Deadline::In(120.0));
  } else {
    std::vector<reconstruct::View2D> views;
    if (input == "truth") {
      views = reconstruct::SyntheticViews(capture->ground_truth, rig, {});
    } else {
      for (size_t c = 0; c < capture->labels.size(); ++c) {
        auto view = reconstruct::ExtractStructure(
            reconstruct::ClassesOfSimLabels(capture->labels[c]), rig.cameras[c],
            options.structure, Deadline::In(120.0));
        if (!view.ok()) return view.status();
        views.push_back(*std::move(view));
      }
    }
    result = reconstruct::ReconstructFromViews(views, rig, options, Deadline::In(120.0));
  }
  if (!result.ok()) return result.status();
  Stop stop{capture->ground_truth, result->model};
  if (!cache.empty()) {
    std::filesystem::create_directories(cache);
    if (auto s = WriteVineModel(model_path, stop.model); !s.ok()) return s;
    if (auto s = WriteVineModel(truth_path, stop.truth); !s.ok()) return s;
  }
  return stop;
}

// Nearest cane of `m` to `p`: its index (-1 if no canes), distance and arc length.
int Nearest(const VineModel& m, const Eigen::Vector3d& p, double* distance, double* arc) {
  int best = -1;
  *distance = 1e9;
  for (size_t i = 0; i < m.canes.size(); ++i) {
    double d = 0.0;
    const double s = m.canes[i].polyline.Project(p, &d);
    if (d < *distance) {
      *distance = d;
      *arc = s;
      best = static_cast<int>(i);
    }
  }
  return best;
}

// Per model cane: the truth cane most of its length lies within 10 mm of (-1: none).
std::vector<int> Correspondence(const VineModel& model, const VineModel& truth) {
  std::vector<int> out(model.canes.size(), -1);
  for (size_t i = 0; i < model.canes.size(); ++i) {
    const Polyline3& line = model.canes[i].polyline;
    std::map<int, int> votes;
    for (double s = 0.0; s <= line.Length(); s += 0.005) {
      double d = 0.0, a = 0.0;
      const int t = Nearest(truth, line.PointAt(s), &d, &a);
      if (t >= 0 && d <= 0.010) ++votes[t];
    }
    int best = 0;
    for (const auto& [t, n] : votes) {
      if (n > best) {
        best = n;
        out[i] = t;
      }
    }
  }
  return out;
}

// Distance from p to the surface of the head (negative inside); +inf without spheres.
double HeadSurfaceDistance(const HeadModel& head, const Eigen::Vector3d& p) {
  double best = 1e9;
  for (const Sphere& s : head.spheres) best = std::min(best, (p - s.center).norm() - s.radius);
  return best;
}

// The truth's scheme carried over to the model: each truth kept cane / spur to the model candidate
// that covers most of its first 0.3 m (ties: the candidate nearer its base), if feasible.
std::optional<decide::Scheme> CarryOver(const VineModel& truth, const CutPlan& truth_plan,
                                        const VineModel& model,
                                        const std::vector<decide::Candidate>& candidates) {
  std::map<int64_t, size_t> cand_of;  // model cane id -> candidate index
  for (size_t i = 0; i < candidates.size(); ++i) cand_of[candidates[i].id.value] = i;
  auto map_one = [&](CaneId id) -> std::optional<CaneId> {
    const Polyline3& line = truth.canes[*truth.IndexOf(id)].polyline;
    std::map<int, int> votes;
    for (double s = 0.0; s <= std::min(0.3, line.Length()); s += 0.005) {
      double d = 0.0, a = 0.0;
      const int m = Nearest(model, line.PointAt(s), &d, &a);
      if (m >= 0 && d <= 0.010 && cand_of.contains(model.canes[m].id.value)) ++votes[m];
    }
    int best = 0;
    std::optional<CaneId> out;
    for (const auto& [m, n] : votes) {
      if (n > best) {
        best = n;
        out = model.canes[m].id;
      }
    }
    return out;
  };
  decide::Scheme scheme;
  std::set<int64_t> used;
  for (CaneId id : truth_plan.keep) {
    auto m = map_one(id);
    if (m && used.insert(m->value).second) scheme.keep.push_back(*m);
  }
  for (CaneId id : truth_plan.spurs) {
    auto m = map_one(id);
    if (m && used.insert(m->value).second) scheme.spurs.push_back(*m);
  }
  std::sort(scheme.keep.begin(), scheme.keep.end());
  std::sort(scheme.spurs.begin(), scheme.spurs.end());
  // Ancestry: drop a kept cane or spur descending from another chosen one.
  auto chosen = [&](CaneId a) {
    return std::find(scheme.keep.begin(), scheme.keep.end(), a) != scheme.keep.end() ||
           std::find(scheme.spurs.begin(), scheme.spurs.end(), a) != scheme.spurs.end();
  };
  for (auto* list : {&scheme.keep, &scheme.spurs}) {
    std::vector<CaneId> kept;
    for (CaneId id : *list) {
      bool ok = true;
      for (CaneId a : candidates[cand_of[id.value]].ancestors) ok = ok && !chosen(a);
      if (ok) kept.push_back(id);
    }
    *list = kept;
  }
  return scheme;
}

}  // namespace vb::cutloss
