// SPDX-License-Identifier: Apache-2.0
#include "app/reconstruct_report.h"

namespace vb::app {

nlohmann::json TimingsToJson(const reconstruct::StageTimings& t) {
  return {{"segment_s", t.segment_s},       {"structure_s", t.structure_s},
          {"correspondence_s", t.correspondence_s}, {"rig_refine_s", t.rig_refine_s},
          {"assembly_s", t.assembly_s},     {"grow_s", t.grow_s},
          {"head_s", t.head_s},             {"connect_s", t.connect_s},
          {"refine_s", t.refine_s},         {"extend_s", t.extend_s},
          {"trellis_s", t.trellis_s},       {"sweep_s", t.sweep_s},
          {"total_s", t.total_s}};
}

nlohmann::json ReconstructReport(const reconstruct::ReconstructResult& result) {
  int canes = 0, spurs = 0;
  for (const Cane& c : result.model.canes) {
    canes += c.kind == CaneKind::kCane;
    spurs += c.kind == CaneKind::kSpur;
  }
  double obstacle_length_m = 0.0;
  for (const WoodObstacle& o : result.model.obstacles) obstacle_length_m += o.polyline.Length();
  nlohmann::json report = {
      {"canes", canes},
      {"spurs", spurs},
      {"trunk", !result.model.canes.empty()},
      {"head_spheres", result.model.head.spheres.size()},
      {"wires", result.model.wires.size()},
      {"posts", result.model.posts.size()},
      {"pieces", result.pieces},
      {"assembled_canes", result.assembled_canes},
      // Step 4d (grow.h): cane ends grown and the length added.
      {"grown_ends", result.grow.ends_grown},
      {"grown_length_m", result.grow.added_length_m},
      {"unattached_canes", result.connect.unattached},
      // The seen wood the model leaves out, carried for the planner (left_out_wood.h).
      {"obstacles", result.model.obstacles.size()},
      {"obstacle_length_m", obstacle_length_m},
      {"rejected_canes", result.fit.rejected_outside + result.fit.rejected_background +
                             result.fit.removed_with_parent},
      {"timings", TimingsToJson(result.timings)}};
  const reconstruct::RigRefineSummary& rr = result.rig_refine;
  report["rig_refine"] = {{"applied", rr.applied},
                          {"points", rr.points},
                          {"median_before_px", rr.median_before_px},
                          {"median_after_px", rr.median_after_px},
                          {"trellis_lines", rr.trellis_lines},
                          {"trellis_rejected", rr.trellis_rejected},
                          {"trellis_rms_before_px", rr.trellis_rms_before_px},
                          {"trellis_rms_after_px", rr.trellis_rms_after_px},
                          {"correction_px", rr.correction_px}};
  if (!rr.reason.empty()) report["rig_refine"]["reason"] = rr.reason;
  if (!result.fiducials.empty()) {
    nlohmann::json cameras = nlohmann::json::array();
    for (size_t c = 0; c < result.fiducials.size(); ++c) {
      const reconstruct::FiducialDetectSummary& f = result.fiducials[c];
      cameras.push_back({{"camera", c < result.rig.cameras.size() ? result.rig.cameras[c].name : ""},
                         {"looked_for", f.looked_for},
                         {"found", f.found},
                         {"missed", f.missed}});
    }
    report["rig_refine"]["fiducials"] = {{"cameras", cameras},
                                         {"observations", rr.fiducial_observations},
                                         {"rejected", rr.fiducials_rejected},
                                         {"rms_before_px", rr.fiducial_rms_before_px},
                                         {"rms_after_px", rr.fiducial_rms_after_px},
                                         {"log", rr.fiducial_log}};
  }
  if (!result.empty_reason.empty()) report["empty_reason"] = result.empty_reason;
  return report;
}

}  // namespace vb::app
