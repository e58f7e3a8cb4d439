// SPDX-License-Identifier: Apache-2.0
// Diagnosis support, not part of the stage (docs/reconstruction.md, step 6, "Head joins that
// reach farther (s22)"): what a head join reaching beyond max_attach_m would take. Every cane a
// tree hangs on another cane (not the trunk or head), by how far its inner end (the end nearer
// the model head's spheres, a bridge point onto its parent skipped) lies from their surface,
// whether that end points at the head (the cosine between its outward tangent and the direction
// to the nearest surface point: connect.h step 6c's test), the probability of the join that
// hangs it, and what it is in the truth. Used by PipelineStages.DISABLED_Report with
// VB_HEAD_FAR=1 (pipeline_diagnose_test.cc). Diagnosis only; deterministic.
#pragma once

#include <cstdint>
#include <cstdio>
#include <vector>

#include "core/vine_model.h"
#include "workers/reconstruct/connect.h"

namespace vb::reconstruct {

// The classes of a hung cane (its majority true cane, MajorityCane): a cane of the head (true
// parent the trunk) or of another cane, on the right route (every model cane down to the trunk
// reconstructs one of its true ancestors or itself) or a wrong one; or a ghost (no true cane).
enum HungClass {
  kHeadWrong,
  kHeadRight,
  kCaneRight,
  kCaneWrong,
  kGhostHung,
  kHungClassCount
};

class HeadFarTally {
 public:
  static constexpr int kBins = 4;  // inner end from the head: < 15, 15-25, 25-40, > 40 cm

  // One stop's tree `connected` (BuildTree's, from `prepared` and `joins`; its head is the model
  // head) against `truth`.
  // With `csv` (an open file), one line per hung cane: seed, class, length, distance, cosine,
  // join probability, its mean radius over 3 cm at the inner end, the parent's radius at the
  // join, |cos| of the angle between the child's base tangent and the parent's there, whether
  // the parent hangs on the trunk or head itself.
  void Add(const VineModel& connected, const PreparedCanes& prepared,
           const std::vector<JoinCandidate>& joins, const VineModel& truth,
           std::FILE* csv = nullptr, uint64_t seed = 0);
  // The table (metres of hung cane, summed over the stops added).
  void Print() const;

  // Metres of hung cane in `bin` of `cls`: all, pointing (cos >= 0.8), pointing with cos >= 0.9,
  // pointing hung by a join less likely than 0.5; and the sum of the pointing canes' join
  // probabilities times their length (for the length-weighted mean).
  struct Cell {
    double all = 0, pointing = 0, pointing_09 = 0, pointing_unlikely = 0, p_weighted = 0;
  };
  const Cell& At(int bin, HungClass cls) const { return cells_[bin][cls]; }

 private:
  Cell cells_[kBins][kHungClassCount];
};

// The bin of HeadFarTally a distance from the head's surface falls in.
int HeadFarBin(double distance_m);

// The end of `line` nearer the surface of `head`'s spheres (which must not be empty): whether it
// is the last point, its signed distance from that surface, and the cosine between the line's
// outward tangent there (EndOutward) and the direction to the nearest surface point (1 inside).
struct InnerEnd {
  bool last = false;
  double distance_m = 0;
  double cos = 1;
};
InnerEnd InnerEndToHead(const Polyline3& line, const HeadModel& head);

}  // namespace vb::reconstruct
