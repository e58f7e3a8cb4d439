// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/fiducials.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "Eigen/Dense"

namespace vb::reconstruct {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The window of one search: min(R, G, B) per pixel, and whether the pixel looks like the blue
// backdrop (blue at least as bright as red and green).
struct Window {
  int x0 = 0, y0 = 0, w = 0, h = 0;
  std::vector<float> value;
  std::vector<uint8_t> blue;
  std::vector<float> red_over_blue;  // chromaticity: independent of the light falling there
  std::vector<float> blue_dn;
  float at(int x, int y) const { return value[static_cast<size_t>(y) * w + x]; }
};

Window Cut(const Image& image, int x0, int y0, int x1, int y1) {
  Window out;
  out.x0 = x0, out.y0 = y0, out.w = x1 - x0 + 1, out.h = y1 - y0 + 1;
  out.value.resize(static_cast<size_t>(out.w) * out.h);
  out.blue.resize(out.value.size());
  out.red_over_blue.resize(out.value.size());
  out.blue_dn.resize(out.value.size());
  for (int y = 0; y < out.h; ++y) {
    for (int x = 0; x < out.w; ++x) {
      const uint8_t* p = image.at(x0 + x, y0 + y);
      const size_t i = static_cast<size_t>(y) * out.w + x;
      out.value[i] = static_cast<float>(std::min({p[0], p[1], p[2]}));
      out.blue[i] = p[2] >= std::max(p[0], p[1]);
      out.red_over_blue[i] = static_cast<float>(p[0]) / std::max<float>(p[2], 1.0f);
      out.blue_dn[i] = p[2];
    }
  }
  return out;
}

// One fiducial in one image; nullopt with `reason` set when not found.
std::optional<Eigen::Vector2d> Find(const Image& image, const CameraCalibration& camera,
                                    const Fiducial& fiducial, const Eigen::Vector2d& expected,
                                    const Eigen::Matrix2d& axes, const FiducialDetectOptions& o,
                                    std::string* reason) {
  const double area_px = kPi * std::abs(axes.determinant());
  const double radius_px = std::sqrt(std::abs(axes.determinant()));
  const double half = o.search_radius_px + 2.6 * radius_px;
  const int x0 = static_cast<int>(std::floor(expected.x() - half));
  const int y0 = static_cast<int>(std::floor(expected.y() - half));
  const int x1 = static_cast<int>(std::ceil(expected.x() + half));
  const int y1 = static_cast<int>(std::ceil(expected.y() + half));
  if (x0 < 0 || y0 < 0 || x1 >= camera.image_width || y1 >= camera.image_height) {
    *reason = "too near the image border";
    return std::nullopt;
  }
  const Window win = Cut(image, x0, y0, x1, y1);
  std::vector<float> sorted = win.value;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const float background = sorted[sorted.size() / 2];
  float peak = background;
  for (int y = 1; y + 1 < win.h; ++y) {
    for (int x = 1; x + 1 < win.w; ++x) {
      float sum = 0.0f;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) sum += win.at(x + dx, y + dy);
      peak = std::max(peak, sum / 9.0f);
    }
  }
  if (peak - background < o.min_contrast_dn) {
    *reason = absl::StrCat("no bright disc (contrast ", peak - background, " DN)");
    return std::nullopt;
  }
  const float threshold = 0.5f * (background + peak);

