// SPDX-License-Identifier: Apache-2.0
#include "sim/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "sim/render_rays.h"
#include "sim/render_scene.h"
#include "sim/render_shading.h"

namespace vb::sim {
namespace {

absl::Status Invalid(const std::string& field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("render options: ", field, " ", why));
}

// Standard normal quantiles at (i + 0.5) / 4096: indexing it with 12 random bits draws an exact
// (discretised) normal sample for the price of a table lookup, ~10x cheaper than Box-Muller.
const std::array<float, 4096>& NormalQuantiles() {
  static const std::array<float, 4096> table = [] {
    std::array<float, 4096> q{};
    for (int i = 0; i < 4096; ++i) {
      const double p = (i + 0.5) / 4096.0;
      double lo = -10.0, hi = 10.0;
      for (int it = 0; it < 80; ++it) {  // bisection on the CDF 0.5 erfc(-x / sqrt 2)
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
      }
      q[i] = static_cast<float>(0.5 * (lo + hi));
    }
    return q;
  }();
  return table;
}

// Counter-style generator: one splitmix64 stream per image row, so noise is reproducible and
// does not depend on the order rows are produced in. Each 64-bit draw yields four samples.
class RowNoise {
 public:
  RowNoise(uint64_t seed, int row)
      : state_(seed ^ (0x9E3779B97F4A7C15ull * (static_cast<uint64_t>(row) + 1))),
        table_(NormalQuantiles().data()) {}
  float Gaussian() {
    if (left_ == 0) {
      uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      bits_ = z ^ (z >> 31);
      left_ = 4;
    }
    --left_;
    const float g = table_[bits_ & 0xFFF];
    bits_ >>= 16;
    return g;
  }

 private:
  uint64_t state_;
  const float* table_;
  uint64_t bits_ = 0;
  int left_ = 0;
};

// Colour channel (0 R, 1 G, 2 B) of pixel (x, y) in a Bayer mosaic; the format names the first row
// of the top-left 2x2 block.
int BayerChannel(PixelFormat f, int x, int y) {
  const int i = (y & 1) * 2 + (x & 1);
  static constexpr int kRg[4] = {0, 1, 1, 2};
  static constexpr int kGb[4] = {1, 2, 0, 1};
  static constexpr int kGr[4] = {1, 0, 2, 1};
  static constexpr int kBg[4] = {2, 1, 1, 0};
  switch (f) {
    case PixelFormat::kBayerRg8: return kRg[i];
    case PixelFormat::kBayerGb8: return kGb[i];
    case PixelFormat::kBayerGr8: return kGr[i];
    case PixelFormat::kBayerBg8: return kBg[i];
    default: return 1;
  }
}

}  // namespace

absl::Status RenderOptions::Validate() const {
  switch (pixel_format) {
    case PixelFormat::kRgb8: case PixelFormat::kMono8: case PixelFormat::kBayerRg8:
    case PixelFormat::kBayerGb8: case PixelFormat::kBayerGr8: case PixelFormat::kBayerBg8:
      break;
    default:
      return Invalid("pixel_format", absl::StrCat("is not a known format (", static_cast<int>(pixel_format), ")"));
  }
  if (!(std::isfinite(exposure) && exposure > 0.0)) {
    return Invalid("exposure", absl::StrCat("must be finite and > 0, is ", exposure));
  }
  if (!(std::isfinite(read_noise_dn) && read_noise_dn >= 0.0)) {
    return Invalid("read_noise_dn", absl::StrCat("must be finite and >= 0, is ", read_noise_dn));
  }
  if (!(std::isfinite(shot_noise) && shot_noise >= 0.0)) {
    return Invalid("shot_noise", absl::StrCat("must be finite and >= 0, is ", shot_noise));
  }
  if (!(std::isfinite(ambient) && ambient >= 0.0 && ambient <= 10.0)) {
    return Invalid("ambient", absl::StrCat("must be in [0, 10], is ", ambient));
  }
  if (!(vignetting >= 0.0 && vignetting < 1.0)) {
    return Invalid("vignetting", absl::StrCat("must be in [0, 1), is ", vignetting));
  }
  if (!(std::isfinite(light_radius_m) && light_radius_m >= 0.0)) {
    return Invalid("light_radius_m", absl::StrCat("must be finite and >= 0, is ", light_radius_m));
  }
  return absl::OkStatus();
}

absl::StatusOr<RenderedView> Render(const Scene& scene, const CameraCalibration& camera,
                                    const RenderOptions& options, uint64_t noise_seed) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = camera.Validate(); !s.ok()) return s;
  const std::shared_ptr<const RayTable> rays = RayTableFor(camera);
  return Render(scene, camera, *rays, options, noise_seed);
}

