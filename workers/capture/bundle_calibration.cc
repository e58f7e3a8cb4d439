// SPDX-License-Identifier: Apache-2.0
// calibration.yaml (OpenCV FileStorage YAML) of the capture bundle. The nodes are walked by hand
// rather than with `node >> cv::Mat` so that every missing field, wrong type and wrong matrix
// shape gets a message naming the camera and field; OpenCV's own readers either throw terse
// assertions or silently return empty matrices.
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "opencv2/core.hpp"
#include "workers/capture/bundle.h"
#include "workers/capture/bundle_internal.h"

namespace vb::capture {
namespace {

std::string NodeTypeName(const cv::FileNode& node) {
  if (node.isNone()) return "nothing";
  if (node.isInt()) return "an integer";
  if (node.isReal()) return "a real number";
  if (node.isString()) return "a string";
  if (node.isSeq()) return "a sequence";
  if (node.isMap()) return "a map";
  return "an unknown node";
}

absl::Status Missing(const std::string& what) {
  return absl::InvalidArgumentError(absl::StrCat(what, ": missing"));
}

absl::Status WrongType(const std::string& what, const std::string& expected,
                       const cv::FileNode& node) {
  return absl::InvalidArgumentError(
      absl::StrCat(what, ": expected ", expected, ", got ", NodeTypeName(node)));
}

absl::StatusOr<std::string> ReadString(const cv::FileNode& map, const std::string& key,
                                       const std::string& what) {
  const cv::FileNode node = map[key];
  if (node.empty() || node.isNone()) return Missing(what);
  if (!node.isString()) return WrongType(what, "a string", node);
  return node.string();
}

absl::StatusOr<int> ReadInt(const cv::FileNode& map, const std::string& key,
                            const std::string& what) {
  const cv::FileNode node = map[key];
  if (node.empty() || node.isNone()) return Missing(what);
  if (!node.isInt()) return WrongType(what, "an integer", node);
  return static_cast<int>(node);
}

// Reads an !!opencv-matrix {rows, cols, dt, data} of any numeric dt into row-major doubles.
// `shapes` lists the accepted (rows, cols); the first one is named in errors.
absl::StatusOr<std::vector<double>> ReadMatrix(const cv::FileNode& map, const std::string& key,
                                               const std::string& what,
                                               std::initializer_list<std::pair<int, int>> shapes) {
  const std::pair<int, int> expected = *shapes.begin();
  const cv::FileNode node = map[key];
  if (node.empty() || node.isNone()) return Missing(what);
  if (!node.isMap()) {
    return WrongType(what, absl::StrCat("a ", expected.first, "x", expected.second, " !!opencv-matrix"),
                     node);
  }
  VB_ASSIGN_OR_RETURN(const int rows, ReadInt(node, "rows", what + ".rows"));
  VB_ASSIGN_OR_RETURN(const int cols, ReadInt(node, "cols", what + ".cols"));
  bool shape_ok = false;
  for (const auto& [r, c] : shapes) shape_ok = shape_ok || (rows == r && cols == c);
  if (!shape_ok) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": expected ", expected.first, "x",
                                                   expected.second, ", got ", rows, "x", cols));
  }
  const cv::FileNode data = node["data"];
  if (data.empty() || data.isNone()) return Missing(what + ".data");
  if (!data.isSeq()) return WrongType(what + ".data", "a sequence of numbers", data);
  const size_t count = static_cast<size_t>(rows) * static_cast<size_t>(cols);
  if (data.size() != count) {
    return absl::InvalidArgumentError(absl::StrCat(what, ".data: expected ", count,
                                                   " numbers for ", rows, "x", cols, ", got ",
                                                   data.size()));
  }
  std::vector<double> values;
  values.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const cv::FileNode v = data[static_cast<int>(i)];
    if (!v.isInt() && !v.isReal()) {
      return WrongType(absl::StrCat(what, ".data[", i, "]"), "a number", v);
    }
    values.push_back(v.isInt() ? static_cast<double>(static_cast<int>(v)) : v.real());
  }
  return values;
}

