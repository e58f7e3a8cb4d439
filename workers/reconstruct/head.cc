// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/head.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/head_carve.h"

namespace vb::reconstruct {
namespace {

using head_internal::Carver;
using head_internal::Cube;
using head_internal::CubeVerdict;
using head_internal::LabelLargestComponent;
using head_internal::VoxelGrid;

// The upper of the two middle values for an even count (core's Median, core/statistics.h, takes
// their mean: tried in s19, it changed 3 of tuning stops 1100-1129, so the head keeps this one).
double UpperMedian(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

absl::Status HeadOptions::Validate() const {
  auto positive = [](double v, const char* name) -> absl::Status {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("head options: ", name, " must be > 0"));
    return absl::OkStatus();
  };
  for (auto [v, name] : {std::pair{coarse_cell_m, "coarse_cell_m"}, {min_cell_m, "min_cell_m"},
                         {slab_m, "slab_m"}, {head_width_factor, "head_width_factor"},
                         {head_min_height_m, "head_min_height_m"},
                         {peel_cane_radius_m, "peel_cane_radius_m"}, {peel_link_m, "peel_link_m"},
                         {head_depth_factor, "head_depth_factor"}}) {
    if (absl::Status s = positive(v, name); !s.ok()) return s;
  }
  if (min_cell_m > coarse_cell_m)
    return absl::InvalidArgumentError("head options: min_cell_m must be <= coarse_cell_m");
  if (!std::isfinite(silhouette_margin_px) || silhouette_margin_px < 0)
    return absl::InvalidArgumentError("head options: silhouette_margin_px must be >= 0");
  if (!std::isfinite(depth_margin_m) || depth_margin_m < 0)
    return absl::InvalidArgumentError("head options: depth_margin_m must be >= 0");
  if (!std::isfinite(peel_depth_px) || peel_depth_px < 0)
    return absl::InvalidArgumentError("head options: peel_depth_px must be >= 0");
  if (!std::isfinite(leaf_radius_fraction) || leaf_radius_fraction < 0 ||
      leaf_radius_fraction > 1) {
    return absl::InvalidArgumentError("head options: leaf_radius_fraction must be in [0, 1]");
  }
  if (!std::isfinite(leaf_wood_radius_px) || leaf_wood_radius_px < 0)
    return absl::InvalidArgumentError("head options: leaf_wood_radius_px must be >= 0");
  if (foreground_reach_px < 0 || foreground_reach_px > 100)
    return absl::InvalidArgumentError("head options: foreground_reach_px must be in [0, 100]");
  if (foreground_reach_max_views < 1)
    return absl::InvalidArgumentError("head options: foreground_reach_max_views must be >= 1");
  if (min_views < 1) return absl::InvalidArgumentError("head options: min_views must be >= 1");
  return absl::OkStatus();
}

absl::StatusOr<HeadAndTrunk> ReconstructHeadAndTrunk(
    const std::vector<View2D>& views, const RigCalibration& rig, const WorkingVolume& volume,
    const HeadOptions& options, const Deadline& deadline,
    const std::vector<Eigen::Vector3d>& depth_hints) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (views.size() != rig.cameras.size()) {
    return absl::InvalidArgumentError(absl::StrCat("head: ", views.size(), " views for ",
                                                   rig.cameras.size(), " cameras"));
  }
  for (size_t v = 0; v < views.size(); ++v) {
    if (views[v].width != rig.cameras[v].image_width ||
        views[v].height != rig.cameras[v].image_height ||
        views[v].thick_mask.size() != static_cast<size_t>(views[v].width) * views[v].height ||
        views[v].classes.data.size() != views[v].thick_mask.size()) {
      return absl::InvalidArgumentError(
          absl::StrCat("head: view ", v, " (", rig.cameras[v].name,
                       "): thick_mask or class image size disagrees with the calibration"));
    }
  }
  HeadAndTrunk result;
  const Carver carver(views, rig, options, depth_hints);
  std::vector<Cube> kept;
  const Eigen::Vector3d extent = volume.box.max() - volume.box.min();
  const Eigen::Vector3i roots = (extent / options.coarse_cell_m).array().ceil().cast<int>();
  for (int k = 0; k < roots.z(); ++k) {
    if (absl::Status s = deadline.Check("head"); !s.ok()) return s;
    for (int j = 0; j < roots.y(); ++j)
      for (int i = 0; i < roots.x(); ++i) {
        const Eigen::Vector3d centre =
            volume.box.min() +
            (Eigen::Vector3d(i, j, k).array() + 0.5).matrix() * options.coarse_cell_m;
        carver.Carve({centre, options.coarse_cell_m}, &kept);
      }
  }
  result.cells_kept = static_cast<int>(kept.size());
  if (kept.empty()) return result;

