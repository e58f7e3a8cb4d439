// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/phenomics.h"

#include <cmath>
#include <string>

#include "gtest/gtest.h"

namespace vb::decide {
namespace {

Cane Straight(int64_t id, std::optional<int64_t> parent, CaneKind kind, Eigen::Vector3d base,
              Eigen::Vector3d dir, double length, double r0, double r1) {
  Cane c;
  c.id = CaneId(id);
  if (parent) c.parent_id = CaneId(*parent);
  c.kind = kind;
  const Eigen::Vector3d d = dir.normalized();
  c.polyline.points = {base, base + 0.5 * length * d, base + length * d};
  c.polyline.radii = {r0, 0.5 * (r0 + r1), r1};
  return c;
}

// Trunk 1 (1 m, diameter 40 mm at the ground to 20 mm at the head) under a head sphere of
// radius 0.05 m at z = 1.05; cane 2 (head, 6 mm, 0.8 m) along +x; cane 3 (head, 10 mm, 0.5 m)
// along -x; cane 4 (water shoot from the trunk at z = 0.5, 8 mm, 0.4 m); cane 5 (secondary, from
// cane 3 at 0.3 m along it, 6 mm, 0.3 m); an old spur 6.
VineModel Vine() {
  VineModel v;
  v.head.spheres.push_back({Eigen::Vector3d(0, 0, 1.05), 0.05});
  const CaneKind kCane = CaneKind::kCane;
  v.canes.push_back(
      Straight(1, std::nullopt, CaneKind::kTrunk, {0, 0, 0}, {0, 0, 1}, 1.0, 0.02, 0.01));
  v.canes.push_back(Straight(2, 1, kCane, {0.05, 0, 1.05}, {1, 0, 0}, 0.8, 0.003, 0.003));
  v.canes.push_back(Straight(3, 1, kCane, {-0.05, 0, 1.05}, {-1, 0, 0}, 0.5, 0.005, 0.005));
  v.canes.push_back(Straight(4, 1, kCane, {0, 0, 0.5}, {1, 0, 0.2}, 0.4, 0.004, 0.004));
  v.canes.push_back(Straight(5, 3, kCane, {-0.35, 0, 1.05}, {0, 0, 1}, 0.3, 0.003, 0.003));
  v.canes.push_back(
      Straight(6, 1, CaneKind::kSpur, {0, 0.05, 1.05}, {0, 1, 0.5}, 0.05, 0.004, 0.004));
  return v;
}

Cut MakeCut(int64_t id, int64_t cane, Eigen::Vector3d point, CutReason reason) {
  Cut c;
  c.id = CutId(id);
  c.cane_id = CaneId(cane);
  c.point = point;
  c.direction = Eigen::Vector3d::UnitX();
  c.diameter_m = 0.006;
  c.reason = reason;
  return c;
}

double Cylinder(double r, double length) { return M_PI * r * r * length; }

TEST(ComputePhenomics, CountsLengthsAndDiametersOfAHandBuiltVine) {
  auto p = ComputePhenomics(Vine(), nullptr);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_EQ(p->canes, 4);
  EXPECT_EQ(p->canes_from_head, 2);
  EXPECT_EQ(p->canes_from_trunk, 1);
  EXPECT_EQ(p->canes_from_cane, 1);
  EXPECT_EQ(p->old_spurs, 1);
  EXPECT_NEAR(p->cane_length_total_m, 2.0, 1e-9);
  EXPECT_NEAR(p->cane_length_mean_m, 0.5, 1e-9);
  // Diameters 6, 10, 8, 6 mm.
  EXPECT_NEAR(p->cane_diameter_mean_mm, 7.5, 1e-9);
  EXPECT_NEAR(p->cane_diameter_median_mm, 7.0, 1e-9);
  EXPECT_NEAR(p->cane_diameter_p10_mm, 6.0, 1e-9);
  EXPECT_NEAR(p->cane_diameter_p90_mm, 10.0 - 0.3 * 2.0, 1e-9);  // position 2.7 of {6, 6, 8, 10}
  EXPECT_EQ(p->cane_diameter_histogram.bin_mm, 1.0);
  EXPECT_NEAR(p->cane_diameter_histogram.first_bin_mm, 6.0, 1e-9);
  EXPECT_EQ(p->cane_diameter_histogram.counts, (std::vector<int>{2, 0, 1, 0, 1}));
  // Linear taper 40 -> 20 mm: the median over equal arc-length samples is the middle, 30 mm.
  EXPECT_NEAR(p->trunk_diameter_mm, 30.0, 1e-6);
  EXPECT_NEAR(p->trunk_length_m, 1.0, 1e-12);
  // A reconstruction's trunk that stops 0.4 m above the ground (the unseen part is an obstacle):
  // the gap counts as vertical trunk.
  VineModel cut = Vine();
  for (Cane& cane : cut.canes) {
    if (cane.kind != CaneKind::kTrunk) continue;
    cane.polyline.points = {{0, 0, 0.4}, {0, 0, 1}};
    cane.polyline.radii = {0.016, 0.01};
  }
  const auto q = ComputePhenomics(cut, nullptr);
  ASSERT_TRUE(q.ok()) << q.status();
  EXPECT_NEAR(q->trunk_length_m, 1.0, 1e-12);
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(0.05, 3);
  EXPECT_NEAR(p->head_volume_m3, sphere, 0.01 * sphere);
  EXPECT_FALSE(p->has_plan);
  EXPECT_EQ(p->pruning_weight_kg, 0.0);
  EXPECT_EQ(p->cuts_planned, 0);
}

TEST(ComputePhenomics, PruningWeightIsTheRemovedCylindersTimesDensity) {
  const VineModel vine = Vine();
  CutPlan plan;
  plan.keep = {CaneId(2)};
  // Cane 2 kept and shortened at 0.6 m; cane 4 removed 0.01 m from its base.
  plan.cuts = {MakeCut(1, 2, {0.65, 0, 1.05}, CutReason::kShorten),
               MakeCut(2, 4, vine.canes[3].polyline.PointAt(0.01), CutReason::kRemove)};
  auto p = ComputePhenomics(vine, &plan);
  ASSERT_TRUE(p.ok()) << p.status();
  const double removed = Cylinder(0.003, 0.2) + Cylinder(0.004, 0.39);
  EXPECT_NEAR(p->removed_wood_volume_m3, removed, 1e-12);
  EXPECT_NEAR(p->pruning_weight_kg, removed * kFreshCaneDensityKgM3, 1e-9);
  EXPECT_NEAR(p->kept_length_m, 0.6, 1e-9);
  EXPECT_EQ(p->kept_canes, 1);
  EXPECT_EQ(p->spurs, 0);
  EXPECT_EQ(p->cuts_planned, 2);
  EXPECT_EQ(p->cuts_shorten, 1);
  EXPECT_EQ(p->cuts_remove, 1);
  EXPECT_EQ(p->cuts_spur, 0);
  PhenomicsOptions heavy;
  heavy.fresh_density_kg_m3 = 1100;
  p = ComputePhenomics(vine, &plan, heavy);
  ASSERT_TRUE(p.ok());
  EXPECT_NEAR(p->pruning_weight_kg, removed * 1100, 1e-9);
}

TEST(ComputePhenomics, TaperedCaneVolumeIsAFrustum) {
  VineModel vine = Vine();
  vine.canes[3] = Straight(4, 1, CaneKind::kCane, {0, 0, 0.5}, {1, 0, 0}, 0.4, 0.006, 0.002);
  CutPlan plan;
  plan.cuts = {MakeCut(1, 4, {0, 0, 0.5}, CutReason::kRemove)};  // at the base: all of it goes
  auto p = ComputePhenomics(vine, &plan);
  ASSERT_TRUE(p.ok()) << p.status();
  const double frustum = M_PI * 0.4 * (0.006 * 0.006 + 0.006 * 0.002 + 0.002 * 0.002) / 3.0;
  EXPECT_NEAR(p->removed_wood_volume_m3, frustum, 1e-12);
}

TEST(ComputePhenomics, CanesGrowingBeyondACutFallWithIt) {
  const VineModel vine = Vine();
  // Cane 5 grows from cane 3 at 0.3 m along it.
  CutPlan before;
  before.cuts = {MakeCut(1, 3, {-0.25, 0, 1.05}, CutReason::kRemove)};  // 0.2 m: cane 5 falls
  auto p = ComputePhenomics(vine, &before);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_NEAR(p->removed_wood_volume_m3, Cylinder(0.005, 0.3) + Cylinder(0.003, 0.3), 1e-12);
  CutPlan beyond;
  beyond.cuts = {MakeCut(1, 3, {-0.45, 0, 1.05}, CutReason::kShorten)};  // 0.4 m: cane 5 stays
  p = ComputePhenomics(vine, &beyond);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_NEAR(p->removed_wood_volume_m3, Cylinder(0.005, 0.1), 1e-12);
  // A second cut on the fallen secondary is not counted twice.
  before.cuts.push_back(MakeCut(2, 5, {-0.35, 0, 1.15}, CutReason::kRemove));
  p = ComputePhenomics(vine, &before);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_NEAR(p->removed_wood_volume_m3, Cylinder(0.005, 0.3) + Cylinder(0.003, 0.3), 1e-12);
}

TEST(ComputePhenomics, RejectsMalformedModelsAndPlansNamingThem) {
  VineModel unknown_parent = Vine();
  unknown_parent.canes[2].parent_id = CaneId(77);
  auto p = ComputePhenomics(unknown_parent, nullptr);
  ASSERT_FALSE(p.ok());
  EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(p.status().message().find("model: canes[2]"), std::string_view::npos) << p.status();
  EXPECT_NE(p.status().message().find("parent_id"), std::string_view::npos) << p.status();

  VineModel nan_point = Vine();
  nan_point.canes[1].polyline.points[1].y() = std::nan("");
  p = ComputePhenomics(nan_point, nullptr);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("points[1]"), std::string_view::npos) << p.status();

