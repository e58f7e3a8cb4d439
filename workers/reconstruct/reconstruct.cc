// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/reconstruct.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/join_images.h"

namespace vb::reconstruct {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Runs fn(i) for i in [0, n) on up to `threads` threads; returns the first error.
template <typename Fn>
absl::Status ParallelFor(int n, int threads, Fn fn) {
  std::vector<absl::Status> status(n);
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i = next++; i < n; i = next++) status[i] = fn(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min(threads, n); ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  for (const absl::Status& s : status)
    if (!s.ok()) return s;
  return absl::OkStatus();
}

absl::Status CheckRig(const RigCalibration& rig) {
  if (rig.cameras.size() < 2) {
    return absl::InvalidArgumentError(absl::StrCat(
        "reconstruction needs images from at least two cameras, the stop has ", rig.cameras.size(),
        rig.cameras.size() == 1 ? " (" + rig.cameras[0].name + ")" : std::string()));
  }
  VB_RETURN_IF_ERROR(rig.Validate());
  for (size_t a = 0; a < rig.cameras.size(); ++a)
    for (size_t b = a + 1; b < rig.cameras.size(); ++b) {
      const double baseline =
          (rig.cameras[a].CentreInPlatform() - rig.cameras[b].CentreInPlatform()).norm();
      if (!(baseline >= 0.01)) {
        return absl::InvalidArgumentError(
            absl::StrCat("cameras ", rig.cameras[a].name, " and ", rig.cameras[b].name,
                         " are coincident (baseline ", baseline, " m): no depth can be measured"));
      }
    }
  return absl::OkStatus();
}

// Step 3's options for the first pass, with the rig as calibrated.
CorrespondenceOptions FirstPassOptions(const ReconstructOptions& options) {
  CorrespondenceOptions first = options.correspondence;
  first.classifier = options.first_pass_classifier;
  // The first pass's pieces refine the rig against every view: fitting them to the other views
  // with the rig as calibrated first hides the very errors the refinement measures (rig error
  // 0.24 -> 0.30 px on tuning seeds 1100-1129).
  first.other_views.rounds = 0;
  // Nor are the strand halves searched there: their pieces are the less certain ones, and the
  // halves were measured with the rig refined from the views' own segments.
  first.strand_halves = false;
  return first;
}

// MatchWithRigRefinement after validation; `first_pass`, if given, is the first pass's result
// (the caller timed it separately) and is moved from.
absl::StatusOr<MatchedStop> MatchAndRefine(const std::vector<View2D>& views,
                                           const RigCalibration& calibrated_rig,
                                           const ReconstructOptions& options,
                                           const Deadline& deadline,
                                           std::vector<Piece3D>* first_pass) {
  std::vector<Piece3D> computed;
  if (first_pass == nullptr) {
    VB_ASSIGN_OR_RETURN(computed,
                        MatchSegments(views, calibrated_rig, FirstPassOptions(options), deadline));
    first_pass = &computed;
  }
  MatchedStop out;
  std::vector<TrellisLineMatch> trellis_lines;
  if (options.rig_refine.enabled && options.rig_refine.use_trellis) {
    TrellisOptions match_options = options.trellis;
    match_options.max_residual_px = options.rig_refine.trellis_match_residual_px;
    VB_ASSIGN_OR_RETURN(trellis_lines,
                        MatchTrellisLines(views, calibrated_rig, options.volume, match_options));
  }
  VB_ASSIGN_OR_RETURN(out.rig, RefineRig(views, calibrated_rig, *first_pass, trellis_lines,
                                         options.rig_refine, deadline, &out.rig_refine));
  if (!out.rig_refine.applied) {
    out.pieces = std::move(*first_pass);
    return out;
  }
  // Wire and post lines are in normalised coordinates, which a new focal length changes.
  out.refined_views = views;
  for (size_t v = 0; v < views.size(); ++v) {
    ReexpressLines(calibrated_rig.cameras[v], out.rig.cameras[v], &out.refined_views[v].wires);
    ReexpressLines(calibrated_rig.cameras[v], out.rig.cameras[v], &out.refined_views[v].posts);
  }
  VB_ASSIGN_OR_RETURN(out.pieces, MatchSegments(views, out.rig, options.correspondence, deadline));
  return out;
}

}  // namespace