absl::StatusOr<RenderedView> Render(const Scene& scene, const CameraCalibration& camera,
                                    const RayTable& rays, const RenderOptions& options,
                                    uint64_t noise_seed) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = camera.Validate(); !s.ok()) return s;
  if (!rays.Matches(camera)) {
    return absl::InvalidArgumentError(
        absl::StrCat("rays: the ray table was not built for camera '", camera.name, "'"));
  }
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    if (!l.position_in_platform.allFinite() || !std::isfinite(l.intensity) || l.intensity < 0.0) {
      return absl::InvalidArgumentError(absl::StrCat("scene.lights[", i, "]: position or intensity invalid"));
    }
  }
  if (!std::isfinite(scene.backdrop_y_m) || !std::isfinite(scene.ground_z_m)) {
    return absl::InvalidArgumentError("scene: backdrop_y_m or ground_z_m is not finite");
  }

  const int w = camera.image_width;
  const int h = camera.image_height;
  const Eigen::Vector3d centre = camera.CentreInPlatform();
  const std::vector<render::Segment> segments = render::BuildSegments(scene);
  const std::vector<render::Primitive> prims = render::PreparePrimitives(segments, camera, rays);
  const std::vector<render::PixelHit> hits = render::CastPrimary(prims, segments, rays);
  const render::Shader shader(scene, segments, options, centre, rays);

  RenderedView view;
  view.image = Image(w, h, options.pixel_format);
  view.labels = LabelImage(w, h);
  const double pcx = camera.camera_matrix(0, 2);
  const double pcy = camera.camera_matrix(1, 2);
  double corner2 = 0.0;
  for (double cx : {0.0, w - 1.0}) {
    for (double cy : {0.0, h - 1.0}) corner2 = std::max(corner2, (cx - pcx) * (cx - pcx) + (cy - pcy) * (cy - pcy));
  }
  const float pcx_f = static_cast<float>(pcx);
  const float vig_k = static_cast<float>(options.vignetting / corner2);
  const float gain = static_cast<float>(options.exposure) * 255.0f;
  const float read2 = static_cast<float>(options.read_noise_dn * options.read_noise_dn);
  const float shot2 = static_cast<float>(options.shot_noise * options.shot_noise);
  const bool noisy = read2 > 0.0f || shot2 > 0.0f;
  const PixelFormat format = options.pixel_format;

  // Digital number of a linear value with sensor noise; the same arithmetic for every format so
  // that rgb8 and Bayer renders agree exactly when noise is off.
  // Noise sd per clean digital number, so the per-sample cost is a lookup rather than a sqrt.
  std::array<float, 256> noise_sd{};
  for (int dn = 0; dn < 256; ++dn) noise_sd[dn] = std::sqrt(read2 + shot2 * static_cast<float>(dn));
  auto to_dn = [&](float value, RowNoise& rng) -> uint8_t {
    float dn = std::clamp(value, 0.0f, 255.0f);
    if (noisy) dn += noise_sd[static_cast<int>(dn)] * rng.Gaussian();
    return static_cast<uint8_t>(std::clamp(dn + 0.5f, 0.0f, 255.0f));
  };

  for (int y = 0; y < h; ++y) {
    RowNoise rng(noise_seed, y);
    const RayF* ray_row = rays.row(y);
    const render::PixelHit* hit_row = &hits[static_cast<size_t>(y) * w];
    const float dy2 = static_cast<float>((y - pcy) * (y - pcy));
    uint16_t* label_row = &view.labels.data[static_cast<size_t>(y) * w];
    uint8_t* image_row = &view.image.data[static_cast<size_t>(y) * w * view.image.channels()];
    const int bayer_row[2] = {BayerChannel(format, 0, y), BayerChannel(format, 1, y)};
    for (int x = 0; x < w; ++x) {
      const RayF& r = ray_row[x];
      const render::PixelHit& hit = hit_row[x];
      float rgb[3] = {0.0f, 0.0f, 0.0f};
      uint16_t label = kLabelBackground;
      if (r.x != 0.0f || r.y != 0.0f || r.z != 0.0f) {
        if (hit.prim >= 0) {
          const render::Primitive& p = prims[hit.prim];
          shader.ShadePrimitive(p, render::Closest(p, r.x, r.y, r.z), r, rgb);
          label = segments[p.seg].label;
        } else {
          shader.ShadeBackground(r, rgb);
        }
        if (hit.front_prim >= 0 && hit.front_depth < hit.depth) {
          const render::Primitive& p = prims[hit.front_prim];
          float front[3];
          shader.ShadePrimitive(p, render::Closest(p, r.x, r.y, r.z), r, front);
          const float c = hit.front_cov;
          for (int k = 0; k < 3; ++k) rgb[k] = c * front[k] + (1.0f - c) * rgb[k];
          if (c >= 0.5f) label = segments[p.seg].label;
        }
      }
      label_row[x] = label;
      const float dx = static_cast<float>(x) - pcx_f;
      const float scale = gain * (1.0f - vig_k * (dx * dx + dy2));
      if (format == PixelFormat::kRgb8) {
        uint8_t* out = image_row + 3 * x;
        out[0] = to_dn(rgb[0] * scale, rng);
        out[1] = to_dn(rgb[1] * scale, rng);
        out[2] = to_dn(rgb[2] * scale, rng);
      } else if (format == PixelFormat::kMono8) {
        image_row[x] = to_dn((0.299f * rgb[0] + 0.587f * rgb[1] + 0.114f * rgb[2]) * scale, rng);
      } else {
        image_row[x] = to_dn(rgb[bayer_row[x & 1]] * scale, rng);
      }
    }
  }
  return view;
}

}  // namespace vb::sim