absl::StatusOr<CameraCalibration> ParseCamera(const cv::FileNode& item, size_t index) {
  std::string what = absl::StrCat("cameras[", index, "]");
  if (!item.isMap()) return WrongType(what, "a map", item);
  CameraCalibration cam;
  VB_ASSIGN_OR_RETURN(cam.name, ReadString(item, "name", what + ".name"));
  what = absl::StrCat(what, " (", cam.name, ")");
  VB_ASSIGN_OR_RETURN(cam.image_width, ReadInt(item, "image_width", what + ".image_width"));
  VB_ASSIGN_OR_RETURN(cam.image_height, ReadInt(item, "image_height", what + ".image_height"));

  VB_ASSIGN_OR_RETURN(const std::vector<double> k,
                      ReadMatrix(item, "camera_matrix", what + ".camera_matrix", {{3, 3}}));
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam.camera_matrix(r, c) = k[r * 3 + c];
  }
  // 1x5 is what we write; 5x1 is what many calibration tools (and OpenCV samples) write.
  VB_ASSIGN_OR_RETURN(const std::vector<double> d,
                      ReadMatrix(item, "distortion_coefficients",
                                 what + ".distortion_coefficients", {{1, 5}, {5, 1}}));
  for (int i = 0; i < 5; ++i) cam.distortion[i] = d[i];
  VB_ASSIGN_OR_RETURN(const std::vector<double> rot,
                      ReadMatrix(item, "rotation_camera_from_platform",
                                 what + ".rotation_camera_from_platform", {{3, 3}}));
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam.rotation_camera_from_platform(r, c) = rot[r * 3 + c];
  }
  VB_ASSIGN_OR_RETURN(const std::vector<double> t,
                      ReadMatrix(item, "translation_camera_from_platform",
                                 what + ".translation_camera_from_platform", {{3, 1}, {1, 3}}));
  cam.translation_camera_from_platform = Eigen::Vector3d(t[0], t[1], t[2]);
  return cam;
}

// An optional `fiducials` item: {name, position_in_platform (3x1, m), radius_m}.
absl::StatusOr<Fiducial> ParseFiducial(const cv::FileNode& item, size_t index) {
  std::string what = absl::StrCat("fiducials[", index, "]");
  if (!item.isMap()) return WrongType(what, "a map", item);
  Fiducial f;
  VB_ASSIGN_OR_RETURN(f.name, ReadString(item, "name", what + ".name"));
  what = absl::StrCat(what, " (", f.name, ")");
  VB_ASSIGN_OR_RETURN(const std::vector<double> p,
                      ReadMatrix(item, "position_in_platform", what + ".position_in_platform",
                                 {{3, 1}, {1, 3}}));
  f.position_in_platform = Eigen::Vector3d(p[0], p[1], p[2]);
  const cv::FileNode radius = item["radius_m"];
  if (radius.empty() || radius.isNone()) return Missing(what + ".radius_m");
  if (!radius.isReal() && !radius.isInt()) return WrongType(what + ".radius_m", "a number", radius);
  f.radius_m = radius.isInt() ? static_cast<double>(static_cast<int>(radius)) : radius.real();
  return f;
}

// OpenCV's parser reports "(line): message" in cv::Exception::func and its own function name in
// ::err (parseError passes them swapped); turn that into one readable sentence.
std::string DescribeParseError(const cv::Exception& e) {
  if (e.code == cv::Error::StsParseError && !e.func.empty() && e.func.front() == '(') {
    const size_t close = e.func.find("): ");
    if (close != std::string::npos) {
      return absl::StrCat("malformed YAML at line ", e.func.substr(1, close - 1), ": ",
                          e.func.substr(close + 3));
    }
  }
  return absl::StrCat("malformed YAML: ", e.err);
}

