#include "core/io/camera_calibration.h"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <opencv2/calib3d.hpp>
#include <sstream>

#include "core/config.h"
#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/calibration_yaml.h"

namespace dala {
namespace {

constexpr const char* kFormatsHelp =
    "dala reads OpenCV calibration output (camera_matrix, distortion_coefficients), ROS "
    "camera_info YAML (camera_matrix, distortion_model, projection_matrix), Kalibr camchain "
    "YAML (cam0: intrinsics, distortion_coeffs) and its own (fx fy cx cy width height); "
    "docs/datasets.md, \"Your own camera\"";

std::string ReadText(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << "missing calibration file '" << path << "': check the path (--calibration)";
  }
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// YAML lets a block sequence sit at its key's indentation ("key:\n- a\n- b", as yaml-cpp,
// Kalibr and ROS write it); cv::FileStorage needs it indented deeper: indent such items by two.
std::string IndentSequences(const std::string& text) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line;
  int open_key_indent = -1;  // Indentation of the last "key:" with nothing after the colon.
  bool in_items = false;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(' ');
    const int indent = first == std::string::npos ? -1 : static_cast<int>(first);
    const bool item = indent >= 0 && line.compare(first, 2, "- ") == 0;
    if (item && (indent == open_key_indent) && (in_items || open_key_indent >= 0)) {
      out << "  " << line << "\n";
      in_items = true;
      continue;
    }
    in_items = false;
    open_key_indent = -1;
    if (indent >= 0 && !item) {
      const size_t end = line.find_last_not_of(" \t\r");
      if (line[end] == ':') open_key_indent = indent;
    }
    out << line << "\n";
  }
  return out.str();
}

// A YAML file as ConfigNode, its sequences indented for cv::FileStorage.
ConfigNode LoadYaml(const std::string& path) {
  return ParseConfigString(IndentSequences(ReadText(path)), path);
}

bool HasKey(const std::string& text, const std::string& key) {
  // A key at the start of a line (any indentation), followed by ':'.
  size_t pos = 0;
  while ((pos = text.find(key + ":", pos)) != std::string::npos) {
    size_t k = pos;
    while (k > 0 && (text[k - 1] == ' ' || text[k - 1] == '\t')) --k;
    if (k == 0 || text[k - 1] == '\n') return true;
    pos += key.size();
  }
  return false;
}

// The numbers of a FileNode: a sequence, an !!opencv-matrix, or a ROS {rows, cols, data} map.
std::vector<double> Numbers(const cv::FileNode& node, const std::string& where) {
  std::vector<double> out;
  if (node.empty() || node.isNone()) throw Error() << where << ": missing";
  if (node.isMap() && !node["data"].empty() && node["dt"].empty()) {
    return Numbers(node["data"], where + ".data");  // ROS matrix.
  }
  if (node.isMap()) {  // !!opencv-matrix.
    cv::Mat m;
    try {
      node >> m;
    } catch (const cv::Exception&) {
      throw Error() << where << ": not a matrix";
    }
    cv::Mat d;
    m.convertTo(d, CV_64F);
    d = d.reshape(1, 1);
    for (int i = 0; i < d.cols; ++i) out.push_back(d.at<double>(0, i));
    return out;
  }
  if (node.isSeq()) {
    for (const cv::FileNode& n : node) {
      if (n.isSeq()) {  // Kalibr's nested rows.
        for (const cv::FileNode& m : n) {
          if (!m.isReal() && !m.isInt()) throw Error() << where << ": not a number";
          out.push_back(static_cast<double>(m));
        }
      } else {
        if (!n.isReal() && !n.isInt()) throw Error() << where << ": not a number";
        out.push_back(static_cast<double>(n));
      }
    }
    return out;
  }
  if (node.isReal() || node.isInt()) return {static_cast<double>(node)};
  throw Error() << where << ": expected numbers";
}

std::vector<double> NumbersOfSize(const cv::FileNode& node, const std::string& where,
                                  size_t n) {
  std::vector<double> v = Numbers(node, where);
  if (v.size() != n) {
    throw Error() << where << ": has " << v.size() << " numbers, expected " << n;
  }
  return v;
}

int IntOf(const cv::FileNode& node, const std::string& where) {
  if (!node.isInt() && !node.isReal()) throw Error() << where << ": missing or not a number";
  return static_cast<int>(static_cast<double>(node));
}

