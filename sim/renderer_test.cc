// SPDX-License-Identifier: Apache-2.0
#include "sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/render_rays.h"
#include "sim/rig.h"

namespace vb::sim {
namespace {

using ::testing::HasSubstr;

// One camera at (0, 0, 1.05) looking along +y, 640x512, 100 deg; optionally with lens distortion.
CameraCalibration TestCamera(bool distortion = false) {
  RigOptions o;
  o.camera_count = 1;
  o.toe_in = false;
  o.rig_y_m = 0.0;  // the rig's default is 0.12 m further back
  o.image_width = 640;
  o.image_height = 512;
  if (!distortion) o.k1 = o.k2 = o.p1 = o.p2 = o.k3 = 0.0;
  return MakeRig(o)->cameras[0];
}

Cane VerticalCane(int id, double x, double y, double radius) {
  Cane c;
  c.id = CaneId(id);
  c.kind = CaneKind::kCane;
  for (int i = 0; i <= 30; ++i) {
    c.polyline.points.emplace_back(x, y, 0.6 + 0.9 * i / 30.0);
    c.polyline.radii.push_back(radius);
  }
  return c;
}

Scene BaseScene() {
  Scene s;
  s.backdrop_y_m = 1.25;
  s.lights = {{{0.1, 0.0, 1.1}, 1.0}};
  return s;
}

RenderOptions Clean() {
  RenderOptions o;
  o.read_noise_dn = 0.0;
  o.shot_noise = 0.0;
  o.vignetting = 0.0;
  return o;
}

RenderedView MustRender(const Scene& scene, const CameraCalibration& camera,
                        const RenderOptions& options, uint64_t seed = 1) {
  auto view = Render(scene, camera, options, seed);
  EXPECT_TRUE(view.ok()) << view.status();
  return view.ok() ? *std::move(view) : RenderedView{};
}

Eigen::Vector2i Pixel(const CameraCalibration& c, const Eigen::Vector3d& p) {
  const Eigen::Vector2d uv = *c.Project(p);
  return {static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y()))};
}

TEST(Renderer, VerticalCaneIsLabelledAndBrownerThanTheBackdrop) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  scene.vine.canes.push_back(VerticalCane(7, 0.0, 0.8, 0.008));
  const RenderedView view = MustRender(scene, camera, Clean());
  ASSERT_EQ(view.image.width, 640);
  ASSERT_EQ(view.labels.height, 512);
  for (double z = 0.7; z <= 1.4; z += 0.05) {
    const Eigen::Vector2i px = Pixel(camera, {0.0, 0.8, z});
    EXPECT_EQ(view.labels.at(px.x(), px.y()), kLabelCaneBase + 7) << "z " << z;
    const uint8_t* cane = view.image.at(px.x(), px.y());
    const uint8_t* back = view.image.at(px.x() + 40, px.y());
    EXPECT_EQ(view.labels.at(px.x() + 40, px.y()), kLabelBackground);
    // The backdrop is blue; the cane is brown: more red than blue, and less blue than the backdrop.
    EXPECT_GT(back[2], back[0] + 20) << "z " << z;
    EXPECT_GT(cane[0], cane[2]) << "z " << z;
    EXPECT_LT(cane[2], back[2]) << "z " << z;
  }
}