absl::StatusOr<RigCalibration> ParseRig(std::string text) {
  // OpenCV only recognises YAML by its directive; accept hand-written files without one.
  if (text.rfind("%YAML", 0) != 0) text = "%YAML:1.0\n" + text;
  cv::FileStorage fs;
  try {
    if (!fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY |
                           cv::FileStorage::FORMAT_YAML)) {
      return absl::InvalidArgumentError("not a readable OpenCV FileStorage YAML document");
    }
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(DescribeParseError(e));
  }
  const cv::FileNode root = fs.root();
  if (!root.isMap()) return WrongType("top level", "a map holding 'cameras'", root);
  const cv::FileNode cameras = root["cameras"];
  if (cameras.empty() || cameras.isNone()) return Missing("cameras");
  if (!cameras.isSeq()) return WrongType("cameras", "a sequence", cameras);
  RigCalibration rig;
  for (size_t i = 0; i < cameras.size(); ++i) {
    VB_ASSIGN_OR_RETURN(CameraCalibration cam, ParseCamera(cameras[static_cast<int>(i)], i));
    rig.cameras.push_back(std::move(cam));
  }
  // Optional (absent in bundles written before fiducials existed): the platform's fiducials.
  const cv::FileNode fiducials = root["fiducials"];
  if (!fiducials.empty() && !fiducials.isNone()) {
    if (!fiducials.isSeq()) return WrongType("fiducials", "a sequence", fiducials);
    for (size_t i = 0; i < fiducials.size(); ++i) {
      VB_ASSIGN_OR_RETURN(Fiducial f, ParseFiducial(fiducials[static_cast<int>(i)], i));
      rig.fiducials.push_back(std::move(f));
    }
  }
  VB_RETURN_IF_ERROR(rig.Validate());
  return rig;
}

cv::Mat ToCvMat(const double* row_major, int rows, int cols) {
  cv::Mat m(rows, cols, CV_64F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m.at<double>(r, c) = row_major[r * cols + c];
  }
  return m;
}

cv::Mat ToCvMat(const Eigen::Matrix3d& m) {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> row_major = m;
  return ToCvMat(row_major.data(), 3, 3);
}

}  // namespace

absl::StatusOr<RigCalibration> ReadCalibrationYaml(const std::string& path) {
  VB_ASSIGN_OR_RETURN(const std::string text, internal::ReadFileBytes(path));
  absl::StatusOr<RigCalibration> rig;
  try {
    rig = ParseRig(text);
  } catch (const cv::Exception& e) {
    // FileNode accessors assert on structures the checks above did not anticipate.
    rig = absl::InvalidArgumentError(absl::StrCat("malformed calibration: ", e.err));
  }
  if (!rig.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", std::string(rig.status().message())));
  }
  return rig;
}

absl::Status WriteCalibrationYaml(const std::string& path, const RigCalibration& rig) {
  if (absl::Status s = rig.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", std::string(s.message())));
  }
  std::string text;
  try {
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                    cv::FileStorage::FORMAT_YAML);
    fs << "cameras" << "[";
    for (const CameraCalibration& c : rig.cameras) {
      const Eigen::Vector3d& t = c.translation_camera_from_platform;
      fs << "{";
      fs << "name" << c.name;
      fs << "image_width" << c.image_width;
      fs << "image_height" << c.image_height;
      fs << "camera_matrix" << ToCvMat(c.camera_matrix);
      fs << "distortion_coefficients" << ToCvMat(c.distortion.data(), 1, 5);
      fs << "rotation_camera_from_platform" << ToCvMat(c.rotation_camera_from_platform);
      fs << "translation_camera_from_platform" << ToCvMat(t.data(), 3, 1);
      fs << "}";
    }
    fs << "]";
    if (!rig.fiducials.empty()) {
      fs << "fiducials" << "[";
      for (const Fiducial& f : rig.fiducials) {
        fs << "{";
        fs << "name" << f.name;
        fs << "position_in_platform" << ToCvMat(f.position_in_platform.data(), 3, 1);
        fs << "radius_m" << f.radius_m;
        fs << "}";
      }
      fs << "]";
    }
    text = fs.releaseAndGetString();
  } catch (const cv::Exception& e) {
    return absl::InternalError(absl::StrCat(path, ": cannot serialise calibration: ", e.err));
  }
  return internal::WriteFileAtomically(path, text);
}

}  // namespace vb::capture
