// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/strand_halves.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

absl::Status Invalid(const std::string& field, const std::string& message) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", message));
}

// Luminance (Rec. 601) of an rgb8 image at p, bilinear, averaged over the 5 points p + k * along,
// k = -2..2, that lie inside the image (0 if none).
double LumaAlong(const Image& image, const Eigen::Vector2d& p, const Eigen::Vector2d& along) {
  auto luma = [&image](int x, int y) {
    const uint8_t* c = image.at(x, y);
    return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
  };
  double sum = 0.0;
  int n = 0;
  for (int k = -2; k <= 2; ++k) {
    const Eigen::Vector2d q = p + along * k;
    const int x0 = static_cast<int>(std::floor(q.x()));
    const int y0 = static_cast<int>(std::floor(q.y()));
    if (x0 < 0 || y0 < 0 || x0 + 1 >= image.width || y0 + 1 >= image.height) continue;
    const double fx = q.x() - x0;
    const double fy = q.y() - y0;
    sum += (1 - fx) * (1 - fy) * luma(x0, y0) + fx * (1 - fy) * luma(x0 + 1, y0) +
           (1 - fx) * fy * luma(x0, y0 + 1) + fx * fy * luma(x0 + 1, y0 + 1);
    ++n;
  }
  return n > 0 ? sum / n : 0.0;
}

// Unit direction of points[hi] - points[lo] (zero when they coincide).
Eigen::Vector2d Direction(const std::vector<Eigen::Vector2d>& points, size_t lo, size_t hi) {
  const Eigen::Vector2d d = points[hi] - points[lo];
  return d.norm() > 0.0 ? Eigen::Vector2d(d / d.norm()) : Eigen::Vector2d::Zero();
}

bool OnThickMask(const View2D& view, const Eigen::Vector2d& p) {
  if (view.thick_mask.empty()) return false;
  const int x = static_cast<int>(std::lround(p.x()));
  const int y = static_cast<int>(std::lround(p.y()));
  return x >= 0 && y >= 0 && x < view.width && y < view.height &&
         view.thick_mask[static_cast<size_t>(y) * view.width + x] != 0;
}

// The two halves of points [k, e] of `segment`, appended to `out` as siblings.
void AddHalves(const Segment2D& segment, int parent, size_t k, size_t e,
               std::vector<StrandHalf>* out) {
  StrandHalf left, right;
  left.parent = right.parent = parent;
  for (size_t i = k; i <= e; ++i) {
    const Eigen::Vector2d d =
        Direction(segment.points, i >= k + 2 ? i - 2 : k, std::min(e, i + 2));
    if (d.isZero()) continue;
    const Eigen::Vector2d normal(-d.y(), d.x());
    const double w = segment.widths_px[i];
    left.path.points.push_back(segment.points[i] + normal * (w / 4));
    right.path.points.push_back(segment.points[i] - normal * (w / 4));
    left.path.widths_px.push_back(w / 2);
    right.path.widths_px.push_back(w / 2);
    left.to_sibling_px.push_back(-normal * (w / 2));
    right.to_sibling_px.push_back(normal * (w / 2));
  }
  if (left.path.points.size() < 2) return;
  const int first = static_cast<int>(out->size());
  left.sibling = first + 1;
  right.sibling = first;
  out->push_back(std::move(left));
  out->push_back(std::move(right));
}

// The step to the sibling at arc length `arc_px` along `half`'s path (its nearest point at or
// beyond that arc; the last one past the end).
Eigen::Vector2d SiblingStepAt(const StrandHalf& half, double arc_px) {
  const auto& p = half.path.points;
  double arc = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (i > 0) arc += (p[i] - p[i - 1]).norm();
    if (arc >= arc_px) return half.to_sibling_px[i];
  }
  return half.to_sibling_px.back();
}

}  // namespace