TEST(Renderer, LabelsAgreeWithProjectionOfCanePoints) {
  const CameraCalibration camera = TestCamera(/*distortion=*/true);
  Scene scene = BaseScene();
  // Three separated slanted canes at different depths.
  for (int k = 0; k < 3; ++k) {
    Cane c;
    c.id = CaneId(10 + k);
    for (int i = 0; i <= 40; ++i) {
      const double f = i / 40.0;
      c.polyline.points.emplace_back(-0.5 + 0.4 * k + 0.3 * f, 0.7 + 0.1 * k, 0.6 + 0.8 * f);
      c.polyline.radii.push_back(0.007 - 0.003 * f);
    }
    scene.vine.canes.push_back(c);
  }
  const RenderedView view = MustRender(scene, camera, Clean());
  int total = 0, agree = 0;
  for (const Cane& c : scene.vine.canes) {
    for (const Eigen::Vector3d& p : c.polyline.Sample(0.01)) {
      const Eigen::Vector2i px = Pixel(camera, p);
      if (px.x() < 0 || px.y() < 0 || px.x() >= 640 || px.y() >= 512) continue;
      ++total;
      agree += view.labels.at(px.x(), px.y()) == kLabelCaneBase + c.id.value;
    }
  }
  ASSERT_GT(total, 200);
  EXPECT_GE(agree, total * 98 / 100) << agree << " of " << total;
}

TEST(Renderer, NearerCaneWinsTheLabelWhereCanesCross) {
  const CameraCalibration camera = TestCamera();
  for (bool vertical_in_front : {true, false}) {
    Scene scene = BaseScene();
    const double yv = vertical_in_front ? 0.6 : 0.9;
    const double yh = vertical_in_front ? 0.9 : 0.6;
    scene.vine.canes.push_back(VerticalCane(2, 0.0, yv, 0.01));
    Cane h;
    h.id = CaneId(3);
    // Horizontal at the camera height so it crosses the vertical cane on the optical axis.
    h.polyline.points = {{-0.5, yh, 1.05}, {0.5, yh, 1.05}};
    h.polyline.radii = {0.01, 0.01};
    scene.vine.canes.push_back(h);
    const RenderedView view = MustRender(scene, camera, Clean());
    const Eigen::Vector2i centre = Pixel(camera, {0.0, 1.0, 1.05});
    EXPECT_EQ(view.labels.at(centre.x(), centre.y()), kLabelCaneBase + (vertical_in_front ? 2 : 3));
    // Away from the crossing each cane keeps its own label.
    const Eigen::Vector2i up = Pixel(camera, {0.0, yv, 1.25});
    const Eigen::Vector2i side = Pixel(camera, {0.3, yh, 1.05});
    EXPECT_EQ(view.labels.at(up.x(), up.y()), kLabelCaneBase + 2);
    EXPECT_EQ(view.labels.at(side.x(), side.y()), kLabelCaneBase + 3);
  }
}

TEST(Renderer, ThinWireIsAThinLineWithPartiallyCoveredPixels) {
  const CameraCalibration camera = TestCamera();
  const double fx = camera.camera_matrix(0, 0);
  auto scene_with_wire = [](double radius) {
    Scene scene = BaseScene();
    Wire w;
    w.id = WireId(1);
    // Slightly sloped so the wire crosses pixel rows at every sub-pixel phase.
    w.points = {{-1.0, 0.8, 1.18}, {1.0, 0.8, 1.22}};
    w.radius = radius;
    scene.vine.wires.push_back(w);
    return scene;
  };
  const RenderedView thin = MustRender(scene_with_wire(0.0015), camera, Clean());
  // A thick wire gives the colour of pixels the wire covers completely.
  const RenderedView thick = MustRender(scene_with_wire(0.006), camera, Clean());
  const double width_px = 2 * 0.0015 * fx / 0.8;  // ~1 px at this resolution
  int mixed_columns = 0, columns = 0;
  for (int x = 200; x < 440; x += 7) {
    const double xw = (x - camera.camera_matrix(0, 2)) / fx * 0.8;
    const int v = Pixel(camera, {xw, 0.8, 1.2 + 0.02 * xw}).y();
    int wire_rows = 0;
    for (int y = v - 6; y <= v + 6; ++y) wire_rows += thin.labels.at(x, y) == kLabelWire;
    EXPECT_GE(wire_rows, 1) << "x " << x;
    EXPECT_LE(wire_rows, 2) << "x " << x;
    // Red channel: the metallic wire is much brighter than the blue backdrop in red.
    const double back = thin.image.at(x, v - 8)[0];
    double full = 0.0;  // brightest point across the thick wire (its specular highlight)
    for (int y = v - 6; y <= v + 6; ++y) full = std::max(full, static_cast<double>(thick.image.at(x, y)[0]));
    ASSERT_GT(full, back + 60) << "x " << x;
    double excess = 0.0;
    bool mixed = false;
    for (int y = v - 4; y <= v + 4; ++y) {
      const double r = thin.image.at(x, y)[0];
      excess += r - back;
      if (r > back + 0.1 * (full - back) && r < full - 0.1 * (full - back)) mixed = true;
      // (A thin wire pixel may catch the specular highlight that the thick wire's pixels straddle.)
      EXPECT_LE(r, back + 1.5 * (full - back)) << "x " << x << " y " << y;
    }
    // Coverage integrates to the wire's width in pixels (its shading varies across the
    // cylinder, hence the tolerance).
    EXPECT_GT(excess / (full - back), 0.5 * width_px) << "x " << x;
    EXPECT_LT(excess / (full - back), 1.6 * width_px) << "x " << x;
    mixed_columns += mixed;
    ++columns;
  }
  // Most columns have a pixel the wire only partly covers.
  EXPECT_GE(mixed_columns, columns * 2 / 3);
}