  // Connected bright regions (4-connected); the one of the right area nearest the expectation.
  std::vector<int> component(win.value.size(), -1);
  std::vector<int> best_pixels;
  double best_distance = 1e300;
  int wrong_area = 0;
  for (size_t start = 0; start < win.value.size(); ++start) {
    if (component[start] >= 0 || win.value[start] <= threshold) continue;
    std::vector<int> pixels{static_cast<int>(start)};
    component[start] = static_cast<int>(start);
    bool border = false;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (size_t k = 0; k < pixels.size(); ++k) {
      const int x = pixels[k] % win.w, y = pixels[k] / win.w;
      sum += Eigen::Vector2d(x, y);
      border = border || x == 0 || y == 0 || x == win.w - 1 || y == win.h - 1;
      const int nx[4] = {x - 1, x + 1, x, x};
      const int ny[4] = {y, y, y - 1, y + 1};
      for (int n = 0; n < 4; ++n) {
        if (nx[n] < 0 || ny[n] < 0 || nx[n] >= win.w || ny[n] >= win.h) continue;
        const size_t i = static_cast<size_t>(ny[n]) * win.w + nx[n];
        if (component[i] >= 0 || win.value[i] <= threshold) continue;
        component[i] = static_cast<int>(start);
        pixels.push_back(static_cast<int>(i));
      }
    }
    const double area = static_cast<double>(pixels.size());
    if (border || area < (1.0 - o.area_tolerance) * area_px ||
        area > (1.0 + o.area_tolerance) * area_px) {
      wrong_area += area >= 0.25 * area_px;
      continue;
    }
    const Eigen::Vector2d centre = sum / area + Eigen::Vector2d(x0, y0);
    const double distance = (centre - expected).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best_pixels = std::move(pixels);
    }
  }
  if (best_pixels.empty()) {
    *reason = wrong_area > 0 ? "bright region of the wrong size or cut by the window (occluded?)"
                             : "no bright region of the disc's size";
    return std::nullopt;
  }

  // Centroid of the disc's coverage of each pixel over the region grown by 2 px (its
  // anti-aliased edge). Coverage comes from the colour, not the brightness: a white disc on a
  // blue backdrop has red / blue ~1 against ~0.15, whatever light falls there, so a soft shadow
  // or the falloff of the light across the disc does not pull the centre. With backdrop ratio
  // qa, disc ratio qd and disc blue = k x backdrop blue (all measured in the window), a pixel
  // covered by a fraction c has ratio q = (qa + c (qd k - qa)) / (1 + c (k - 1)).
  auto median = [](std::vector<float> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::vector<float> disc_q, disc_b;
  for (int i : best_pixels) {
    disc_q.push_back(win.red_over_blue[static_cast<size_t>(i)]);
    disc_b.push_back(win.blue_dn[static_cast<size_t>(i)]);
  }
  const double qa = median(win.red_over_blue);
  const double qd = median(disc_q);
  const double k = std::max<double>(median(disc_b), 1.0) / std::max<double>(median(win.blue_dn), 1.0);
  if (!(qd - qa > 0.2)) {
    *reason = absl::StrCat("not white on blue (red/blue ", qd, " on the disc, ", qa, " around)");
    return std::nullopt;
  }
  std::vector<uint8_t> mask(win.value.size(), 0);
  for (int i : best_pixels) {
    const int x = i % win.w, y = i / win.w;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx >= 0 && yy >= 0 && xx < win.w && yy < win.h) mask[static_cast<size_t>(yy) * win.w + xx] = 1;
      }
  }
  double total = 0.0;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  for (int y = 0; y < win.h; ++y)
    for (int x = 0; x < win.w; ++x) {
      const size_t i = static_cast<size_t>(y) * win.w + x;
      if (!mask[i]) continue;
      const double q = win.red_over_blue[i];
      const double denominator = qd * k - qa - q * (k - 1.0);
      const double weight =
          std::abs(denominator) > 1e-6 ? std::clamp((q - qa) / denominator, 0.0, 1.0) : 0.0;
      total += weight;
      moment += weight * Eigen::Vector2d(x, y);
    }
  const Eigen::Vector2d centre = moment / std::max(total, 1e-9) + Eigen::Vector2d(x0, y0);
  // The bright region and the white one must agree: a disc half in a shadow or partly behind a
  // thin cane has a bright region smaller than the white one, with its centre elsewhere.
  Eigen::Vector2d bright_centre = Eigen::Vector2d::Zero();
  for (int i : best_pixels) bright_centre += Eigen::Vector2d(i % win.w, i / win.w);
  bright_centre = bright_centre / static_cast<double>(best_pixels.size()) + Eigen::Vector2d(x0, y0);
  if (std::abs(total / area_px - 1.0) > o.area_tolerance ||
      (bright_centre - centre).norm() > o.max_centre_disagreement_px) {
    *reason = absl::StrCat("unevenly lit or partly hidden (white area ", total / area_px,
                           " of the disc's, bright and white centres ",
                           (bright_centre - centre).norm(), " px apart)");
    return std::nullopt;
  }

  // The surround must be clean backdrop: in the ring 1.6-2.4 disc radii out (in the disc's own
  // projected axes), dark and blue.
  const Eigen::Matrix2d inverse = axes.inverse();
  int ring = 0, clean = 0;
  for (int y = 0; y < win.h; ++y)
    for (int x = 0; x < win.w; ++x) {
      const double rho = (inverse * (Eigen::Vector2d(x0 + x, y0 + y) - centre)).norm();
      if (rho < 1.6 || rho > 2.4) continue;
      const size_t i = static_cast<size_t>(y) * win.w + x;
      ++ring;
      clean += win.value[i] <= threshold && win.blue[i];
    }
  if (ring == 0 || clean < o.min_clean_surround * ring) {
    *reason = absl::StrCat("surround not clean backdrop (", clean, " of ", ring,
                           " pixels): occluded or in a cane's way");
    return std::nullopt;
  }
  return centre;
}

}  // namespace

absl::Status FiducialDetectOptions::Validate() const {
  auto bad = [](const char* field, double v) {
    return absl::InvalidArgumentError(absl::StrCat("fiducial_detect.", field, ": out of range (", v, ")"));
  };
  if (!(std::isfinite(search_radius_px) && search_radius_px > 0 && search_radius_px <= 200))
    return bad("search_radius_px", search_radius_px);
  if (!(std::isfinite(min_contrast_dn) && min_contrast_dn > 0 && min_contrast_dn < 255))
    return bad("min_contrast_dn", min_contrast_dn);
  if (!(area_tolerance > 0 && area_tolerance < 1)) return bad("area_tolerance", area_tolerance);
  if (!(std::isfinite(min_radius_px) && min_radius_px > 0)) return bad("min_radius_px", min_radius_px);
  if (!(std::isfinite(max_centre_disagreement_px) && max_centre_disagreement_px > 0))
    return bad("max_centre_disagreement_px", max_centre_disagreement_px);
  if (!(min_clean_surround >= 0 && min_clean_surround <= 1))
    return bad("min_clean_surround", min_clean_surround);
  return absl::OkStatus();
}

