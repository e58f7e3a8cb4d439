// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/bundle.h"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "opencv2/core.hpp"
#include "opencv2/imgcodecs.hpp"

namespace vb::capture {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr int kWidth = 64;
constexpr int kHeight = 48;

std::string Message(const absl::Status& s) { return std::string(s.message()); }

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

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

CameraCalibration MakeCalibration(const std::string& name, int index) {
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

Image MakeImage(PixelFormat format, int width, int height, uint32_t seed) {
  Image image(width, height, format);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  for (uint8_t& v : image.data) v = static_cast<uint8_t>(byte(rng));
  return image;
}

CaptureBundle MakeBundle() {
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

void ExpectSameCalibration(const CameraCalibration& a, const CameraCalibration& b) {
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

std::string YamlMatrix(int rows, int cols, const std::string& data) {
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

std::string YamlText(const std::vector<YamlCamera>& cameras) {
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

std::vector<YamlCamera> ThreeYamlCameras() {
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

TEST_F(BundleTest, RoundTripsThreeCameraBundle) {
  const CaptureBundle original = MakeBundle();
  absl::StatusOr<CaptureBundle> read = ReadBundle(BundleDir());
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->metadata.row, original.metadata.row);
  EXPECT_EQ(read->metadata.vine_position_m, original.metadata.vine_position_m);
  EXPECT_EQ(read->metadata.captured_at, original.metadata.captured_at);
  ASSERT_EQ(read->metadata.cameras.size(), 3u);
  ASSERT_EQ(read->images.size(), 3u);
  ASSERT_EQ(read->calibration.cameras.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(read->metadata.cameras[i].name, original.metadata.cameras[i].name);
    EXPECT_EQ(read->metadata.cameras[i].image, original.metadata.cameras[i].image);
    EXPECT_EQ(read->metadata.cameras[i].pixel_format, original.metadata.cameras[i].pixel_format);
    ExpectSameCalibration(read->calibration.cameras[i], original.calibration.cameras[i]);
    ExpectSameCalibration(read->CalibrationOf(i), original.calibration.cameras[i]);
    EXPECT_EQ(read->images[i].width, kWidth);
    EXPECT_EQ(read->images[i].height, kHeight);
    EXPECT_EQ(read->images[i].format, original.images[i].format);
    EXPECT_TRUE(read->images[i].data == original.images[i].data);
  }
  // Every file was renamed into place.
  for (const auto& entry : std::filesystem::directory_iterator(BundleDir())) {
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
  }
}

TEST_F(BundleTest, ReadsCamerasInMetadataOrderWhateverTheCalibrationOrder) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  std::swap(cams[0], cams[2]);
  cams[2].camera_matrix = YamlMatrix(3, 3, "55., 0., 32., 0., 56., 24., 0., 0., 1.");  // cam0
  WriteYaml(cams);
  absl::StatusOr<CaptureBundle> read = ReadBundle(BundleDir());
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->calibration.cameras[0].name, "cam2");
  EXPECT_EQ(read->CalibrationOf(0).name, "cam0");
  EXPECT_EQ(read->CalibrationOf(0).camera_matrix(0, 0), 55.0);
  EXPECT_EQ(read->CalibrationOf(2).name, "cam2");
}

TEST_F(BundlePngTest, Rgb8PngIsStoredInRgbOrder) {
  Image red(4, 3, PixelFormat::kRgb8);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) red.at(x, y)[0] = 255;
  }
  ASSERT_TRUE(WritePng(Path("red.png"), red).ok());
  // OpenCV decodes into BGR: red must land in channel 2.
  const cv::Mat bgr = cv::imread(Path("red.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 2), cv::Vec3b(0, 0, 255));
}

TEST_F(BundlePngTest, LabelPngRoundTrips) {
  LabelImage labels(7, 5);
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 7; ++x) labels.at(x, y) = static_cast<uint16_t>(x * 9000 + y * 77 + 1);
  }
  labels.at(6, 4) = 65535;
  ASSERT_TRUE(WriteLabelPng(Path("labels.png"), labels).ok());
  absl::StatusOr<LabelImage> read = ReadLabelPng(Path("labels.png"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->width, 7);
  EXPECT_EQ(read->height, 5);
  EXPECT_EQ(read->data, labels.data);
}

TEST_F(BundlePngTest, ReadLabelPngRejects8BitPng) {
  ASSERT_TRUE(WritePng(Path("mono.png"), MakeImage(PixelFormat::kMono8, 5, 4, 1)).ok());
  const absl::Status s = ReadLabelPng(Path("mono.png")).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("mono.png"), HasSubstr("8-bit"), HasSubstr("16-bit")));
}

TEST_F(BundlePngTest, ReadPngOfMissingFileIsNotFound) {
  EXPECT_EQ(ReadPng(Path("nope.png"), PixelFormat::kMono8).status().code(),
            absl::StatusCode::kNotFound);
}

TEST_F(BundlePngTest, ReadPngRejectsNonPngFile) {
  WriteText(Path("fake.png"), "GIF89a not a png at all");
  const absl::Status s = ReadPng(Path("fake.png"), PixelFormat::kMono8).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("fake.png"), HasSubstr("not a PNG")));
}