TEST(Renderer, ShadowsDarkenTheBackdropBehindACane) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  const Eigen::Vector3d light(0.25, 0.0, 1.05);
  scene.lights = {{light, 1.0}};
  scene.vine.canes.push_back(VerticalCane(4, 0.0, 0.8, 0.012));
  // Where the light's ray past the cane at z = 1.05 meets the backdrop.
  const Eigen::Vector3d on_cane(0.0, 0.8, 1.05);
  const Eigen::Vector3d shadow = light + (on_cane - light) * (1.25 - light.y()) / (0.8 - light.y());
  RenderOptions with = Clean();
  RenderOptions without = Clean();
  without.shadows = false;
  const RenderedView a = MustRender(scene, camera, with);
  const RenderedView b = MustRender(scene, camera, without);
  const Eigen::Vector2i px = Pixel(camera, shadow);
  ASSERT_EQ(a.labels.at(px.x(), px.y()), kLabelBackground);
  const int lit = b.image.at(px.x(), px.y())[2];
  const int dark = a.image.at(px.x(), px.y())[2];
  EXPECT_LT(dark, 0.6 * lit) << "lit " << lit << " shadowed " << dark;
  // Far from the shadow the backdrop is unchanged.
  const Eigen::Vector2i far = Pixel(camera, {0.5, 1.25, 1.05});
  EXPECT_NEAR(a.image.at(far.x(), far.y())[2], b.image.at(far.x(), far.y())[2], 1);
}

TEST(Renderer, CaneInFrontShadowsCaneBehind) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  // The light above the camera, so the shadow of the front cane on the back cane is visible.
  const Eigen::Vector3d light(0.0, 0.0, 1.25);
  scene.lights = {{light, 1.0}};
  Cane front;
  front.id = CaneId(2);
  front.polyline.points = {{-0.4, 0.5, 1.05}, {0.4, 0.5, 1.05}};
  front.polyline.radii = {0.01, 0.01};
  scene.vine.canes.push_back(front);
  scene.vine.canes.push_back(VerticalCane(3, 0.15, 0.9, 0.015));
  // Where the light's ray past the front cane's axis meets the front of the back cane.
  const double y_back = 0.9 - 0.015;
  const Eigen::Vector3d shaded(0.15, y_back, 1.25 + (1.05 - 1.25) * y_back / 0.5);
  RenderOptions without = Clean();
  without.shadows = false;
  const RenderedView a = MustRender(scene, camera, Clean());
  const RenderedView b = MustRender(scene, camera, without);
  const Eigen::Vector2i px = Pixel(camera, shaded);
  ASSERT_EQ(a.labels.at(px.x(), px.y()), kLabelCaneBase + 3);
  EXPECT_LT(a.image.at(px.x(), px.y())[0], 0.7 * b.image.at(px.x(), px.y())[0]);
}