absl::Status ReconstructOptions::Validate() const {
  if (volume.box.isEmpty()) return absl::InvalidArgumentError("options.volume: empty box");
  VB_RETURN_IF_ERROR(structure.Validate());
  VB_RETURN_IF_ERROR(correspondence.Validate());
  if (absl::Status s = first_pass_classifier.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.first_pass_classifier: ", s.message()));
  }
  VB_RETURN_IF_ERROR(assembly.Validate());
  VB_RETURN_IF_ERROR(sweep.Validate());
  VB_RETURN_IF_ERROR(grow.Validate());
  VB_RETURN_IF_ERROR(head.Validate());
  VB_RETURN_IF_ERROR(head_bases.Validate());
  VB_RETURN_IF_ERROR(connect.Validate());
  VB_RETURN_IF_ERROR(fit.Validate());
  VB_RETURN_IF_ERROR(extend.Validate());
  VB_RETURN_IF_ERROR(trellis.Validate());
  if (absl::Status s = strand_halves.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("strand_halves.", s.message()));
  }
  VB_RETURN_IF_ERROR(left_out_wood.Validate());
  VB_RETURN_IF_ERROR(fiducials.Validate());
  if (threads < 1) return absl::InvalidArgumentError("options.threads must be >= 1");
  return absl::OkStatus();
}

absl::StatusOr<MatchedStop> MatchWithRigRefinement(const std::vector<View2D>& views,
                                                   const RigCalibration& calibrated_rig,
                                                   const ReconstructOptions& options,
                                                   const Deadline& deadline) {
  VB_RETURN_IF_ERROR(options.Validate());
  VB_RETURN_IF_ERROR(CheckRig(calibrated_rig));
  return MatchAndRefine(views, calibrated_rig, options, deadline, nullptr);
}