absl::StatusOr<std::vector<FiducialObservation>> DetectFiducials(
    const Image& image, const CameraCalibration& camera, const std::vector<Fiducial>& fiducials,
    const FiducialDetectOptions& options, FiducialDetectSummary* summary) {
  FiducialDetectSummary local;
  FiducialDetectSummary& out = summary != nullptr ? *summary : local;
  out = FiducialDetectSummary{};
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (image.format != PixelFormat::kRgb8) {
    return absl::InvalidArgumentError(absl::StrCat(camera.name, ": fiducials need an rgb8 image"));
  }
  if (image.width != camera.image_width || image.height != camera.image_height) {
    return absl::InvalidArgumentError(absl::StrCat(camera.name, ": image is ", image.width, "x",
                                                   image.height, ", calibration says ",
                                                   camera.image_width, "x", camera.image_height));
  }
  std::vector<FiducialObservation> found;
  for (size_t f = 0; f < fiducials.size(); ++f) {
    const Fiducial& fiducial = fiducials[f];
    const Eigen::Vector3d& c = fiducial.position_in_platform;
    const std::optional<Eigen::Vector2d> expected = camera.Project(c);
    if (!expected || !camera.InImage(*expected)) continue;
    // The disc's projected half-axes: its radius along x and along z (it faces -y).
    const double r = fiducial.radius_m;
    const auto xp = camera.Project(c + Eigen::Vector3d(r, 0, 0));
    const auto xm = camera.Project(c - Eigen::Vector3d(r, 0, 0));
    const auto zp = camera.Project(c + Eigen::Vector3d(0, 0, r));
    const auto zm = camera.Project(c - Eigen::Vector3d(0, 0, r));
    if (!xp || !xm || !zp || !zm) continue;
    Eigen::Matrix2d axes;
    axes.col(0) = 0.5 * (*xp - *xm);
    axes.col(1) = 0.5 * (*zp - *zm);
    if (std::sqrt(std::abs(axes.determinant())) < options.min_radius_px) continue;
    ++out.looked_for;
    std::string reason;
    const std::optional<Eigen::Vector2d> uv =
        Find(image, camera, fiducial, *expected, axes, options, &reason);
    if (!uv) {
      out.missed.push_back(absl::StrCat(fiducial.name, ": ", reason));
      continue;
    }
    // The centroid of a disc's image is not the image of its centre (perspective, and the lens,
    // which bends a disc near the corners by up to a pixel): correct by the difference between
    // the two, computed through the calibration (equal-area samples of the disc).
    Eigen::Vector2d model_centroid = Eigen::Vector2d::Zero();
    int samples = 0;
    for (int ring = 0; ring < 12; ++ring) {
      const double rho = r * std::sqrt((ring + 0.5) / 12.0);
      for (int a = 0; a < 36; ++a) {
        const double angle = 2.0 * kPi * (a + 0.5 * (ring % 2)) / 36.0;
        const auto p = camera.Project(c + rho * Eigen::Vector3d(std::cos(angle), 0, std::sin(angle)));
        if (!p) continue;
        model_centroid += *p;
        ++samples;
      }
    }
    const Eigen::Vector2d bias = samples > 0 ? Eigen::Vector2d(model_centroid / samples - *expected)
                                             : Eigen::Vector2d::Zero();
    ++out.found;
    found.push_back({static_cast<int>(f), *uv - bias, *expected});
  }
  return found;
}

void ClearFiducials(const std::vector<FiducialObservation>& found, const CameraCalibration& camera,
                    const std::vector<Fiducial>& fiducials, ClassImage* classes) {
  for (const FiducialObservation& f : found) {
    if (f.fiducial < 0 || f.fiducial >= static_cast<int>(fiducials.size())) continue;
    const Fiducial& fiducial = fiducials[static_cast<size_t>(f.fiducial)];
    const Eigen::Vector3d& c = fiducial.position_in_platform;
    const auto xp = camera.Project(c + Eigen::Vector3d(fiducial.radius_m, 0, 0));
    const auto zp = camera.Project(c + Eigen::Vector3d(0, 0, fiducial.radius_m));
    const auto centre = camera.Project(c);
    if (!xp || !zp || !centre) continue;
    const double reach = 1.5 * std::max((*xp - *centre).norm(), (*zp - *centre).norm());
    const int x0 = std::max(0, static_cast<int>(std::floor(f.uv_px.x() - reach)));
    const int y0 = std::max(0, static_cast<int>(std::floor(f.uv_px.y() - reach)));
    const int x1 = std::min(classes->width - 1, static_cast<int>(std::ceil(f.uv_px.x() + reach)));
    const int y1 = std::min(classes->height - 1, static_cast<int>(std::ceil(f.uv_px.y() + reach)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if ((Eigen::Vector2d(x, y) - f.uv_px).norm() <= reach) classes->set(x, y, PixelClass::kBackground);
  }
}

}  // namespace vb::reconstruct