TEST(Renderer, NoiseIsDeterministicInTheSeed) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  scene.vine.canes.push_back(VerticalCane(5, 0.0, 0.8, 0.01));
  RenderOptions o;
  o.read_noise_dn = 3.0;
  const RenderedView a = MustRender(scene, camera, o, 11);
  const RenderedView b = MustRender(scene, camera, o, 11);
  const RenderedView c = MustRender(scene, camera, o, 12);
  EXPECT_EQ(a.image.data, b.image.data);
  EXPECT_NE(a.image.data, c.image.data);
  EXPECT_EQ(a.labels.data, c.labels.data);
  // The noise has about the requested size and no bias.
  o.read_noise_dn = 0.0;
  o.shot_noise = 0.0;
  o.read_noise_dn = 0.0;
  RenderOptions noisy = o;
  noisy.read_noise_dn = 3.0;
  const RenderedView clean = MustRender(scene, camera, o, 1);
  const RenderedView n = MustRender(scene, camera, noisy, 1);
  double sum = 0.0, sum2 = 0.0;
  int count = 0;
  for (size_t i = 0; i < clean.image.data.size(); ++i) {
    const int v = clean.image.data[i];
    if (v < 20 || v > 235) continue;  // away from clamping
    const double d = static_cast<double>(n.image.data[i]) - v;
    sum += d;
    sum2 += d * d;
    ++count;
  }
  ASSERT_GT(count, 10000);
  EXPECT_NEAR(sum / count, 0.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum2 / count), std::sqrt(9.0 + 1.0 / 12.0), 0.3);
}

TEST(Renderer, BayerMosaicsSampleTheRgbRenderInTheirPattern) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  scene.vine.canes.push_back(VerticalCane(5, 0.0, 0.8, 0.01));
  RenderOptions o = Clean();
  o.vignetting = 0.3;
  const RenderedView rgb = MustRender(scene, camera, o);
  // Channel (0 R, 1 G, 2 B) at (x even/odd, y even/odd): [row0 col0, row0 col1, row1 col0, row1 col1].
  const std::pair<PixelFormat, std::array<int, 4>> patterns[] = {
      {PixelFormat::kBayerRg8, {0, 1, 1, 2}},
      {PixelFormat::kBayerGb8, {1, 2, 0, 1}},
      {PixelFormat::kBayerGr8, {1, 0, 2, 1}},
      {PixelFormat::kBayerBg8, {2, 1, 1, 0}}};
  for (const auto& [format, channels] : patterns) {
    o.pixel_format = format;
    const RenderedView bayer = MustRender(scene, camera, o);
    ASSERT_EQ(bayer.image.channels(), 1);
    int mismatches = 0;
    for (int y = 0; y < 512; ++y) {
      for (int x = 0; x < 640; ++x) {
        const int ch = channels[(y % 2) * 2 + (x % 2)];
        mismatches += bayer.image.at(x, y)[0] != rgb.image.at(x, y)[ch];
      }
    }
    EXPECT_EQ(mismatches, 0) << PixelFormatName(format);
    EXPECT_EQ(bayer.labels.data, rgb.labels.data);
  }
  o.pixel_format = PixelFormat::kMono8;
  const RenderedView mono = MustRender(scene, camera, o);
  for (int y = 0; y < 512; y += 7) {
    for (int x = 0; x < 640; x += 7) {
      const uint8_t* p = rgb.image.at(x, y);
      EXPECT_NEAR(mono.image.at(x, y)[0], 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2], 1.5);
    }
  }
}