std::string StringOf(const cv::FileNode& node) {
  return node.isString() ? static_cast<std::string>(node) : std::string();
}

// Reads distortion coefficients into `cam` for the model; extra OpenCV coefficients (rational
// k4..k6, thin prism, tilt) must be zero.
void SetDistortion(const std::vector<double>& d, const std::string& where, RawCamera* cam) {
  if (cam->model == LensModel::kFisheye) {
    if (d.size() != 4) {
      throw Error() << where << ": the fisheye (equidistant) model has 4 coefficients k1..k4, "
                    << "got " << d.size();
    }
    for (int i = 0; i < 4; ++i) cam->distortion[i] = d[i];
    return;
  }
  if (d.size() < 4) {
    throw Error() << where << ": radial-tangential needs k1 k2 p1 p2 [k3], got " << d.size()
                  << " coefficients";
  }
  for (size_t i = 0; i < d.size(); ++i) {
    if (i < 5) {
      cam->distortion[i] = d[i];
    } else if (d[i] != 0) {
      throw Error() << where << ": coefficient " << i + 1 << " (" << d[i]
                    << ") is not 0: the rational / thin-prism models are not supported; "
                    << "recalibrate with pinhole radial-tangential (k1 k2 p1 p2 k3) or fisheye";
    }
  }
}

LensModel ParseModel(const std::string& name, const std::string& where) {
  if (name == "radtan" || name == "radial-tangential" || name == "plumb_bob" || name == "pinhole" ||
      name == "radial_tangential") {
    return LensModel::kRadtan;
  }
  if (name == "equidistant" || name == "fisheye" || name == "equi" || name == "kannala_brandt") {
    return LensModel::kFisheye;
  }
  throw Error() << where << ": unknown distortion model '" << name
                << "': dala supports radtan (plumb_bob, radial-tangential) and equidistant "
                << "(fisheye, Kannala-Brandt k1..k4); recalibrate with one of them";
}

void SetK(const std::vector<double>& k, RawCamera* cam) {
  cam->fx = k[0];
  cam->cx = k[2];
  cam->fy = k[4];
  cam->cy = k[5];
}

Pose PoseFromRt(const std::vector<double>& R, const std::vector<double>& t,
                const std::string& where) {
  Eigen::Matrix3d Rm;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Rm(r, c) = R[3 * r + c];
  }
  if ((Rm.transpose() * Rm - Eigen::Matrix3d::Identity()).norm() > 1e-3 || Rm.determinant() < 0) {
    throw Error() << where << ": the stereo rotation is not a rotation matrix";
  }
  return Orthonormalized(MakePose(Rm, Eigen::Vector3d(t[0], t[1], t[2])));
}

CameraCalibration ReadOpenCv(const std::string& path) {
  const ConfigNode root = LoadConfigFile(path);
  const cv::FileNode& n = root.node();
  CameraCalibration out;
  out.path = path;
  out.format = CalibrationFormat::kOpenCv;
  LensModel model = LensModel::kRadtan;
  if (!n["fisheye_model"].empty() && IntOf(n["fisheye_model"], path + ": fisheye_model") != 0) {
    model = LensModel::kFisheye;
  }
  if (!n["distortion_model"].empty()) {
    model = ParseModel(StringOf(n["distortion_model"]), path + ": distortion_model");
  }
  const bool stereo_calib_sample = n["camera_matrix"].empty() && !n["M1"].empty();
  const char* k0 = stereo_calib_sample ? "M1" : "camera_matrix";
  const char* d0 = stereo_calib_sample ? "D1" : "distortion_coefficients";
  const char* k1 = stereo_calib_sample ? "M2" : "camera_matrix_right";
  const char* d1 = stereo_calib_sample ? "D2" : "distortion_coefficients_right";
  const auto read_cam = [&](const char* k, const char* d, RawCamera* cam) {
    cam->model = model;
    SetK(NumbersOfSize(n[k], path + ": " + k, 9), cam);
    SetDistortion(Numbers(n[d], path + ": " + d), path + ": " + d, cam);
    if (n["image_width"].empty() || n["image_height"].empty()) {
      throw Error() << path << ": needs image_width and image_height (the size of the "
                    << "calibrated images; OpenCV's calibration sample writes them)";
    }
    cam->width = IntOf(n["image_width"], path + ": image_width");
    cam->height = IntOf(n["image_height"], path + ": image_height");
  };
  read_cam(k0, d0, &out.cam0);
  if (!n[k1].empty()) {
    RawCamera cam1;
    read_cam(k1, d1, &cam1);
    out.cam1 = cam1;
    out.T_c1_c0 = PoseFromRt(NumbersOfSize(n["R"], path + ": R", 9),
                             NumbersOfSize(n["T"], path + ": T", 3), path);
  }
  return out;
}

