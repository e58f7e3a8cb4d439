// SPDX-License-Identifier: Apache-2.0
// The reconstruction stage: one stop's calibrated images -> a vine model in the platform frame
// (issue 3; docs/reconstruction.md). After Botterill et al., "A Robot System for Pruning Grape
// Vines" (J. Field Robotics 2017) sec. 3.2, adapted to a stop where all views are simultaneous:
//   1. segment each image (segmenter.h)             5. head and trunk by shape from silhouette
//   2. 2D structure per view (structure2d.h)           (head.h)
//   3. correspondence across views, Gibbs sampling  6. connect canes into one tree (connect.h)
//      and minimum expected loss (correspondence.h) 7. joint Ceres refinement (cane_fit.h)
//   4. assemble 3D pieces into canes (cane_assembly.h) 8. wires and posts (trellis3d.h)
//   2b. halves of the skeleton where two canes lie side by side, from the colour image
//       (strand_halves.h; off by default, s23), searched by 3's second pass
//   4e. canes found by a depth sweep along the skeleton paths no assembled cane explains
//       (depth_sweep.h; on by default since s20), before 4d
//   4d. the assembled canes' ends grown through junctions on two-view evidence (grow.h; on by
//       default), before 5
//   5b. the cane ends pointing at the head extended to it (head_bases.h; off by default)
//   7b. cane tips continued in one view (extend.h; on by default; "4c" in
//      docs/reconstruction.md, which numbers by its sections), after 7
//   9. the stretches of the canes given to step 6 that the model leaves out, as its obstacles
//      (left_out_wood.h: avoided by the planner, no cane)
// Between 3 and 4 the rig's rotations are refined on the confident matches and correspondence
// runs again with the refined rig (rig_refine.h).
// Steps 1-2 run per view on up to `threads` threads. Thread-safe (no shared state).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "core/image.h"
#include "core/vine_model.h"
#include "workers/reconstruct/cane_assembly.h"
#include "workers/reconstruct/cane_fit.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/depth_sweep.h"
#include "workers/reconstruct/extend.h"
#include "workers/reconstruct/fiducials.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/head_bases.h"
#include "workers/reconstruct/left_out_wood.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/rig_refine.h"
#include "workers/reconstruct/segmenter.h"
#include "workers/reconstruct/strand_halves.h"
#include "workers/reconstruct/structure2d.h"
#include "workers/reconstruct/trellis3d.h"

namespace vb::reconstruct {

struct ReconstructOptions {
  WorkingVolume volume;                  // structure outside it is rejected
  Structure2DOptions structure;
  // Halves of the skeleton where two canes lie side by side (strand_halves.h), found from the
  // colour images by Reconstruct (ReconstructFromViews takes the views as given) and searched by
  // the second pass of correspondence (correspondence.strand_halves).
  StrandHalfOptions strand_halves;
  CorrespondenceOptions correspondence;
  AssemblyOptions assembly;
  DepthSweepOptions sweep;               // step 4e: unexplained skeleton paths (depth_sweep.h)
  GrowOptions grow;                      // step 4d: assembled cane ends grown in >= 2 views (grow.h)
  HeadOptions head;
  HeadBasesOptions head_bases;           // after 5: cane ends extended to the head (head_bases.h)
  ConnectOptions connect;
  FitOptions fit;
  ExtendOptions extend;                  // step 4c: cane tips continued in one view (extend.h)
  TrellisOptions trellis;
  LeftOutWoodOptions left_out_wood;      // step 9: the seen wood the model leaves out
  RigRefineOptions rig_refine;           // step 3b: refine the rig on confident matches, re-match
  // Step 3's classifier for the first pass, with the rig as calibrated (correspondence.classifier
  // scores the second pass, with the refined rig).
  MatchClassifier first_pass_classifier = CalibratedRigMatchClassifier();
  FiducialDetectOptions fiducials;       // the platform's fiducials, for 3b (rig.fiducials)
  bool refine = true;                    // run the joint Ceres refinement (step 7)
  int threads = 2;                       // threads for the per-view steps

  absl::Status Validate() const;
};

// Wall-clock seconds per step (per-view steps: the wall time of all views together).
struct StageTimings {
  double segment_s = 0, structure_s = 0, correspondence_s = 0, assembly_s = 0, grow_s = 0,
         head_s = 0, connect_s = 0, refine_s = 0, extend_s = 0, rig_refine_s = 0, trellis_s = 0,
         total_s = 0;
  double sweep_s = 0;  // step 4e
};

struct ReconstructResult {
  VineModel model;
  StageTimings timings;
  std::string empty_reason;      // why the model has no canes ("" if it has some)
  int pieces = 0;                // 3D pieces from correspondence
  int assembled_canes = 0;       // canes after assembly
  GrowSummary grow;              // step 4d
  DepthSweepSummary sweep;       // step 4e
  HeadBasesSummary head_bases;   // after step 5 (head_bases.h)
  ConnectSummary connect;
  FitSummary fit;
  ExtendSummary extend;
  RigRefineSummary rig_refine;
  // Per camera: the platform's fiducials looked for and found (none when the rig lists none, or
  // fiducial detection or rig refinement is off).
  std::vector<FiducialDetectSummary> fiducials;
  // The rig the model was built with: the calibration, or its refinement (rig_refine.applied).
  RigCalibration rig;
};

// images[i] (rgb8) was taken by rig.cameras[i]. The fiducials of rig.fiducials are looked for in
// each image (fiducials.h) and refine the rig in step 3b. Errors, each naming the camera or field:
// INVALID_ARGUMENT for fewer than two cameras, an image count or size that disagrees with the
// calibration, a non-rgb8 image, an invalid calibration (NaN, singular), camera centres closer
// than 1 cm, invalid options; DEADLINE_EXCEEDED / CANCELLED when `deadline` passes (nothing is
// returned then). Images without wood give an OK result with an empty model and empty_reason.
absl::StatusOr<ReconstructResult> Reconstruct(const std::vector<Image>& images,
                                              const RigCalibration& rig,
                                              const SegmenterModel& segmenter,
                                              const ReconstructOptions& options,
                                              const Deadline& deadline);

// Step 3 with the rig refined in between (3b): a first correspondence pass with `calibrated_rig`,
// RefineRig on its confident pieces and on the trellis lines (MatchTrellisLines), and, when the
// rig changed, a second pass with the refined rig. What the later steps are given; the training
// and diagnosis tools call it to see what the pipeline sees. Errors as MatchSegments and
// RefineRig.
struct MatchedStop {
  std::vector<Piece3D> pieces;
  RigCalibration rig;             // the refined rig, or calibrated_rig when not applied
  RigRefineSummary rig_refine;
  // When rig_refine.applied: the views with their wire and post lines re-expressed for the
  // refined focal lengths (ReexpressLines); empty otherwise (use the input views).
  std::vector<View2D> refined_views;
};
absl::StatusOr<MatchedStop> MatchWithRigRefinement(const std::vector<View2D>& views,
                                                   const RigCalibration& calibrated_rig,
                                                   const ReconstructOptions& options,
                                                   const Deadline& deadline);

// Steps 3-8 from given views (for tests and benchmarks of the 3D stages on SyntheticViews).
absl::StatusOr<ReconstructResult> ReconstructFromViews(const std::vector<View2D>& views,
                                                       const RigCalibration& rig,
                                                       const ReconstructOptions& options,
                                                       const Deadline& deadline);

}  // namespace vb::reconstruct