absl::StatusOr<ReconstructResult> ReconstructFromViews(const std::vector<View2D>& views,
                                                       const RigCalibration& calibrated_rig,
                                                       const ReconstructOptions& options,
                                                       const Deadline& deadline) {
  VB_RETURN_IF_ERROR(options.Validate());
  VB_RETURN_IF_ERROR(CheckRig(calibrated_rig));
  ReconstructResult result;
  auto t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(std::vector<Piece3D> pieces,
                      MatchSegments(views, calibrated_rig, FirstPassOptions(options), deadline));
  result.timings.correspondence_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(MatchedStop matched,
                      MatchAndRefine(views, calibrated_rig, options, deadline, &pieces));
  std::vector<View2D> refined_views = std::move(matched.refined_views);
  pieces = std::move(matched.pieces);
  result.rig = std::move(matched.rig);
  result.rig_refine = std::move(matched.rig_refine);
  result.pieces = static_cast<int>(pieces.size());
  result.timings.rig_refine_s = SecondsSince(t);
  const RigCalibration& rig = result.rig;

  t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(std::vector<Polyline3> canes,
                      AssembleCanes(pieces, options.assembly, deadline));
  std::erase_if(canes,
                [&](const Polyline3& cane) { return options.volume.MostlyOutside(cane); });
  result.assembled_canes = static_cast<int>(canes.size());
  result.timings.assembly_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  VB_RETURN_IF_ERROR(SweepUnexplainedPaths(views, rig, options.volume, options.sweep, deadline,
                                           &canes, &result.sweep));
  result.timings.sweep_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  if (!options.grow.after_connection) {
    VB_RETURN_IF_ERROR(
        GrowCaneEnds(views, rig, options.volume, options.grow, &canes, &result.grow));
  }
  result.timings.grow_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> depth_hints;
  for (const Polyline3& cane : canes)
    depth_hints.insert(depth_hints.end(), cane.points.begin(), cane.points.end());
  VB_ASSIGN_OR_RETURN(const HeadAndTrunk head,
                      ReconstructHeadAndTrunk(views, rig, options.volume, options.head, deadline,
                                              depth_hints));
  // The bases run to the model's head (the tight spheres when leaf_radius_fraction < 1; connect
  // below is given them grown back): measured so, docs/reconstruction.md step 5 (s19).
  VB_RETURN_IF_ERROR(
      ExtendBasesToHead(views, rig, head.head, options.head_bases, &canes, &result.head_bases));
  result.timings.head_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  // Seen gaps (connect.h): a base whose gap to its parent is wood in every view is drawn on it.
  const GapSupportFn gap_support = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return GapSupport(a, b, views, rig);
  };
  // The join classifier's image features (join_images.h), if its weights use them.
  const JoinImageFn join_images = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return MeasureJoinImages(a, b, views, rig);
  };
  // Tight leaves (HeadOptions::leaf_radius_fraction < 1) leave some smallest cubes out of the
  // head; connection is given every sphere grown by the reach the tight test gives up, (1 -
  // fraction) of a smallest cube's bounding radius, an approximation of the loose head its joins
  // were trained on (it grows the kept spheres rather than restoring the dropped leaves), and the
  // model keeps the tight ones (docs/reconstruction.md step 5, s19).
  HeadModel connect_head = head.head;
  const double grow_m = (1.0 - options.head.leaf_radius_fraction) * 0.5 * std::sqrt(3.0) *
                        options.head.min_cell_m;
  if (grow_m > 0.0) {
    for (Sphere& sphere : connect_head.spheres) sphere.radius += grow_m;
  }
  VB_ASSIGN_OR_RETURN(result.model, ConnectCanes(canes, head.trunk, connect_head, options.connect,
                                                 &result.connect, gap_support, join_images));
  if (grow_m > 0.0) result.model.head = head.head;
  result.timings.connect_s = SecondsSince(t);

  if (options.grow.after_connection) {  // step 4d on the tree: tips only (bases are pinned)
    t = std::chrono::steady_clock::now();
    std::vector<Polyline3> lines;
    for (const Cane& cane : result.model.canes) lines.push_back(cane.polyline);
    VB_RETURN_IF_ERROR(GrowCaneEnds(views, rig, options.volume, options.grow, &lines,
                                    &result.grow, /*tips_only=*/true));
    // Only canes take their growth: the trunk and old spurs stay as connection left them (they
    // were passed so that growth does not run along them).
    for (size_t i = 0; i < lines.size(); ++i) {
      if (result.model.canes[i].kind == CaneKind::kCane) result.model.canes[i].polyline = lines[i];
    }
    result.timings.grow_s += SecondsSince(t);
  }

  if (options.refine && !result.model.canes.empty()) {
    t = std::chrono::steady_clock::now();
    VB_RETURN_IF_ERROR(
        RefineModel(&result.model, views, rig, options.fit, deadline, &result.fit));
    result.timings.refine_s = SecondsSince(t);
  }
  t = std::chrono::steady_clock::now();
  VB_RETURN_IF_ERROR(
      ExtendCanes(views, rig, options.volume, options.extend, &result.model, &result.extend));
  result.timings.extend_s = SecondsSince(t);

  t = std::chrono::steady_clock::now();
  VB_ASSIGN_OR_RETURN(const Trellis trellis,
                      ReconstructTrellis(refined_views.empty() ? views : refined_views, rig,
                                         options.volume, options.trellis));
  result.model.wires = trellis.wires;
  result.model.posts = trellis.posts;
  result.timings.trellis_s = SecondsSince(t);

  // Step 9: what connect was given and the model does not hold is wood the cameras saw and the
  // arm must still avoid; the model's canes, and so every metric, stay as they are. (The
  // obstacles already hold the trunk below the images, cane_fit.h.)
  VB_ASSIGN_OR_RETURN(std::vector<WoodObstacle> left_out,
                      LeftOutWood(canes, result.model, options.left_out_wood));
  result.model.obstacles.insert(result.model.obstacles.end(), left_out.begin(), left_out.end());

  if (result.model.canes.empty()) {
    result.empty_reason = pieces.empty() ? "no cane was matched across the views"
                                         : "no cane connects to a trunk or head";
  }
  VB_RETURN_IF_ERROR(result.model.Validate());
  return result;
}