CameraCalibration ReadRos(const std::string& path) {
  const ConfigNode root = LoadYaml(path);
  const cv::FileNode& n = root.node();
  CameraCalibration out;
  out.path = path;
  out.format = CalibrationFormat::kRos;
  RawCamera& cam = out.cam0;
  cam.width = IntOf(n["image_width"], path + ": image_width");
  cam.height = IntOf(n["image_height"], path + ": image_height");
  SetK(NumbersOfSize(n["camera_matrix"], path + ": camera_matrix", 9), &cam);
  cam.model = ParseModel(n["distortion_model"].empty() ? "plumb_bob"
                                                       : StringOf(n["distortion_model"]),
                         path + ": distortion_model");
  SetDistortion(Numbers(n["distortion_coefficients"], path + ": distortion_coefficients"),
                path + ": distortion_coefficients", &cam);
  return out;
}

RawCamera ReadKalibrCamera(const cv::FileNode& n, const std::string& where) {
  if (!n.isMap()) throw Error() << where << ": missing or not a map";
  const std::string model = StringOf(n["camera_model"]);
  if (!model.empty() && model != "pinhole") {
    throw Error() << where << ".camera_model: '" << model << "' is not supported: dala reads "
                  << "pinhole cameras (with radtan or equidistant distortion); recalibrate with "
                  << "Kalibr's pinhole-radtan or pinhole-equi";
  }
  RawCamera cam;
  const auto k = NumbersOfSize(n["intrinsics"], where + ".intrinsics", 4);
  cam.fx = k[0];
  cam.fy = k[1];
  cam.cx = k[2];
  cam.cy = k[3];
  cam.model = ParseModel(n["distortion_model"].empty() ? "radtan" : StringOf(n["distortion_model"]),
                         where + ".distortion_model");
  SetDistortion(Numbers(n["distortion_coeffs"], where + ".distortion_coeffs"),
                where + ".distortion_coeffs", &cam);
  const auto res = NumbersOfSize(n["resolution"], where + ".resolution", 2);
  cam.width = static_cast<int>(res[0]);
  cam.height = static_cast<int>(res[1]);
  return cam;
}

CameraCalibration ReadKalibr(const std::string& path) {
  const ConfigNode root = LoadYaml(path);
  const cv::FileNode& n = root.node();
  CameraCalibration out;
  out.path = path;
  out.format = CalibrationFormat::kKalibr;
  out.cam0 = ReadKalibrCamera(n["cam0"], path + ": cam0");
  if (!n["cam1"].empty()) {
    out.cam1 = ReadKalibrCamera(n["cam1"], path + ": cam1");
    const auto T = NumbersOfSize(n["cam1"]["T_cn_cnm1"], path + ": cam1.T_cn_cnm1", 16);
    out.T_c1_c0 = PoseFromRt({T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10]},
                             {T[3], T[7], T[11]}, path + ": cam1.T_cn_cnm1");
  }
  return out;
}

CameraCalibration ReadDala(const std::string& path) {
  const StereoRig rig = ReadCalibrationYaml(path);
  CameraCalibration out;
  out.path = path;
  out.format = CalibrationFormat::kDala;
  RawCamera& cam = out.cam0;
  cam.width = rig.left.width;
  cam.height = rig.left.height;
  cam.fx = rig.left.fx;
  cam.fy = rig.left.fy;
  cam.cx = rig.left.cx;
  cam.cy = rig.left.cy;
  cam.distortion = rig.left.distortion;
  out.rectified_baseline = rig.baseline;
  return out;
}

cv::Mat ToCv(const Eigen::Matrix3d& R) {
  cv::Mat m(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.at<double>(r, c) = R(r, c);
  }
  return m;
}

PinholeCamera CameraFromK(const cv::Mat& K, cv::Size size) {
  PinholeCamera c;
  c.width = size.width;
  c.height = size.height;
  c.fx = K.at<double>(0, 0);
  c.fy = K.at<double>(1, 1);
  c.cx = K.at<double>(0, 2);
  c.cy = K.at<double>(1, 2);
  return c;
}

}  // namespace