  // Rasterise the kept cubes and take the largest 26-connected component: this vine's head and
  // trunk (neighbours' heads lie outside the working volume).
  VoxelGrid grid(volume.box, options.min_cell_m);
  std::vector<std::vector<size_t>> voxels_of_cube;
  const int best_label = LabelLargestComponent(kept, options.min_cell_m, &grid, &voxels_of_cube);
  const std::vector<int>& labels = grid.labels();
  const Eigen::Vector3i size = grid.size();

  // Voxels seen as wood: near the thick silhouette in every view that sees them. The others are
  // kept only because a post hides them in some view; beside a post that is a column as wide as
  // the post's shadow, which says nothing of the trunk's or head's width (tuning stop 1294: a
  // post beside the trunk made the "trunk" 16 cm wide, so the head never widened past it and
  // collapsed to its top). They stay in the hull but are left out of the slabs' statistics.
  std::vector<uint8_t> wood(labels.size(), 0);
  bool any_wood = false;
  for (size_t c = 0; c < kept.size(); ++c) {
    if (!kept[c].seen_as_wood) continue;
    for (size_t flat : voxels_of_cube[c]) {
      wood[flat] = 1;
      any_wood = any_wood || labels[flat] == best_label;
    }
  }

  // Slabs of the component: x extent per slab, and the depth of the slab's widest row. Seen
  // from a rig on one side, the hull of a trunk is a diamond long in depth whose widest point is
  // at the trunk's true depth (perspective makes the back half longer, so the centroid is not).
  const int voxels_per_slab =
      std::max(1, static_cast<int>(std::lround(options.slab_m / options.min_cell_m)));
  const int slabs = (size.z() + voxels_per_slab - 1) / voxels_per_slab;
  std::vector<double> min_x(slabs, 1e9), max_x(slabs, -1e9);
  std::vector<double> centre_x(slabs, 0.0), centre_y(slabs, 0.0);  // of the widest rows
  std::vector<int> count(slabs, 0);
  std::vector<std::vector<int>> row_count(slabs, std::vector<int>(size.y(), 0));
  std::vector<std::vector<double>> row_sum_x(slabs, std::vector<double>(size.y(), 0.0));
  double top_z = -1e9;
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const Eigen::Vector3i ijk(x, y, z);
        if (labels[grid.Flat(ijk)] != best_label) continue;
        const Eigen::Vector3d p = grid.Centre(ijk);
        top_z = std::max(top_z, p.z());
        if (any_wood && !wood[grid.Flat(ijk)]) continue;
        const int s = z / voxels_per_slab;
        min_x[s] = std::min(min_x[s], p.x());
        max_x[s] = std::max(max_x[s], p.x());
        ++row_count[s][y];
        row_sum_x[s][y] += p.x();
        ++count[s];
      }
  for (int s = 0; s < slabs; ++s) {
    if (count[s] == 0) continue;
    const int widest = *std::max_element(row_count[s].begin(), row_count[s].end());
    double n = 0;
    for (int y = 0; y < size.y(); ++y) {
      if (row_count[s][y] < widest) continue;
      centre_y[s] += grid.Centre({0, y, 0}).y();
      centre_x[s] += row_sum_x[s][y] / row_count[s][y];
      ++n;
    }
    centre_x[s] /= n;
    centre_y[s] /= n;
  }
  auto slab_z = [&](int s) {
    return volume.box.min().z() + (s + 0.5) * voxels_per_slab * options.min_cell_m;
  };
  std::vector<int> occupied;
  for (int s = 0; s < slabs; ++s)
    if (count[s] > 0) occupied.push_back(s);
  std::vector<double> lower_widths;
  for (size_t i = 0; i < occupied.size() / 2; ++i)
    lower_widths.push_back(max_x[occupied[i]] - min_x[occupied[i]] + options.min_cell_m);
  const double trunk_width = lower_widths.empty() ? 0.0 : UpperMedian(lower_widths);