TEST_F(BundlePngTest, WritePngRejectsInconsistentImage) {
  Image image(4, 4, PixelFormat::kRgb8);
  image.data.resize(10);
  const absl::Status s = WritePng(Path("bad.png"), image);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("48"));
  EXPECT_FALSE(std::filesystem::exists(Path("bad.png")));
}

TEST_F(BundleFilesTest, ReadBundleOfMissingDirectoryIsNotFound) {
  const absl::Status s = ReadBundle(Path("does_not_exist")).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(Message(s), HasSubstr("does_not_exist"));
}

TEST_F(BundleFilesTest, ReadBundleOfPlainFileRejects) {
  WriteText(Path("file"), "x");
  EXPECT_EQ(ReadBundle(Path("file")).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(BundleTest, MissingCaptureJsonRejects) {
  std::filesystem::remove(BundleFile("capture.json"));
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("capture.json"));
}

TEST_F(BundleTest, MalformedCaptureJsonRejects) {
  WriteText(BundleFile("capture.json"), "{\"format\": \"vinebot.capture.v1\", \"row\": ");
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("capture.json"), HasSubstr("JSON")));
}

TEST_F(BundleTest, MissingCalibrationYamlRejects) {
  std::filesystem::remove(BundleFile("calibration.yaml"));
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("calibration.yaml"));
}

TEST_F(BundleTest, MissingImageFileRejects) {
  std::filesystem::remove(BundleFile("cam1.png"));
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam1.png"), HasSubstr("no such file")));
}

TEST_F(BundleTest, TruncatedPngRejects) {
  const std::string png = ReadText(BundleFile("cam0.png"));
  ASSERT_GT(png.size(), 100u);
  WriteText(BundleFile("cam0.png"), png.substr(0, png.size() / 2));
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam0.png"), HasSubstr("truncated or corrupt")));
}

TEST_F(BundleTest, ImageSizeDisagreeingWithCalibrationRejects) {
  ASSERT_TRUE(WritePng(BundleFile("cam2.png"), MakeImage(PixelFormat::kMono8, 32, 48, 7)).ok());
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam2.png"), HasSubstr("'cam2'"), HasSubstr("32x48"),
                                HasSubstr("64x48")));
}

TEST_F(BundleTest, AbsurdPngHeaderSizeRejectsWithoutDecoding) {
  std::string png = ReadText(BundleFile("cam1.png"));
  ASSERT_EQ(png.compare(12, 4, "IHDR"), 0);
  png.replace(16, 8, std::string("\x7f\xff\xff\xff\x7f\xff\xff\xff", 8));  // width, height
  WriteText(BundleFile("cam1.png"), png);
  absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam1.png"), HasSubstr("2147483647x2147483647")));
  s = ReadPng(BundleFile("cam1.png"), PixelFormat::kBayerRg8).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("header claims"));
}

