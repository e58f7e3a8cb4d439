// SPDX-License-Identifier: Apache-2.0
// Test support for the bundle and calibration.yaml tests (bundle_test.cc,
// calibration_yaml_test.cc): a fresh directory per test, a standard three-camera bundle, and
// calibration.yaml written by hand with any one field replaceable. Test-only.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "workers/capture/bundle.h"

namespace vb::capture::bundle_test_util {


inline constexpr int kWidth = 64;
inline constexpr int kHeight = 48;

inline std::string Message(const absl::Status& s) { return std::string(s.message()); }

// A fresh directory per test, removed afterwards.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::path(::testing::TempDir()) /
           absl::StrCat("vb_bundle_", info->test_suite_name(), "_", info->name(), "_", getpid());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string BundleDir() const { return Path("bundle"); }
  std::string BundleFile(const std::string& name) const { return (dir_ / "bundle" / name).string(); }

  std::filesystem::path dir_;
};

using BundleFilesTest = TempDirTest;     // bundle-level behaviour without a prepared bundle
using BundlePngTest = TempDirTest;       // single PNG files
using CalibrationYamlTest = TempDirTest;  // calibration.yaml alone

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

inline CameraCalibration MakeCalibration(const std::string& name, int index) {
  CameraCalibration c;
  c.name = name;
  c.image_width = kWidth;
  c.image_height = kHeight;
  c.camera_matrix << 71.123456789012345, 0.0, 31.7 + index, 0.0, 70.98765432101234, 23.9, 0, 0, 1;
  c.distortion = {-0.123456789, 0.0456789, 1.5e-4, -2.5e-4, -0.0012345};
  c.rotation_camera_from_platform =
      Eigen::AngleAxisd(0.1 * (index + 1), Eigen::Vector3d(0.3, -1.0, 0.2).normalized())
          .toRotationMatrix();
  c.translation_camera_from_platform = Eigen::Vector3d(-0.12 * index, 0.013, 1.234567890123);
  return c;
}

inline Image MakeImage(PixelFormat format, int width, int height, uint32_t seed) {
  Image image(width, height, format);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  for (uint8_t& v : image.data) v = static_cast<uint8_t>(byte(rng));
  return image;
}

inline CaptureBundle MakeBundle() {
  CaptureBundle b;
  b.metadata.row = "row-07";
  b.metadata.vine_position_m = 12.4;
  b.metadata.captured_at = "2026-07-14T09:12:03Z";
  const PixelFormat formats[] = {PixelFormat::kRgb8, PixelFormat::kBayerRg8, PixelFormat::kMono8};
  for (int i = 0; i < 3; ++i) {
    const std::string name = absl::StrCat("cam", i);
    b.metadata.cameras.push_back({name, name + ".png", formats[i]});
    b.calibration.cameras.push_back(MakeCalibration(name, i));
    b.images.push_back(MakeImage(formats[i], kWidth, kHeight, 100 + i));
  }
  return b;
}

inline void ExpectSameCalibration(const CameraCalibration& a, const CameraCalibration& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.image_width, b.image_width);
  EXPECT_EQ(a.image_height, b.image_height);
  EXPECT_LE((a.camera_matrix - b.camera_matrix).cwiseAbs().maxCoeff(), 1e-12);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(a.distortion[i], b.distortion[i], 1e-12) << i;
  EXPECT_LE((a.rotation_camera_from_platform - b.rotation_camera_from_platform).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_LE(
      (a.translation_camera_from_platform - b.translation_camera_from_platform).cwiseAbs().maxCoeff(),
      1e-12);
}

// --- calibration.yaml written by hand, one field at a time replaceable ---

inline std::string YamlMatrix(int rows, int cols, const std::string& data) {
  return absl::StrCat("!!opencv-matrix\n      rows: ", rows, "\n      cols: ", cols,
                      "\n      dt: d\n      data: [ ", data, " ]\n");
}

struct YamlCamera {
  std::string name = "cam0";
  std::string width = "64";
  std::string height = "48";
  std::string camera_matrix = YamlMatrix(3, 3, "70., 0., 32., 0., 70., 24., 0., 0., 1.");
  std::string distortion = YamlMatrix(1, 5, "0., 0., 0., 0., 0.");
  std::string rotation = YamlMatrix(3, 3, "1., 0., 0., 0., 1., 0., 0., 0., 1.");
  std::string translation = YamlMatrix(3, 1, "0., 0., 1.");
};

inline std::string YamlText(const std::vector<YamlCamera>& cameras) {
  std::string text = "%YAML:1.0\n---\ncameras:\n";
  for (const YamlCamera& c : cameras) {
    absl::StrAppend(&text, "   - name: ", c.name, "\n     image_width: ", c.width,
                    "\n     image_height: ", c.height, "\n     camera_matrix: ", c.camera_matrix,
                    "     distortion_coefficients: ", c.distortion,
                    "     rotation_camera_from_platform: ", c.rotation,
                    "     translation_camera_from_platform: ", c.translation);
  }
  return text;
}

inline std::vector<YamlCamera> ThreeYamlCameras() {
  std::vector<YamlCamera> cams(3);
  for (int i = 0; i < 3; ++i) cams[i].name = absl::StrCat("cam", i);
  return cams;
}

// Writes the standard bundle; tests then break one thing in it.
class BundleTest : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    ASSERT_TRUE(WriteBundle(BundleDir(), MakeBundle()).ok());
  }
  // Replaces calibration.yaml with hand-written cameras.
  void WriteYaml(const std::vector<YamlCamera>& cameras) {
    WriteText(BundleFile("calibration.yaml"), YamlText(cameras));
  }
  absl::Status ReadStatus() { return ReadBundle(BundleDir()).status(); }
};

}  // namespace vb::capture::bundle_test_util
