// SPDX-License-Identifier: Apache-2.0
// Capture bundles on disk: round trips, PNG files, every rejected file, demosaicing.
#include "workers/capture/bundle.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "opencv2/core.hpp"
#include "opencv2/imgcodecs.hpp"

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "workers/capture/bundle_test_util.h"

namespace vb::capture {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using bundle_test_util::kWidth;
using bundle_test_util::kHeight;
using bundle_test_util::Message;
using bundle_test_util::BundleFilesTest;
using bundle_test_util::BundlePngTest;
using bundle_test_util::ReadText;
using bundle_test_util::WriteText;
using bundle_test_util::MakeImage;
using bundle_test_util::MakeBundle;
using bundle_test_util::ExpectSameCalibration;
using bundle_test_util::YamlMatrix;
using bundle_test_util::YamlCamera;
using bundle_test_util::ThreeYamlCameras;
using bundle_test_util::BundleTest;


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