TEST_F(BundleTest, SixteenBitImageRejects) {
  cv::Mat deep(kHeight, kWidth, CV_16UC3, cv::Scalar(1000, 2000, 3000));
  ASSERT_TRUE(cv::imwrite(BundleFile("cam0.png"), deep));
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam0.png"), HasSubstr("16-bit"), HasSubstr("rgb8")));
}

TEST_F(BundleTest, WrongChannelCountRejects) {
  // A colour PNG where the mono8 camera is expected.
  ASSERT_TRUE(WritePng(BundleFile("cam2.png"), MakeImage(PixelFormat::kRgb8, kWidth, kHeight, 3)).ok());
  absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam2.png"), HasSubstr("3 channel"), HasSubstr("mono8")));

  // And a single-channel PNG where rgb8 is expected.
  ASSERT_TRUE(WritePng(BundleFile("cam2.png"), MakeImage(PixelFormat::kMono8, kWidth, kHeight, 3)).ok());
  ASSERT_TRUE(WritePng(BundleFile("cam0.png"), MakeImage(PixelFormat::kMono8, kWidth, kHeight, 3)).ok());
  s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cam0.png"), HasSubstr("1 channel"), HasSubstr("rgb8")));
}

TEST_F(BundleTest, UnknownPixelFormatRejects) {
  std::string json = ReadText(BundleFile("capture.json"));
  const size_t at = json.find("bayer_rg8");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, 9, "bayer_xy16");
  WriteText(BundleFile("capture.json"), json);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("capture.json"), HasSubstr("cameras[1]"),
                                HasSubstr("pixel_format"), HasSubstr("bayer_xy16")));
}

TEST_F(BundleTest, CameraWithoutCalibrationRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams.pop_back();  // cam2 is captured but not calibrated
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("'cam2'"), HasSubstr("calibration.yaml")));
}

TEST_F(BundleTest, HandWrittenCalibrationIsAccepted) {
  // Guards the rejection tests below: only the one field they change is wrong.
  WriteYaml(ThreeYamlCameras());
  EXPECT_TRUE(ReadStatus().ok()) << ReadStatus();
}

TEST_F(BundleTest, NonFiniteCameraMatrixRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[1].camera_matrix = YamlMatrix(3, 3, "70., 0., .nan, 0., 70., 24., 0., 0., 1.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("calibration.yaml"), HasSubstr("cam1"),
                                HasSubstr("camera_matrix"), HasSubstr("not finite")));
}

TEST_F(BundleTest, SingularCameraMatrixRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[0].camera_matrix = YamlMatrix(3, 3, "0., 0., 32., 0., 70., 24., 0., 0., 1.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("calibration.yaml"), HasSubstr("cam0"),
                                HasSubstr("camera_matrix"), HasSubstr("singular")));
}

TEST_F(BundleTest, NonOrthonormalRotationRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[2].rotation = YamlMatrix(3, 3, "1., 0., 0., 0., 1., 0.01, 0., 0., 1.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("calibration.yaml"), HasSubstr("cam2"),
                                HasSubstr("rotation_camera_from_platform")));
}

TEST_F(BundleTest, ReflectionRotationRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[2].rotation = YamlMatrix(3, 3, "1., 0., 0., 0., 1., 0., 0., 0., -1.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("rotation_camera_from_platform"));
}

TEST_F(BundleTest, MalformedYamlRejects) {
  WriteText(BundleFile("calibration.yaml"),
            "%YAML:1.0\n---\ncameras:\n   - name: cam0\n     image_width: [ 64,\n  : }\n");
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("calibration.yaml"), HasSubstr("malformed YAML at line 6")));
}