absl::StatusOr<ReconstructResult> Reconstruct(const std::vector<Image>& images,
                                              const RigCalibration& rig,
                                              const SegmenterModel& segmenter,
                                              const ReconstructOptions& options,
                                              const Deadline& deadline) {
  const auto start = std::chrono::steady_clock::now();
  VB_RETURN_IF_ERROR(options.Validate());
  VB_RETURN_IF_ERROR(CheckRig(rig));
  if (images.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat(images.size(), " images for ",
                                                   rig.cameras.size(), " calibrated cameras"));
  }
  for (size_t i = 0; i < images.size(); ++i) {
    const CameraCalibration& camera = rig.cameras[i];
    if (images[i].format != PixelFormat::kRgb8) {
      return absl::InvalidArgumentError(absl::StrCat(
          camera.name, ": image must be rgb8 (demosaic first), is ",
          std::string(PixelFormatName(images[i].format))));
    }
    if (images[i].width != camera.image_width || images[i].height != camera.image_height) {
      return absl::InvalidArgumentError(absl::StrCat(
          camera.name, ": image is ", images[i].width, "x", images[i].height,
          " but the calibration says ", camera.image_width, "x", camera.image_height));
    }
  }

  const int n = static_cast<int>(images.size());
  std::vector<ClassImage> classes(n);
  std::vector<View2D> views(n);
  std::vector<double> segment_s(n, 0.0), structure_s(n, 0.0);
  const bool find_fiducials = options.fiducials.enabled && options.rig_refine.enabled &&
                              options.rig_refine.use_fiducials && !rig.fiducials.empty();
  std::vector<FiducialDetectSummary> fiducials(find_fiducials ? n : 0);
  VB_RETURN_IF_ERROR(ParallelFor(n, options.threads, [&](int i) -> absl::Status {
    VB_RETURN_IF_ERROR(deadline.Check("reconstruct"));
    auto t = std::chrono::steady_clock::now();
    VB_ASSIGN_OR_RETURN(classes[i], Segment(images[i], segmenter));
    segment_s[i] = SecondsSince(t);
    t = std::chrono::steady_clock::now();
    std::vector<FiducialObservation> found;
    if (find_fiducials) {
      VB_ASSIGN_OR_RETURN(found, DetectFiducials(images[i], rig.cameras[i], rig.fiducials,
                                                 options.fiducials, &fiducials[i]));
      ClearFiducials(found, rig.cameras[i], rig.fiducials, &classes[i]);  // not wood
    }
    VB_ASSIGN_OR_RETURN(views[i],
                        ExtractStructure(classes[i], rig.cameras[i], options.structure, deadline));
    views[i].fiducials = std::move(found);
    VB_ASSIGN_OR_RETURN(views[i].strand_halves,
                        FindStrandHalves(views[i], images[i], options.strand_halves));
    structure_s[i] = SecondsSince(t);
    return absl::OkStatus();
  }));
  // Per-view steps ran side by side: report their share of the wall time.
  const double per_view_wall = SecondsSince(start);
  double seg = 0, str = 0;
  for (int i = 0; i < n; ++i) {
    seg += segment_s[i];
    str += structure_s[i];
  }
  const double scale = seg + str > 0 ? per_view_wall / (seg + str) : 0.0;

  bool any_wood = false;
  for (const View2D& view : views) any_wood = any_wood || !view.segments.empty();
  ReconstructResult result;
  if (any_wood) {
    VB_ASSIGN_OR_RETURN(result, ReconstructFromViews(views, rig, options, deadline));
  } else {
    result.empty_reason = "no wood (cane, trunk or head) was found in any image";
    result.rig = rig;
  }
  result.fiducials = std::move(fiducials);
  result.timings.segment_s = seg * scale;
  result.timings.structure_s = str * scale;
  result.timings.total_s = SecondsSince(start);
  return result;
}

}  // namespace vb::reconstruct
