// SPDX-License-Identifier: Apache-2.0
// calibration.yaml: hand-written files, every rejected field, round trips of rigs and fiducials.
#include <filesystem>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "opencv2/core.hpp"
#include "workers/capture/bundle.h"
#include "workers/capture/bundle_test_util.h"

namespace vb::capture {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using bundle_test_util::Message;
using bundle_test_util::CalibrationYamlTest;
using bundle_test_util::WriteText;
using bundle_test_util::MakeCalibration;
using bundle_test_util::ExpectSameCalibration;
using bundle_test_util::YamlMatrix;
using bundle_test_util::YamlCamera;
using bundle_test_util::YamlText;
using bundle_test_util::ThreeYamlCameras;
using bundle_test_util::BundleTest;

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
}  // namespace
}  // namespace vb::capture
