// SPDX-License-Identifier: Apache-2.0
// Peeling reconstructed canes off a view's head silhouette (docs/reconstruction.md step 5, s18).
// The silhouette (View2D::thick_mask) is what survives an opening wider than any cane, but where
// cane bases crowd at the head they survive it too, and the hull grows beside the head by their
// bundle. The assembled canes are known in 3D: their projected pixels that lie near the
// silhouette's rim (within HeadOptions::peel_depth_px of its background) are taken out of it.
// Only the rim: a cane crossing in front of the head must not carve a tunnel through it (the
// head is behind it), so deeper pixels stay; where such a cane crosses the rim the silhouette
// loses a notch at most peel_depth_px deep.
#pragma once

#include <cstdint>
#include <vector>

#include "core/calibration.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// `view`'s thick_mask (row-major, nonzero = silhouette) without the peeled pixels. `canes` are
// 3D points of canes in order (ReconstructHeadAndTrunk's depth hints): consecutive points closer
// than options.peel_link_m are drawn as a line options.peel_cane_radius_m thick through `camera`
// (a point with no such neighbour as a disc). The hints carry no cane boundaries, so the last
// point of one cane and the first of the next are linked too when they lie that close (a known
// flaw of this off-by-default option: passing the canes as polylines would fix it). `camera`
// must be the view's (sizes agree; the caller checks). Pure function, thread-safe.
std::vector<uint8_t> PeelCanesOffSilhouette(const View2D& view, const CameraCalibration& camera,
                                            const std::vector<Eigen::Vector3d>& canes,
                                            const HeadOptions& options);

}  // namespace vb::reconstruct