  // Head bottom: the lowest wide slab above the lower half of the trunk (heads carry lobes
  // that hang down beside the trunk top; scanning from below keeps them in the head). Where no
  // slab is clearly wide (the widening is weak evidence: a trunk measured 1 cm wider moves it
  // under the factor), the lowest of the widest slabs starts the head if it is wider than the
  // trunk at all: the head is where the hull is widest, and erring low keeps it enclosed.
  double head_bottom_z = top_z - options.head_min_height_m;
  // Per side (left and right of the trunk), the head may start lower: where that side of the
  // head hangs below the slab that starts it (tuning stop 1253 on the rig that sees more: the
  // right lobe reached 4 cm below the head's bottom, 0.76 of the head enclosed; 1189 the left
  // lobe, 0.976). Below.
  double side_bottom_z[2] = {head_bottom_z, head_bottom_z};
  double trunk_mid_x = 0.0;
  if (trunk_width > 0) {
    auto width = [&](int s) { return max_x[s] - min_x[s] + options.min_cell_m; };
    int bottom_slab = -1;
    int widest_slab = -1;
    for (size_t i = occupied.size() / 2; i < occupied.size(); ++i) {
      const int s = occupied[i];
      if (width(s) > options.head_width_factor * trunk_width) {
        bottom_slab = s;
        break;
      }
      if (widest_slab < 0 || width(s) > width(widest_slab) + 1e-9) widest_slab = s;
    }
    if (bottom_slab < 0 && widest_slab >= 0 && width(widest_slab) > trunk_width + 1e-9)
      bottom_slab = widest_slab;
    if (bottom_slab >= 0)
      head_bottom_z = std::min(head_bottom_z, slab_z(bottom_slab) - 0.5 * options.slab_m);
    side_bottom_z[0] = side_bottom_z[1] = head_bottom_z;
    // A side of the head starts at the lowest slab of an unbroken run, down from the slab that
    // starts the head, whose edge on that side (voxels seen as wood) lies beyond the trunk's
    // edge by half the widening a head needs on both sides. Seen from slightly below, one lobe
    // of a head widens the hull on its side only, too little for the whole slab to count. That
    // side's bottom is where its wood widens, with no head_overlap_m below it (with it, tuning
    // stop 1135 lost 0.02 of recall: the larger head swallowed cane bases).
    std::vector<double> lower_min_x, lower_max_x;
    for (size_t i = 0; i < occupied.size() / 2; ++i) {
      lower_min_x.push_back(min_x[occupied[i]]);
      lower_max_x.push_back(max_x[occupied[i]]);
    }
    const double trunk_left = UpperMedian(lower_min_x);
    const double trunk_right = UpperMedian(lower_max_x);
    trunk_mid_x = 0.5 * (trunk_left + trunk_right);
    const double side_widening = 0.5 * (options.head_width_factor - 1.0) * trunk_width;
    const auto at = std::find(occupied.begin(), occupied.end(), bottom_slab);
    if (bottom_slab >= 0 && at != occupied.end()) {
      for (int side = 0; side < 2; ++side) {
        for (size_t i = static_cast<size_t>(at - occupied.begin()); i-- > occupied.size() / 2;) {
          const int s = occupied[i];
          const bool wide = side == 0 ? min_x[s] < trunk_left - side_widening
                                      : max_x[s] > trunk_right + side_widening;
          if (!wide || occupied[i + 1] != s + 1) break;
          side_bottom_z[side] = std::min(side_bottom_z[side], slab_z(s) - 0.5 * options.slab_m);
        }
      }
    }
  }