TEST_F(CalibrationYamlTest, AcceptsFileWithoutYamlDirective) {
  std::string yaml = YamlText({YamlCamera()});
  ASSERT_EQ(yaml.rfind("%YAML:1.0\n---\n", 0), 0u);
  WriteText(Path("plain.yaml"), yaml.substr(std::string("%YAML:1.0\n---\n").size()));
  absl::StatusOr<RigCalibration> rig = ReadCalibrationYaml(Path("plain.yaml"));
  ASSERT_TRUE(rig.ok()) << rig.status();
  EXPECT_EQ(rig->cameras[0].camera_matrix(0, 2), 32.0);
}

TEST_F(BundleTest, WrongMatrixShapeRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[1].camera_matrix = YamlMatrix(3, 2, "70., 0., 0., 70., 0., 0.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("calibration.yaml: cameras[1] (cam1).camera_matrix: "
                                    "expected 3x3, got 3x2"));
}

TEST_F(BundleTest, MatrixDataCountDisagreeingWithShapeRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[0].translation = YamlMatrix(3, 1, "0., 1.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("translation_camera_from_platform.data"),
                                HasSubstr("expected 3 numbers")));
}

TEST_F(BundleTest, NonNumericMatrixEntryRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[0].distortion = YamlMatrix(1, 5, "0., 0., zero, 0., 0.");
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("distortion_coefficients.data[2]"),
                                HasSubstr("expected a number")));
}

TEST_F(BundleTest, PlainSequenceInsteadOfMatrixRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[0].rotation = "[ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]\n";
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("rotation_camera_from_platform"),
                                HasSubstr("!!opencv-matrix"), HasSubstr("sequence")));
}

TEST_F(BundleTest, WrongFieldTypeRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[1].width = "wide";
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("cameras[1] (cam1).image_width"),
                                HasSubstr("expected an integer"), HasSubstr("a string")));
}

TEST_F(BundleTest, MissingFieldRejects) {
  std::string yaml = YamlText(ThreeYamlCameras());
  const size_t at = yaml.find("     image_height: 48\n");
  ASSERT_NE(at, std::string::npos);
  yaml.erase(at, std::string("     image_height: 48\n").size());
  WriteText(BundleFile("calibration.yaml"), yaml);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("cameras[0] (cam0).image_height: missing"));
}

TEST_F(BundleTest, DuplicateCalibrationNameRejects) {
  std::vector<YamlCamera> cams = ThreeYamlCameras();
  cams[2].name = "cam1";
  WriteYaml(cams);
  const absl::Status s = ReadStatus();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), AllOf(HasSubstr("calibration.yaml"), HasSubstr("duplicate")));
}

TEST_F(BundleTest, EmptyOrWrongTopLevelYamlRejects) {
  for (const std::string& text : {std::string(""), std::string("%YAML:1.0\n---\nrig: 3\n"),
                                 std::string("%YAML:1.0\n---\ncameras: 3\n"),
                                 std::string("%YAML:1.0\n---\ncameras: []\n"),
                                 std::string("%YAML:1.0\n---\ncameras: [ 1, 2 ]\n"),
                                 std::string("[ 1, 2, 3 ]\n")}) {
    SCOPED_TRACE(text);
    WriteText(BundleFile("calibration.yaml"), text);
    const absl::Status s = ReadStatus();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), HasSubstr("calibration.yaml"));
  }
}

// Random damage to any file of the bundle yields OK or INVALID_ARGUMENT, never a crash.
TEST_F(BundleTest, CorruptedFilesNeverCrash) {
  const std::string files[] = {"capture.json", "calibration.yaml", "cam0.png", "cam1.png"};
  std::mt19937 rng(42);
  for (int trial = 0; trial < 80; ++trial) {
    const std::string path = BundleFile(files[trial % 4]);
    const std::string original = ReadText(path);
    std::string damaged = original;
    if (trial % 3 == 0) {
      damaged.resize(std::uniform_int_distribution<size_t>(0, damaged.size())(rng));
    } else {
      for (int k = 0; k < 1 + trial % 5; ++k) {
        damaged[std::uniform_int_distribution<size_t>(0, damaged.size() - 1)(rng)] =
            static_cast<char>(rng());
      }
    }
    WriteText(path, damaged);
    const absl::Status s = ReadStatus();
    EXPECT_TRUE(s.ok() || s.code() == absl::StatusCode::kInvalidArgument) << trial << ": " << s;
    WriteText(path, original);
  }
  EXPECT_TRUE(ReadStatus().ok());
}

