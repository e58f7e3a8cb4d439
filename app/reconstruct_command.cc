// SPDX-License-Identifier: Apache-2.0
#include <iostream>

#include "app/commands.h"
#include "app/reconstruct_flags.h"
#include "app/reconstruct_report.h"
#include "core/status_macros.h"
#include "core/vine_model_json.h"
#include "workers/capture/bundle.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::app {

absl::Status RunReconstruct(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string bundle_dir, flags.RequiredString("bundle"));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  VB_ASSIGN_OR_RETURN(const double deadline_s, flags.Double("deadline-s", 30.0));
  VB_ASSIGN_OR_RETURN(const std::string segmenter_path, flags.String("segmenter", ""));
  VB_ASSIGN_OR_RETURN(const int64_t threads, flags.Int("threads", 2));
  reconstruct::ReconstructOptions options;
  VB_RETURN_IF_ERROR(ReadSelectionFlags(flags, &options.correspondence));
  VB_RETURN_IF_ERROR(ReadStrandHalfFlags(flags, &options.strand_halves));  // step 2b
  VB_RETURN_IF_ERROR(ReadSweepFlags(flags, &options.sweep));
  VB_RETURN_IF_ERROR(ReadHeadFlags(flags, &options.head));
  VB_RETURN_IF_ERROR(ReadHeadBasesFlags(flags, &options.head_bases));
  // --extend-row, --extend-across, --extend-support, --extend-depth-sd (step 4c) and
  // --min-join-probability, --rescue-*, --keep-*, --drop-thickening (step 6).
  VB_RETURN_IF_ERROR(ReadExtendFlags(flags, &options.extend));
  VB_RETURN_IF_ERROR(ReadConnectFlags(flags, &options.connect));
  VB_RETURN_IF_ERROR(ReadHeadExitFlags(flags, &options.connect));  // --head-exit-* (step 6c)
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!(deadline_s > 0)) return absl::InvalidArgumentError("--deadline-s must be > 0");
  if (threads < 1 || threads > 64)
    return absl::InvalidArgumentError("--threads must be in [1, 64]");

  reconstruct::SegmenterModel segmenter = reconstruct::BuiltinSegmenterModel();
  if (!segmenter_path.empty()) {
    VB_ASSIGN_OR_RETURN(segmenter, reconstruct::ReadSegmenterModel(segmenter_path));
  }
  const Deadline deadline = Deadline::In(deadline_s);
  VB_ASSIGN_OR_RETURN(const capture::CaptureBundle bundle, capture::ReadBundle(bundle_dir));
  RigCalibration rig;
  std::vector<Image> images;
  for (size_t i = 0; i < bundle.images.size(); ++i) {
    rig.cameras.push_back(bundle.CalibrationOf(i));
    VB_ASSIGN_OR_RETURN(Image rgb, capture::ToRgb(bundle.images[i]));
    images.push_back(std::move(rgb));
  }
  rig.fiducials = bundle.calibration.fiducials;  // the platform's, if the bundle lists any
  options.threads = static_cast<int>(threads);
  VB_ASSIGN_OR_RETURN(const reconstruct::ReconstructResult result,
                      reconstruct::Reconstruct(images, rig, segmenter, options, deadline));
  VB_RETURN_IF_ERROR(WriteVineModel(out, result.model));
  nlohmann::json report = ReconstructReport(result);
  report["model"] = out;
  std::cout << report.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