  // The lowest head slabs are often no wider than the trunk: reach a little lower, for safety.
  head_bottom_z -= options.head_overlap_m;

  // Trunk: slab centres below the head. Near the bottom of the images only the far part of the
  // views' cones remains, which drags the widest row backwards: keep slabs near a reference depth
  // (below), then extend the trunk straight down to the ground (where trunks grow from), along
  // the line fitted to the kept centres.
  Polyline3 trunk;
  std::vector<double> trunk_y;
  for (int s : occupied) {
    if (slab_z(s) > head_bottom_z) break;
    trunk.points.push_back({centre_x[s], centre_y[s], slab_z(s)});
    trunk_y.push_back(trunk.points.back().y());
  }
  // Reference depth: triangulated wood inside the trunk's silhouette columns if there is enough,
  // else the upper half of the trunk, which every view sees whole.
  double reference_y =
      UpperMedian(std::vector<double>(trunk_y.begin() + trunk_y.size() / 2, trunk_y.end()));
  if (!trunk.points.empty()) {
    std::vector<double> hinted;
    for (const Eigen::Vector3d& p : depth_hints) {
      if (p.z() < trunk.points.front().z() || p.z() > head_bottom_z) continue;
      const int s = std::clamp(
          static_cast<int>((p.z() - volume.box.min().z()) / options.slab_m), 0, slabs - 1);
      if (count[s] > 0 && p.x() >= min_x[s] - 0.01 && p.x() <= max_x[s] + 0.01)
        hinted.push_back(p.y());
    }
    if (hinted.size() >= 5) reference_y = UpperMedian(hinted);
  }
  std::erase_if(trunk.points,
                [&](const Eigen::Vector3d& p) { return std::abs(p.y() - reference_y) > 0.025; });
  const double trunk_radius = std::max(0.01, 0.5 * (trunk_width - options.min_cell_m));
  if (trunk.points.size() >= 3) {
    std::vector<Eigen::Vector3d> smooth = trunk.points;
    for (size_t i = 1; i + 1 < smooth.size(); ++i)
      smooth[i].head<2>() =
          (trunk.points[i - 1] + trunk.points[i] + trunk.points[i + 1]).head<2>() / 3.0;
    trunk.points = smooth;
    // Least-squares line x(z), y(z) through the kept centres, for the extension to the ground.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : trunk.points) mean += p;
    mean /= trunk.points.size();
    double szz = 0, sxz = 0, syz = 0;
    for (const Eigen::Vector3d& p : trunk.points) {
      const Eigen::Vector3d d = p - mean;
      szz += d.z() * d.z();
      sxz += d.x() * d.z();
      syz += d.y() * d.z();
    }
    if (szz > 0 && trunk.points.front().z() > volume.box.min().z() + options.slab_m) {
      const double ground_z = std::max(0.0, volume.box.min().z());
      const double dz = ground_z - mean.z();
      const Eigen::Vector3d ground(mean.x() + sxz / szz * dz, mean.y() + syz / szz * dz, ground_z);
      trunk.points.insert(trunk.points.begin(), ground);
    }
    trunk.radii.assign(trunk.points.size(), trunk_radius);
    result.trunk = trunk;
  }