TEST(Renderer, DistortedCameraRendersAStraightWireAsTheCurveProjectPredicts) {
  const CameraCalibration camera = TestCamera(/*distortion=*/true);
  Scene scene = BaseScene();
  Wire w;
  w.id = WireId(1);
  w.points = {{-1.5, 0.8, 1.5}, {1.5, 0.8, 1.5}};
  scene.vine.wires.push_back(w);
  const RenderedView view = MustRender(scene, camera, Clean());
  double v_min = 1e9, v_max = -1e9;
  int checked = 0;
  for (double x = -1.2; x <= 1.2; x += 0.02) {
    const auto uv = camera.Project({x, 0.8, 1.5});
    if (!uv || !camera.InImage(*uv) || uv->x() < 2 || uv->x() > 637) continue;
    const int u = static_cast<int>(std::lround(uv->x()));
    // The labelled wire row nearest the predicted one.
    double best = 1e9;
    for (int y = 0; y < 512; ++y) {
      if (view.labels.at(u, y) == kLabelWire) best = std::min(best, std::abs(y - uv->y()));
    }
    EXPECT_LE(best, 1.0) << "x " << x;
    v_min = std::min(v_min, uv->y());
    v_max = std::max(v_max, uv->y());
    ++checked;
  }
  EXPECT_GT(checked, 50);
  // Barrel distortion bends the straight wire by many pixels across the image.
  EXPECT_GT(v_max - v_min, 10.0);
}

TEST(Renderer, LabelsHeadPostAndNeighbours) {
  const CameraCalibration camera = TestCamera();
  Scene scene = BaseScene();
  scene.vine.head.spheres.push_back({{0.0, 0.8, 1.0}, 0.03});
  Post post;
  post.base = {0.4, 0.8, 0.0};
  post.top = {0.4, 0.8, 1.9};
  scene.vine.posts.push_back(post);
  VineModel n;
  Cane c = VerticalCane(1, -0.4, 0.8, 0.01);
  n.canes.push_back(c);
  scene.neighbours.push_back(n);
  const RenderedView view = MustRender(scene, camera, Clean());
  const Eigen::Vector2i head = Pixel(camera, {0.0, 0.77, 1.0});
  const Eigen::Vector2i p = Pixel(camera, {0.4, 0.76, 1.2});
  const Eigen::Vector2i o = Pixel(camera, {-0.4, 0.79, 1.0});
  EXPECT_EQ(view.labels.at(head.x(), head.y()), kLabelHead);
  EXPECT_EQ(view.labels.at(p.x(), p.y()), kLabelPost);
  EXPECT_EQ(view.labels.at(o.x(), o.y()), kLabelOtherVine);
}

TEST(Renderer, InvalidOptionsAreRejectedNamingTheField) {
  const CameraCalibration camera = TestCamera();
  const Scene scene = BaseScene();
  auto expect_field = [&](const RenderOptions& o, const std::string& field) {
    const absl::Status s = Render(scene, camera, o, 1).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(std::string(s.message()), HasSubstr(field));
  };
  RenderOptions o;
  o.exposure = 0.0;
  expect_field(o, "exposure");
  o = {};
  o.read_noise_dn = -1.0;
  expect_field(o, "read_noise_dn");
  o = {};
  o.shot_noise = NAN;
  expect_field(o, "shot_noise");
  o = {};
  o.vignetting = 1.5;
  expect_field(o, "vignetting");
  o = {};
  o.ambient = -0.1;
  expect_field(o, "ambient");
  o = {};
  o.light_radius_m = -1.0;
  expect_field(o, "light_radius_m");
  o = {};
  o.pixel_format = static_cast<PixelFormat>(99);
  expect_field(o, "pixel_format");

  CameraCalibration bad = camera;
  bad.camera_matrix(0, 0) = 0.0;
  EXPECT_THAT(std::string(Render(scene, bad, RenderOptions{}, 1).status().message()),
              HasSubstr("camera_matrix"));
  const RayTable other(TestCamera(/*distortion=*/true));
  EXPECT_THAT(std::string(Render(scene, camera, other, RenderOptions{}, 1).status().message()),
              HasSubstr("ray table"));
}

}  // namespace
}  // namespace vb::sim