TEST_F(BundleFilesTest, WriteBundleRejectsInconsistentBundle) {
  {
    CaptureBundle b = MakeBundle();
    b.images.pop_back();
    const absl::Status s = WriteBundle(BundleDir(), b);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), HasSubstr("2 images for 3 cameras"));
  }
  {
    CaptureBundle b = MakeBundle();
    b.images[1] = MakeImage(PixelFormat::kBayerRg8, 32, 32, 1);
    const absl::Status s = WriteBundle(BundleDir(), b);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), AllOf(HasSubstr("cam1"), HasSubstr("32x32"), HasSubstr("64x48")));
  }
  {
    CaptureBundle b = MakeBundle();
    b.images[1].format = PixelFormat::kBayerGb8;
    const absl::Status s = WriteBundle(BundleDir(), b);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), AllOf(HasSubstr("bayer_gb8"), HasSubstr("bayer_rg8")));
  }
  {
    CaptureBundle b = MakeBundle();
    b.calibration.cameras.erase(b.calibration.cameras.begin());
    const absl::Status s = WriteBundle(BundleDir(), b);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), AllOf(HasSubstr("'cam0'"), HasSubstr("no calibration")));
  }
  {
    CaptureBundle b = MakeBundle();
    b.metadata.cameras[2].image = "cam0.png";
    const absl::Status s = WriteBundle(BundleDir(), b);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(Message(s), HasSubstr("clashes"));
  }
  {
    CaptureBundle b = MakeBundle();
    b.calibration.cameras[0].camera_matrix(1, 1) = -5.0;
    EXPECT_EQ(WriteBundle(BundleDir(), b).code(), absl::StatusCode::kInvalidArgument);
  }
  EXPECT_FALSE(std::filesystem::exists(BundleDir()));
}

TEST_F(BundleFilesTest, WriteBundleCreatesNestedDirectories) {
  CaptureBundle b = MakeBundle();
  b.metadata.cameras[0].image = "images/left.png";
  const std::string dir = Path("a/b/bundle");
  ASSERT_TRUE(WriteBundle(dir, b).ok());
  absl::StatusOr<CaptureBundle> read = ReadBundle(dir);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->images[0].data, b.images[0].data);
}