  // Head: kept cubes of the component above the head bottom, depth bounded about its centre.
  double head_min_x = 1e9, head_max_x = -1e9;
  double head_y = 0.0;
  int head_n = 0;
  bool any_head = false;
  std::vector<bool> in_head(kept.size(), false);
  for (size_t c = 0; c < kept.size(); ++c) {
    for (size_t flat : voxels_of_cube[c]) in_head[c] = in_head[c] || labels[flat] == best_label;
    // A cube on one side of the trunk's middle starts at that side's bottom; one across it at
    // the lower of the two.
    const double half = 0.5 * kept[c].side;
    const double bottom_z =
        kept[c].centre.x() + half <= trunk_mid_x   ? side_bottom_z[0]
        : kept[c].centre.x() - half >= trunk_mid_x ? side_bottom_z[1]
                                                   : std::min(side_bottom_z[0], side_bottom_z[1]);
    const bool above_bottom = kept[c].centre.z() + half >= head_bottom_z;
    in_head[c] = in_head[c] && (above_bottom || kept[c].centre.z() + half >= bottom_z);
    // The head's extent (depth hints, depth, hidden box) comes from the cubes above the global
    // bottom only: a side's lower cubes are added, never move what the rest is judged by, so the
    // head holds every sphere it held without the side bottoms.
    if (!in_head[c] || !above_bottom) continue;
    any_head = true;
    head_min_x = std::min(head_min_x, kept[c].centre.x() - 0.5 * kept[c].side);
    head_max_x = std::max(head_max_x, kept[c].centre.x() + 0.5 * kept[c].side);
  }
  // The head's depth: the widest rows of its slabs, as for the trunk.
  for (int s = 0; s < slabs; ++s) {
    if (count[s] == 0 || slab_z(s) + 0.5 * options.slab_m < head_bottom_z) continue;
    head_y += centre_y[s];
    ++head_n;
  }
  if (!any_head || head_n == 0) return result;
  // The trunk's top is well seen and lies under the head; it gives the head's depth where there
  // is a trunk (the widest rows of the head's slabs are dragged backwards like the trunk's).
  head_y = result.trunk ? result.trunk->points.back().y() : head_y / head_n;
  // Better still: the depth of triangulated wood (cane bases) within the head's extent.
  std::vector<double> hinted;
  for (const Eigen::Vector3d& p : depth_hints) {
    if (p.x() >= head_min_x && p.x() <= head_max_x && p.z() >= head_bottom_z &&
        p.z() <= top_z + options.depth_margin_m && volume.Contains(p)) {
      hinted.push_back(p.y());
    }
  }
  if (hinted.size() >= 5 && !(options.head_centre_on_trunk && result.trunk)) {
    head_y = UpperMedian(hinted);
  }
  const double half_depth =
      0.5 * options.head_depth_factor * std::max(head_max_x - head_min_x, top_z - head_bottom_z) +
      options.depth_margin_m;
  for (size_t c = 0; c < kept.size(); ++c) {
    if (!in_head[c] || !kept[c].tight) continue;
    if (std::abs(kept[c].centre.y() - head_y) > half_depth + 0.5 * kept[c].side) continue;
    result.head.spheres.push_back({kept[c].centre, 0.5 * std::sqrt(3.0) * kept[c].side});
  }
  // Within the head's extent, what posts hide in every view may be head (tuning stop 1294: a
  // post beside the trunk hid a quarter of the head from all three cameras): keep it too, so
  // that the head stays enclosed. Elsewhere a post's shadow is not kept (it is no evidence).
  const Eigen::Vector3d hidden_min(head_min_x, head_y - half_depth, head_bottom_z);
  const Eigen::Vector3d hidden_max(head_max_x, head_y + half_depth, top_z);
  Eigen::Vector3i from, to;
  grid.Index(hidden_min.cwiseMax(volume.box.min()), &from);
  grid.Index(hidden_max.cwiseMin(volume.box.max() - Eigen::Vector3d::Constant(1e-9)), &to);
  from = from.cwiseMax(0).cwiseMin(size - Eigen::Vector3i::Ones());
  to = to.cwiseMax(0).cwiseMin(size - Eigen::Vector3i::Ones());
  for (int z = from.z(); z <= to.z(); ++z)
    for (int y = from.y(); y <= to.y(); ++y)
      for (int x = from.x(); x <= to.x(); ++x) {
        const Eigen::Vector3i ijk(x, y, z);
        if (labels[grid.Flat(ijk)] != 0) continue;  // in the hull already
        bool seen_as_wood = true;
        const Cube cell{grid.Centre(ijk), options.min_cell_m};
        if (carver.Judge(cell, &seen_as_wood) != CubeVerdict::kHidden) continue;
        result.head.spheres.push_back({cell.centre, 0.5 * std::sqrt(3.0) * cell.side});
      }
  return result;
}

}  // namespace vb::reconstruct