const char* LensModelName(LensModel model) {
  return model == LensModel::kFisheye ? "fisheye" : "radtan";
}

const char* CalibrationFormatName(CalibrationFormat format) {
  switch (format) {
    case CalibrationFormat::kOpenCv:
      return "opencv";
    case CalibrationFormat::kRos:
      return "ros";
    case CalibrationFormat::kKalibr:
      return "kalibr";
    case CalibrationFormat::kDala:
      return "dala";
  }
  return "?";
}

cv::Mat RawCamera::K() const {
  return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

cv::Mat RawCamera::D() const {
  if (model == LensModel::kFisheye) {
    return (cv::Mat_<double>(1, 4) << distortion[0], distortion[1], distortion[2], distortion[3]);
  }
  return (cv::Mat_<double>(1, 5) << distortion[0], distortion[1], distortion[2], distortion[3],
          distortion[4]);
}

bool RawCamera::IsValid(std::string* why) const {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  c.distortion = distortion;
  return c.IsValid(why);
}

CalibrationFormat DetectCalibrationFormat(const std::string& path) {
  const std::string text = ReadText(path);
  if (HasKey(text, "cam0")) return CalibrationFormat::kKalibr;
  const bool opencv_matrix = text.find("!!opencv-matrix") != std::string::npos;
  if ((HasKey(text, "camera_matrix") || HasKey(text, "M1")) && opencv_matrix) {
    return CalibrationFormat::kOpenCv;
  }
  if (HasKey(text, "camera_matrix") && HasKey(text, "image_width")) return CalibrationFormat::kRos;
  if (HasKey(text, "fx")) return CalibrationFormat::kDala;
  throw Error() << path << ": not a calibration file dala knows: " << kFormatsHelp;
}

CameraCalibration ReadCameraCalibration(const std::string& path) {
  CameraCalibration out;
  switch (DetectCalibrationFormat(path)) {
    case CalibrationFormat::kOpenCv:
      out = ReadOpenCv(path);
      break;
    case CalibrationFormat::kRos:
      out = ReadRos(path);
      break;
    case CalibrationFormat::kKalibr:
      out = ReadKalibr(path);
      break;
    case CalibrationFormat::kDala:
      out = ReadDala(path);
      break;
  }
  std::string why;
  if (!out.cam0.IsValid(&why)) throw Error() << path << ": invalid camera: " << why;
  if (out.cam1 && !out.cam1->IsValid(&why)) {
    throw Error() << path << ": invalid right camera: " << why;
  }
  return out;
}

namespace {

std::string List(const std::vector<double>& v) {
  std::ostringstream os;
  os << std::setprecision(17) << "[";
  for (size_t i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
  os << "]";
  return os.str();
}

std::vector<double> Coefficients(const RawCamera& c) {
  const int n = c.model == LensModel::kFisheye ? 4 : 5;
  return std::vector<double>(c.distortion.data(), c.distortion.data() + n);
}

void WriteKalibrCamera(std::ostream& os, const std::string& name, const RawCamera& c) {
  os << name << ":\n"
     << "  camera_model: pinhole\n"
     << "  distortion_coeffs: "
     << List(c.model == LensModel::kFisheye ? Coefficients(c)
                                             : std::vector<double>(c.distortion.data(),
                                                                   c.distortion.data() + 4))
     << "\n"
     << "  distortion_model: " << (c.model == LensModel::kFisheye ? "equidistant" : "radtan")
     << "\n"
     << "  intrinsics: " << List({c.fx, c.fy, c.cx, c.cy}) << "\n"
     << "  resolution: [" << c.width << ", " << c.height << "]\n";
}

}  // namespace

void WriteCameraCalibration(const std::string& path, const CameraCalibration& calibration,
                            CalibrationFormat format) {
  const RawCamera& c0 = calibration.cam0;
  std::string text;
  switch (format) {
    case CalibrationFormat::kOpenCv: {
      cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
      fs << "image_width" << c0.width << "image_height" << c0.height;
      fs << "distortion_model" << LensModelName(c0.model);
      fs << "fisheye_model" << static_cast<int>(c0.model == LensModel::kFisheye);
      fs << "camera_matrix" << c0.K() << "distortion_coefficients" << c0.D().t();
      if (calibration.cam1) {
        fs << "camera_matrix_right" << calibration.cam1->K();
        fs << "distortion_coefficients_right" << calibration.cam1->D().t();
        cv::Mat R = ToCv(calibration.T_c1_c0.linear());
        const Eigen::Vector3d t = calibration.T_c1_c0.translation();
        fs << "R" << R << "T" << cv::Mat(cv::Vec3d(t[0], t[1], t[2]));
      }
      text = fs.releaseAndGetString();
      break;
    }
    case CalibrationFormat::kRos: {
      std::ostringstream os;
      os << std::setprecision(17);
      os << "image_width: " << c0.width << "\nimage_height: " << c0.height
         << "\ncamera_name: dala\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: "
         << List({c0.fx, 0, c0.cx, 0, c0.fy, c0.cy, 0, 0, 1}) << "\ndistortion_model: "
         << (c0.model == LensModel::kFisheye ? "equidistant" : "plumb_bob")
         << "\ndistortion_coefficients:\n  rows: 1\n  cols: " << Coefficients(c0).size()
         << "\n  data: " << List(Coefficients(c0))
         << "\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: "
         << List({1, 0, 0, 0, 1, 0, 0, 0, 1})
         << "\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: "
         << List({c0.fx, 0, c0.cx, 0, 0, c0.fy, c0.cy, 0, 0, 0, 1, 0}) << "\n";
      text = os.str();
      break;
    }
    case CalibrationFormat::kKalibr: {
      if (c0.model == LensModel::kRadtan && c0.distortion[4] != 0) {
        throw Error() << path << ": Kalibr's radtan has k1 k2 p1 p2 only; k3 = "
                      << c0.distortion[4] << " cannot be written (use the OpenCV format)";
      }
      std::ostringstream os;
      os << std::setprecision(17);
      WriteKalibrCamera(os, "cam0", c0);
      if (calibration.cam1) {
        const Eigen::Matrix4d T = calibration.T_c1_c0.matrix();
        os << "cam1:\n  T_cn_cnm1:\n";
        for (int r = 0; r < 4; ++r) {
          os << "  - " << List({T(r, 0), T(r, 1), T(r, 2), T(r, 3)}) << "\n";
        }
        std::ostringstream cam1;
        cam1 << std::setprecision(17);
        WriteKalibrCamera(cam1, "cam1", *calibration.cam1);
        os << cam1.str().substr(cam1.str().find('\n') + 1);
      }
      text = os.str();
      break;
    }
    case CalibrationFormat::kDala: {
      if (c0.model == LensModel::kFisheye && c0.HasDistortion()) {
        throw Error() << path << ": dala's own calibration format has no fisheye model: write "
                      << "the OpenCV or Kalibr format";
      }
      if (calibration.cam1) {
        throw Error() << path << ": dala's own calibration format holds a rectified pair "
                      << "only: write the OpenCV or Kalibr format for a raw pair";
      }
      std::ostringstream os;
      os << std::setprecision(17) << "%YAML:1.0\nfx: " << c0.fx << "\nfy: " << c0.fy
         << "\ncx: " << c0.cx << "\ncy: " << c0.cy << "\nwidth: " << c0.width
         << "\nheight: " << c0.height << "\n";
      if (calibration.rectified_baseline > 0) {
        os << "baseline: " << calibration.rectified_baseline << "\n";
      }
      const char* keys[5] = {"k1", "k2", "p1", "p2", "k3"};
      if (c0.HasDistortion()) {
        for (int i = 0; i < 5; ++i) os << keys[i] << ": " << c0.distortion[i] << "\n";
      }
      text = os.str();
      break;
    }
  }
  WriteFileAtomically(path, [&](std::ostream& os) { os << text; });
}

Rectification MakeRectification(const CameraCalibration& calibration, bool stereo) {
  const std::string& path = calibration.path;
  if (stereo && !calibration.is_stereo()) {
    throw Error() << path << ": describes one camera (no 'baseline', no right camera), but the images are a "
                  << "stereo pair: give a "
                  << "stereo calibration (Kalibr cam0 + cam1, OpenCV R and T, or dala's own "
                  << "with a baseline) or read the sequence as monocular (--mode mono)";
  }
  Rectification out;
  const RawCamera& c0 = calibration.cam0;
  const cv::Size size(c0.width, c0.height);
  if (stereo && calibration.cam1) {
    const RawCamera& c1 = *calibration.cam1;
    if (c1.width != c0.width || c1.height != c0.height) {
      throw Error() << path << ": the right camera's image size " << c1.width << "x" << c1.height
                    << " differs from the left's " << c0.width << "x" << c0.height
                    << "; dala needs a pair of the same size";
    }
    if (c1.model != c0.model) {
      throw Error() << path << ": the left camera is " << LensModelName(c0.model)
                    << ", the right " << LensModelName(c1.model)
                    << "; dala rectifies a pair of one lens model: calibrate both with the same";
    }
    const cv::Mat R = ToCv(calibration.T_c1_c0.linear());
    const Eigen::Vector3d t = calibration.T_c1_c0.translation();
    const cv::Mat T = (cv::Mat_<double>(3, 1) << t[0], t[1], t[2]);
    cv::Mat R1, R2, P1, P2, Q;
    if (c0.model == LensModel::kFisheye) {
      cv::fisheye::stereoRectify(c0.K(), c0.D(), c1.K(), c1.D(), size, R, T, R1, R2, P1, P2, Q,
                                 cv::CALIB_ZERO_DISPARITY, size, /*balance=*/0.0,
                                 /*fov_scale=*/1.0);
      cv::fisheye::initUndistortRectifyMap(c0.K(), c0.D(), R1, P1, size, CV_16SC2,
                                           out.left_map1, out.left_map2);
      cv::fisheye::initUndistortRectifyMap(c1.K(), c1.D(), R2, P2, size, CV_16SC2,
                                           out.right_map1, out.right_map2);
    } else {
      cv::stereoRectify(c0.K(), c0.D(), c1.K(), c1.D(), size, R, T, R1, R2, P1, P2, Q,
                        cv::CALIB_ZERO_DISPARITY, /*alpha=*/0.0, size);
      cv::initUndistortRectifyMap(c0.K(), c0.D(), R1, P1, size, CV_16SC2, out.left_map1,
                                  out.left_map2);
      cv::initUndistortRectifyMap(c1.K(), c1.D(), R2, P2, size, CV_16SC2, out.right_map1,
                                  out.right_map2);
    }
    out.rig.left = CameraFromK(P1, size);
    // P2 = K_rect [I | (-b, 0, 0)] in the rectified left frame.
    out.rig.baseline = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
    if (!(out.rig.baseline > 0)) {
      throw Error() << path << ": the right camera is not to the right of the left one after "
                    << "rectification (baseline " << out.rig.baseline << "): check the stereo "
                    << "extrinsics (T_c1_c0: p_c1 = R p_c0 + T, T about (-b, 0, 0)) and the "
                    << "order of the cameras";
    }
    Eigen::Matrix3d R1e;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R1e(r, c) = R1.at<double>(r, c);
    }
    // R1 rotates raw cam0 coordinates into the rectified frame: p_c0rect = R1 p_c0.
    out.T_c0_c0rect =
        Orthonormalized(MakePose(Eigen::Matrix3d(R1e.transpose()), Eigen::Vector3d::Zero()));
    return out;
  }
  if (stereo && calibration.rectified_baseline > 0 && c0.HasDistortion()) {
    throw Error() << path << ": a rectified pair (baseline) cannot have distortion: give the "
                  << "raw cameras and their extrinsics instead (Kalibr or OpenCV stereo)";
  }
  out.rig.baseline = stereo ? calibration.rectified_baseline : 0.0;
  if (!c0.HasDistortion()) {
    out.rig.left = CameraFromK(c0.K(), size);
    return out;
  }
  if (c0.model == LensModel::kFisheye) {
    cv::Mat new_K;
    cv::fisheye::estimateNewCameraMatrixForUndistortRectify(c0.K(), c0.D(), size,
                                                            cv::Mat::eye(3, 3, CV_64F), new_K,
                                                            /*balance=*/0.0, size);
    cv::fisheye::initUndistortRectifyMap(c0.K(), c0.D(), cv::Mat::eye(3, 3, CV_64F), new_K, size,
                                         CV_16SC2, out.left_map1, out.left_map2);
    out.rig.left = CameraFromK(new_K, size);
  } else {
    const cv::Mat new_K = cv::getOptimalNewCameraMatrix(c0.K(), c0.D(), size, /*alpha=*/0.0, size);
    cv::initUndistortRectifyMap(c0.K(), c0.D(), cv::Mat(), new_K, size, CV_16SC2, out.left_map1,
                                out.left_map2);
    out.rig.left = CameraFromK(new_K, size);
  }
  return out;
}

}  // namespace dala