  VineModel radii = Vine();
  radii.canes[1].polyline.radii.pop_back();
  p = ComputePhenomics(radii, nullptr);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("radii"), std::string_view::npos) << p.status();

  p = ComputePhenomics(VineModel{}, nullptr);
  ASSERT_FALSE(p.ok());
  EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(p.status().message().find("model: empty"), std::string_view::npos) << p.status();

  CutPlan plan;
  plan.cuts = {MakeCut(1, 42, {0, 0, 1}, CutReason::kRemove)};
  p = ComputePhenomics(Vine(), &plan);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("plan: "), std::string_view::npos) << p.status();

  PhenomicsOptions options;
  options.fresh_density_kg_m3 = 0;
  p = ComputePhenomics(Vine(), nullptr, options);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("fresh_density_kg_m3"), std::string_view::npos);
}

TEST(PhenomicsToJson, PlanFieldsAreNullWithoutAPlan) {
  auto p = ComputePhenomics(Vine(), nullptr);
  ASSERT_TRUE(p.ok()) << p.status();
  nlohmann::json j = PhenomicsToJson(*p);
  for (const char* key :
       {"canes", "canes_from_head", "canes_from_trunk", "canes_from_cane", "old_spurs",
        "cane_length_total_m", "cane_length_mean_m", "cane_diameter_mean_mm",
        "cane_diameter_median_mm", "cane_diameter_p10_mm", "cane_diameter_p90_mm",
        "cane_diameter_histogram", "trunk_diameter_mm", "head_volume_m3", "pruning_weight_kg",
        "kept_length_m", "cuts_planned", "cuts_by_reason", "fresh_density_kg_m3"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["pruning_weight_kg"].is_null());
  EXPECT_EQ(j["canes_from_trunk"], 1);
  CutPlan plan;
  plan.cuts = {MakeCut(1, 4, {0, 0, 0.5}, CutReason::kRemove)};
  p = ComputePhenomics(Vine(), &plan);
  ASSERT_TRUE(p.ok());
  j = PhenomicsToJson(*p);
  EXPECT_GT(j["pruning_weight_kg"].get<double>(), 0.0);
  EXPECT_EQ(j["cuts_by_reason"]["remove"], 1);
}

}  // namespace
}  // namespace vb::decide