TEST_F(CalibrationYamlTest, RoundTripsAndAcceptsColumnDistortion) {
  RigCalibration rig;
  rig.cameras = {MakeCalibration("left", 0), MakeCalibration("right", 1)};
  ASSERT_TRUE(WriteCalibrationYaml(Path("calibration.yaml"), rig).ok());
  absl::StatusOr<RigCalibration> read = ReadCalibrationYaml(Path("calibration.yaml"));
  ASSERT_TRUE(read.ok()) << read.status();
  ASSERT_EQ(read->cameras.size(), 2u);
  for (size_t i = 0; i < 2; ++i) ExpectSameCalibration(read->cameras[i], rig.cameras[i]);

  YamlCamera cam;
  cam.distortion = YamlMatrix(5, 1, "0.1, 0.2, 0.3, 0.4, 0.5");
  WriteText(Path("column.yaml"), YamlText({cam}));
  read = ReadCalibrationYaml(Path("column.yaml"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->cameras[0].distortion[4], 0.5);
}

// The platform's fiducials travel in calibration.yaml; a file without them (every bundle written
// before they existed, as the one above) reads with none.
TEST_F(CalibrationYamlTest, RoundTripsFiducials) {
  RigCalibration rig;
  rig.cameras = {MakeCalibration("left", 0), MakeCalibration("right", 1)};
  ASSERT_TRUE(WriteCalibrationYaml(Path("plain.yaml"), rig).ok());
  absl::StatusOr<RigCalibration> read = ReadCalibrationYaml(Path("plain.yaml"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_TRUE(read->fiducials.empty());

  rig.fiducials = {{"fid0", Eigen::Vector3d(-0.9, 1.25, 0.3), 0.02},
                   {"fid1", Eigen::Vector3d(1.1, 1.25, 1.75), 0.025}};
  ASSERT_TRUE(WriteCalibrationYaml(Path("calibration.yaml"), rig).ok());
  read = ReadCalibrationYaml(Path("calibration.yaml"));
  ASSERT_TRUE(read.ok()) << read.status();
  ASSERT_EQ(read->fiducials.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(read->fiducials[i].name, rig.fiducials[i].name);
    EXPECT_EQ(read->fiducials[i].position_in_platform, rig.fiducials[i].position_in_platform);
    EXPECT_EQ(read->fiducials[i].radius_m, rig.fiducials[i].radius_m);
  }
}

TEST_F(CalibrationYamlTest, ReadRejectsAFiducialWithoutRadius) {
  WriteText(Path("bad.yaml"), YamlText({YamlCamera{}}) +
                                  "fiducials:\n   - name: fid0\n     position_in_platform: " +
                                  YamlMatrix(3, 1, "0., 1.25, 0.3"));
  const absl::StatusOr<RigCalibration> read = ReadCalibrationYaml(Path("bad.yaml"));
  ASSERT_FALSE(read.ok());
  EXPECT_THAT(Message(read.status()), HasSubstr("fiducials[0] (fid0).radius_m"));
}

TEST_F(CalibrationYamlTest, ProjectsLikeTheCalibration) {
  // The written file is the model of core/calibration.h: x_cam = R x_platform + t.
  RigCalibration rig;
  rig.cameras = {MakeCalibration("cam0", 1)};
  ASSERT_TRUE(WriteCalibrationYaml(Path("c.yaml"), rig).ok());
  cv::FileStorage fs(Path("c.yaml"), cv::FileStorage::READ);
  cv::Mat r, t;
  fs["cameras"][0]["rotation_camera_from_platform"] >> r;
  fs["cameras"][0]["translation_camera_from_platform"] >> t;
  ASSERT_EQ(r.rows, 3);
  ASSERT_EQ(t.rows, 3);
  const Eigen::Vector3d p(0.3, 1.2, 0.8);
  const Eigen::Vector3d expected = rig.cameras[0].camera_from_platform() * p;
  for (int i = 0; i < 3; ++i) {
    const double got = r.at<double>(i, 0) * p.x() + r.at<double>(i, 1) * p.y() +
                       r.at<double>(i, 2) * p.z() + t.at<double>(i, 0);
    EXPECT_NEAR(got, expected[i], 1e-12);
  }
}

TEST_F(CalibrationYamlTest, ReadOfMissingFileIsNotFound) {
  EXPECT_EQ(ReadCalibrationYaml(Path("none.yaml")).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(CalibrationYamlTest, WriteRejectsInvalidRig) {
  RigCalibration rig;
  rig.cameras = {MakeCalibration("cam0", 0)};
  rig.cameras[0].translation_camera_from_platform.x() = std::nan("");
  const absl::Status s = WriteCalibrationYaml(Path("c.yaml"), rig);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("translation_camera_from_platform"));
  EXPECT_FALSE(std::filesystem::exists(Path("c.yaml")));
}

// --- demosaicing ---

struct BayerCase {
  PixelFormat format;
  const char* layout;  // colours of (0,0) (1,0) (0,1) (1,1), PFNC naming
};

void PrintTo(const BayerCase& c, std::ostream* os) { *os << PixelFormatName(c.format); }

class DemosaicTest : public ::testing::TestWithParam<BayerCase> {};

// A 4x4 grid of 16x16 flat patches of distinct colours, mosaicked by hand, must come back with
// the right colour at every patch centre. A pattern mix-up swaps or mixes channels and fails.
TEST_P(DemosaicTest, RecoversFlatColourPatches) {
  const BayerCase& c = GetParam();
  constexpr int kPatch = 16;
  constexpr int kGrid = 4;
  std::vector<std::array<uint8_t, 3>> colours;
  for (int i = 0; i < kGrid * kGrid; ++i) {
    colours.push_back({static_cast<uint8_t>(20 + 37 * i % 220), static_cast<uint8_t>(240 - 53 * i % 200),
                       static_cast<uint8_t>(10 + 71 * (i + 3) % 230)});
  }
  Image mosaic(kPatch * kGrid, kPatch * kGrid, c.format);
  for (int y = 0; y < mosaic.height; ++y) {
    for (int x = 0; x < mosaic.width; ++x) {
      const std::array<uint8_t, 3>& rgb = colours[(y / kPatch) * kGrid + x / kPatch];
      const char channel = c.layout[(y % 2) * 2 + x % 2];
      *mosaic.at(x, y) = rgb[channel == 'R' ? 0 : channel == 'G' ? 1 : 2];
    }
  }
  absl::StatusOr<Image> rgb = ToRgb(mosaic);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  ASSERT_EQ(rgb->format, PixelFormat::kRgb8);
  ASSERT_EQ(rgb->width, mosaic.width);
  ASSERT_EQ(rgb->height, mosaic.height);
  for (int py = 0; py < kGrid; ++py) {
    for (int px = 0; px < kGrid; ++px) {
      const std::array<uint8_t, 3>& expected = colours[py * kGrid + px];
      // A 4x4 block at the centre covers every mosaic phase.
      for (int y = py * kPatch + 6; y < py * kPatch + 10; ++y) {
        for (int x = px * kPatch + 6; x < px * kPatch + 10; ++x) {
          for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(rgb->at(x, y)[ch], expected[ch], 2)
                << "patch " << px << "," << py << " pixel " << x << "," << y << " channel " << ch;
          }
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Demosaic, DemosaicTest,
                         ::testing::Values(BayerCase{PixelFormat::kBayerRg8, "RGGB"},
                                           BayerCase{PixelFormat::kBayerGb8, "GBRG"},
                                           BayerCase{PixelFormat::kBayerGr8, "GRBG"},
                                           BayerCase{PixelFormat::kBayerBg8, "BGGR"}),
                         [](const ::testing::TestParamInfo<BayerCase>& info) {
                           return std::string(PixelFormatName(info.param.format));
                         });

TEST(DemosaicMiscTest, MonoBecomesGreyAndRgbIsCopied) {
  const Image mono = MakeImage(PixelFormat::kMono8, 5, 3, 9);
  absl::StatusOr<Image> rgb = ToRgb(mono);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(rgb->at(x, y)[ch], *mono.at(x, y));
    }
  }
  const Image colour = MakeImage(PixelFormat::kRgb8, 5, 3, 9);
  absl::StatusOr<Image> same = ToRgb(colour);
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->data, colour.data);
}

TEST(DemosaicMiscTest, RejectsInconsistentOrTinyImages) {
  Image broken(8, 8, PixelFormat::kBayerRg8);
  broken.data.resize(3);
  EXPECT_EQ(ToRgb(broken).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ToRgb(Image()).status().code(), absl::StatusCode::kInvalidArgument);
  const absl::Status s = ToRgb(Image(1, 7, PixelFormat::kBayerGr8)).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("2x2"));
}

TEST(DemosaicMiscTest, SmallAndOddSizedMosaicsConvert) {
  for (const auto& [w, h] : {std::pair{2, 2}, std::pair{3, 2}, std::pair{2, 5}, std::pair{7, 9}}) {
    SCOPED_TRACE(absl::StrCat(w, "x", h));
    absl::StatusOr<Image> rgb = ToRgb(MakeImage(PixelFormat::kBayerBg8, w, h, 5));
    ASSERT_TRUE(rgb.ok()) << rgb.status();
    EXPECT_EQ(rgb->data.size(), static_cast<size_t>(w * h * 3));
  }
}

}  // namespace
}  // namespace vb::capture
