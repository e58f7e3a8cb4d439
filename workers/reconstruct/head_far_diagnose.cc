// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head_far_diagnose.h"

#include <algorithm>
#include <cstdio>

#include "workers/reconstruct/connect_internal.h"
#include "workers/reconstruct/diagnose_util.h"
#include "workers/reconstruct/join_test_util.h"

namespace vb::reconstruct {
namespace {

constexpr double kBinUpper[HeadFarTally::kBins] = {0.15, 0.25, 0.40, 1e9};
const char* const kBinNames[HeadFarTally::kBins] = {"< 15 cm", "15-25 cm", "25-40 cm",
                                                    "> 40 cm"};
const char* const kClassNames[kHungClassCount] = {"head cane, wrong route", "head cane, right",
                                                  "cane of cane, right", "cane of cane, wrong",
                                                  "ghost"};

bool InAncestry(const VineModel& truth, int g, int x) {
  for (int at = g, hops = 0; at >= 0 && hops <= static_cast<int>(truth.canes.size()); ++hops) {
    if (at == x) return true;
    at = TrueParent(truth, at);
  }
  return false;
}

}  // namespace

int HeadFarBin(double distance_m) {
  for (int b = 0; b < HeadFarTally::kBins; ++b)
    if (distance_m < kBinUpper[b]) return b;
  return HeadFarTally::kBins - 1;
}

InnerEnd InnerEndToHead(const Polyline3& line, const HeadModel& head) {
  Eigen::Vector3d at_front, at_back;
  const double d_front = connect_internal::DistanceToHead(line.points.front(), head, &at_front);
  const double d_back = connect_internal::DistanceToHead(line.points.back(), head, &at_back);
  InnerEnd end;
  end.last = d_back < d_front;
  end.distance_m = std::min(d_front, d_back);
  const Eigen::Vector3d inner = end.last ? line.points.back() : line.points.front();
  const Eigen::Vector3d to_head = (end.last ? at_back : at_front) - inner;
  if (end.distance_m > 0.0 && to_head.norm() >= 1e-9)
    end.cos = connect_internal::EndOutward(line, end.last).dot(to_head.normalized());
  return end;
}

void HeadFarTally::Add(const VineModel& connected, const PreparedCanes& prepared,
                       const std::vector<JoinCandidate>& joins, const VineModel& truth,
                       std::FILE* csv, uint64_t seed) {
  if (connected.head.spheres.empty()) return;
  const size_t n = connected.canes.size();
  std::vector<int> majority(n, -1);
  for (size_t m = 0; m < n; ++m) majority[m] = MajorityCane(connected.canes[m].polyline, truth);
  // The prepared canes each model cane holds.
  std::vector<std::vector<int>> held(n);
  for (size_t m = 0; m < n; ++m)
    for (size_t i = 0; i < prepared.canes.size(); ++i)
      if (HoldsEnds(prepared.canes[i], connected.canes[m].polyline))
        held[m].push_back(static_cast<int>(i));
  for (size_t m = 0; m < n; ++m) {
    const Cane& cane = connected.canes[m];
    if (!cane.parent_id || cane.polyline.points.size() < 2) continue;
    const size_t parent = *connected.IndexOf(*cane.parent_id);
    if (connected.canes[parent].kind == CaneKind::kTrunk) continue;  // on the trunk or head
    // The cane as seen: a first point drawn onto the parent (a bridge) is dropped.
    Polyline3 seen = cane.polyline;
    if (seen.points.size() > 2 &&
        DistanceToPolyline(seen.points[0], connected.canes[parent].polyline) < 1e-3) {
      seen.points.erase(seen.points.begin());
      seen.radii.erase(seen.radii.begin());
    }
    const InnerEnd end = InnerEndToHead(seen, connected.head);
    const bool last = end.last;
    const double d = end.distance_m, cos = end.cos;
    // The join that hangs it: from the prepared cane holding its base to one its parent holds.
    int child = -1;
    double child_d = 1e9;
    for (int i : held[m]) {
      const Polyline3& p = prepared.canes[i];
      const double e = std::min((p.points.front() - seen.points.front()).norm(),
                                (p.points.back() - seen.points.front()).norm());
      if (e < child_d) child_d = e, child = i;
    }
    double probability = -1;
    for (const JoinCandidate& j : joins)
      if (j.child == child && j.parent >= 0 &&
          std::find(held[parent].begin(), held[parent].end(), j.parent) != held[parent].end())
        probability = std::max(probability, j.probability);
    // What it is.
    const int g = majority[m];
    HungClass cls = kGhostHung;
    if (g >= 0) {
      bool right = true;
      for (size_t at = parent, hops = 0; hops <= n; ++hops) {
        if (connected.canes[at].kind == CaneKind::kTrunk) break;
        if (!InAncestry(truth, g, majority[at])) {
          right = false;
          break;
        }
        if (!connected.canes[at].parent_id) break;
        at = *connected.IndexOf(*connected.canes[at].parent_id);
      }
      const bool of_head = TrueParent(truth, g) == 0;
      cls = of_head ? (right ? kHeadRight : kHeadWrong) : (right ? kCaneRight : kCaneWrong);
    }
    Cell& cell = cells_[HeadFarBin(d)][cls];
    const double length = seen.Length();
    cell.all += length;
    if (cos >= 0.8) {
      cell.pointing += length;
      cell.p_weighted += std::max(0.0, probability) * length;
      if (probability < 0.5) cell.pointing_unlikely += length;
    }
    if (cos >= 0.9) cell.pointing_09 += length;
    if (csv) {
      const Polyline3& par = connected.canes[parent].polyline;
      const double s_join = par.Project(cane.polyline.points.front());
      const double base_len = std::min(0.03, length);
      const double r_inner = last ? connect_internal::MeanRadius(seen, length - base_len, length)
                                  : connect_internal::MeanRadius(seen, 0.0, base_len);
      const double along = std::abs(
          connect_internal::EndOutward(seen, false).dot(par.TangentAt(s_join)));
      const size_t grand = connected.canes[parent].parent_id
                               ? *connected.IndexOf(*connected.canes[parent].parent_id)
                               : parent;
      std::fprintf(csv, "%llu,%d,%.4f,%.4f,%.3f,%.3f,%.5f,%.5f,%.3f,%d\n",
                   static_cast<unsigned long long>(seed), static_cast<int>(cls), length, d, cos,
                   probability, r_inner, par.RadiusAt(s_join), along,
                   connected.canes[grand].kind == CaneKind::kTrunk ? 1 : 0);
    }
  }
}

void HeadFarTally::Print() const {
  std::printf("canes hung on another cane, by their inner end's distance from the model head "
              "(m of cane: all / pointing at the head, cos >= 0.8 / cos >= 0.9 / pointing, join "
              "p < 0.5; mean join p of the pointing)\n");
  for (int c = 0; c < kHungClassCount; ++c) {
    std::printf("  %s\n", kClassNames[c]);
    for (int b = 0; b < kBins; ++b) {
      const Cell& x = cells_[b][c];
      std::printf("    %-9s %6.2f / %6.2f / %6.2f / %6.2f; p %.2f\n", kBinNames[b], x.all,
                  x.pointing, x.pointing_09, x.pointing_unlikely,
                  x.pointing > 0 ? x.p_weighted / x.pointing : 0.0);
    }
  }
}

}  // namespace vb::reconstruct