absl::Status StrandHalfOptions::Validate() const {
  if (!(min_width_px >= 1.0) || !std::isfinite(min_width_px)) {
    return Invalid("min_width_px", "must be finite and >= 1");
  }
  if (!(min_width_ratio >= 1.0) || !std::isfinite(min_width_ratio)) {
    return Invalid("min_width_ratio", "must be finite and >= 1");
  }
  if (!(min_run_px >= 2.0) || !std::isfinite(min_run_px)) {
    return Invalid("min_run_px", "must be finite and >= 2");
  }
  if (!(min_seam_dip >= 0.0) || !std::isfinite(min_seam_dip)) {
    return Invalid("min_seam_dip", "must be finite and >= 0");
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<StrandHalf>> FindStrandHalves(const View2D& view, const Image& image,
                                                         const StrandHalfOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (image.format != PixelFormat::kRgb8) return Invalid("image", "must be rgb8");
  if (image.width != view.width || image.height != view.height) {
    return Invalid("image", absl::StrCat("is ", image.width, "x", image.height, " but the view ",
                                         view.width, "x", view.height));
  }
  std::vector<StrandHalf> halves;
  if (!options.enabled) return halves;
  std::vector<double> widths;
  for (const Segment2D& s : view.segments) {
    widths.insert(widths.end(), s.widths_px.begin(), s.widths_px.end());
  }
  if (widths.empty()) return halves;
  std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
  const double min_width =
      std::max(options.min_width_px, options.min_width_ratio * widths[widths.size() / 2]);
  for (int si = 0; si < static_cast<int>(view.segments.size()); ++si) {
    const Segment2D& segment = view.segments[si];
    const size_t n = segment.points.size();
    if (n < 3 || segment.widths_px.size() != n) continue;
    auto seamed = [&](size_t k) {
      const double w = segment.widths_px[k];
      if (!(w >= min_width) || OnThickMask(view, segment.points[k])) return false;
      const Eigen::Vector2d d =
          Direction(segment.points, k >= 2 ? k - 2 : 0, std::min(n - 1, k + 2));
      if (d.isZero()) return false;
      const Eigen::Vector2d normal(-d.y(), d.x());
      const Eigen::Vector2d& p = segment.points[k];
      const double seam = LumaAlong(image, p, d);
      const double axis = std::min(LumaAlong(image, p + normal * (w / 4), d),
                                   LumaAlong(image, p - normal * (w / 4), d));
      return axis - seam >= options.min_seam_dip;
    };
    size_t k = 0;
    while (k < n) {
      if (!seamed(k)) {
        ++k;
        continue;
      }
      size_t e = k;
      double run = 0.0;
      while (e + 1 < n && seamed(e + 1)) {
        run += (segment.points[e + 1] - segment.points[e]).norm();
        ++e;
      }
      if (run >= options.min_run_px) AddHalves(segment, si, k, e, &halves);
      k = e + 1;
    }
  }
  return halves;
}

bool CrossesStrands(const MatchCandidate& candidate, const StrandHalf& a, const StrandHalf& b,
                    const CameraCalibration& camera_a, const CameraCalibration& camera_b) {
  if (a.to_sibling_px.empty() || b.to_sibling_px.empty()) return false;
  const Eigen::Vector3d centre_a = camera_a.CentreInPlatform();
  const Eigen::Vector3d centre_b = camera_b.CentreInPlatform();
  int ordered = 0, crossed = 0;
  for (const EpipolarHit& hit : candidate.hits) {
    const Eigen::Vector3d& x = hit.point;
    const auto in_a = camera_a.Project(x);
    const auto in_b = camera_b.Project(x);
    // 1 cm deeper along the other camera's ray: the epipolar direction of increasing depth.
    const auto deeper_a = camera_a.Project(x + 0.01 * (x - centre_b).normalized());
    const auto deeper_b = camera_b.Project(x + 0.01 * (x - centre_a).normalized());
    if (!in_a || !in_b || !deeper_a || !deeper_b) continue;
    const double side_a = SiblingStepAt(a, hit.arc_a_px).dot(*deeper_a - *in_a);
    const double side_b = SiblingStepAt(b, hit.arc_b_px).dot(*deeper_b - *in_b);
    if (side_a * side_b < 0) ++ordered;
    if (side_a * side_b > 0) ++crossed;
  }
  return crossed > ordered;
}

}  // namespace vb::reconstruct
