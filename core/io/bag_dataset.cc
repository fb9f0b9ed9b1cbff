#include "core/io/bag_dataset.h"

#include "core/error.h"

#ifndef DALA_HAVE_ROSBAG

namespace dala {

bool HaveBagSupport() { return false; }

std::unique_ptr<Dataset> OpenBagDataset(const std::string& path, const DatasetOptions&) {
  throw Error() << "'" << path << "' is a ROS bag, but this dala was built without ROS bag "
                << "support: install librosbag-dev and libsensor-msgs-dev "
                << "(scripts/install_deps.sh) and rebuild (CMake option DALA_WITH_ROSBAG), or "
                << "export the images (rosbag / bag_to_images) and run the folder";
}

}  // namespace dala

#else  // DALA_HAVE_ROSBAG

#include <glog/logging.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/io/camera_calibration.h"
#include "core/io/image_sequence.h"

namespace dala {
namespace {

constexpr const char* kImage = "sensor_msgs/Image";
constexpr const char* kCompressed = "sensor_msgs/CompressedImage";
constexpr const char* kCameraInfo = "sensor_msgs/CameraInfo";

struct BagImage {
  int64_t t_ns = 0;
  // (MessageInstance is not assignable: shared, so that the index can be sorted.)
  std::shared_ptr<const rosbag::MessageInstance> message;
};

std::string TopicList(const std::map<std::string, std::string>& topics) {
  std::string s;
  for (const auto& [topic, type] : topics) s += (s.empty() ? "" : ", ") + topic + " (" + type + ")";
  return s.empty() ? "none" : s;
}

int64_t StampNs(const ros::Time& stamp, const ros::Time& record) {
  return static_cast<int64_t>(stamp.isZero() ? record.toNSec() : stamp.toNSec());
}

// The image of a message as 8-bit grayscale; empty with `why` set when it cannot be used.
cv::Mat DecodeGray(const rosbag::MessageInstance& m, std::string* why) {
  if (const auto image = m.instantiate<sensor_msgs::Image>()) {
    const std::string& e = image->encoding;
    int type = 0, code = -1;
    if (e == "mono8" || e == "8UC1") {
      type = CV_8UC1;
    } else if (e == "bgr8" || e == "rgb8") {
      type = CV_8UC3;
      code = e == "bgr8" ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY;
    } else if (e == "bgra8" || e == "rgba8") {
      type = CV_8UC4;
      code = e == "bgra8" ? cv::COLOR_BGRA2GRAY : cv::COLOR_RGBA2GRAY;
    } else {
      *why = "image encoding '" + e + "' is not supported (mono8, bgr8, rgb8, bgra8, rgba8)";
      return {};
    }
    const size_t row = static_cast<size_t>(image->width) * CV_ELEM_SIZE(type);
    if (image->step < row || image->data.size() < static_cast<size_t>(image->step) * image->height) {
      *why = "image data is shorter than width x height";
      return {};
    }
    const cv::Mat view(static_cast<int>(image->height), static_cast<int>(image->width), type,
                       const_cast<uint8_t*>(image->data.data()), image->step);
    cv::Mat gray;
    if (code < 0) {
      gray = view.clone();
    } else {
      cv::cvtColor(view, gray, code);
    }
    return gray;
  }
  if (const auto compressed = m.instantiate<sensor_msgs::CompressedImage>()) {
    cv::Mat gray = cv::imdecode(compressed->data, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) *why = "compressed image (" + compressed->format + ") cannot be decoded";
    return gray;
  }
  *why = "not an image message";
  return {};
}

RawCamera CameraOfInfo(const sensor_msgs::CameraInfo& info, const std::string& where) {
  RawCamera c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fx = info.K[0];
  c.fy = info.K[4];
  c.cx = info.K[2];
  c.cy = info.K[5];
  const std::string& model = info.distortion_model;
  if (model == "equidistant") {
    c.model = LensModel::kFisheye;
  } else if (model == "plumb_bob" || model.empty() ||
             (model == "rational_polynomial" && info.D.size() >= 5 &&
              std::all_of(info.D.begin() + 5, info.D.end(), [](double d) { return d == 0; }))) {
    c.model = LensModel::kRadtan;
  } else {
    throw Error() << where << ": unknown distortion model '" << model
                  << "': dala supports plumb_bob and equidistant; give a calibration file "
                  << "(--calibration)";
  }
  for (size_t i = 0; i < info.D.size() && i < 5; ++i) c.distortion[i] = info.D[i];
  std::string why;
  if (!c.IsValid(&why)) throw Error() << where << ": invalid camera: " << why;
  return c;
}

class BagDataset : public Dataset {
 public:
  BagDataset(std::string path, std::unique_ptr<rosbag::Bag> bag, std::vector<BagImage> left,
             std::vector<BagImage> right, Rectification rect, cv::Size raw_size, size_t begin,
             size_t end, std::vector<std::optional<Pose>> gt)
      : path_(std::move(path)),
        bag_(std::move(bag)),
        left_(std::move(left)),
        right_(std::move(right)),
        rect_(std::move(rect)),
        raw_size_(raw_size),
        begin_(begin),
        end_(end),
        next_(begin),
        gt_(std::move(gt)) {
    if (!gt_.empty()) {
      Trajectory trajectory;
      for (size_t i = begin_; i < end_; ++i) {
        if (gt_[i]) trajectory.Add(left_[i].t_ns, *gt_[i]);
      }
      if (!trajectory.empty()) ground_truth_ = std::move(trajectory);
    }
  }

  DatasetFormat format() const override { return DatasetFormat::kBag; }
  const std::string& path() const override { return path_; }
  bool is_stereo() const override { return !right_.empty(); }
  const StereoRig& rig() const override { return rect_.rig; }
  size_t size() const override { return end_ - begin_; }
  void Rewind() override { next_ = begin_; }
  const std::optional<Trajectory>& ground_truth() const override { return ground_truth_; }

  bool Next(Frame* frame) override {
    CHECK(frame != nullptr);
    if (next_ >= end_) return false;
    const size_t i = next_++;
    Frame f;
    f.id = FrameId(static_cast<int64_t>(i));
    f.t_ns = left_[i].t_ns;
    f.left = Load(left_[i], rect_.left_map1, rect_.left_map2, f);
    if (is_stereo()) f.right = Load(right_[i], rect_.right_map1, rect_.right_map2, f);
    if (!gt_.empty()) f.T_w_c0_gt = gt_[i];
    *frame = std::move(f);
    return true;
  }

 private:
  cv::Mat Load(const BagImage& image, const cv::Mat& map1, const cv::Mat& map2,
               const Frame& f) const {
    std::string why;
    cv::Mat gray = DecodeGray(*image.message, &why);
    if (gray.empty()) {
      throw FrameError(f.id, f.t_ns,
                       path_ + ": " + image.message->getTopic() + " at " +
                           std::to_string(image.t_ns) + " ns: " + why);
    }
    if (gray.size() != raw_size_) {
      throw FrameError(f.id, f.t_ns,
                       path_ + ": " + image.message->getTopic() + " image is " +
                           std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                           ", expected " + std::to_string(raw_size_.width) + "x" +
                           std::to_string(raw_size_.height) + " (the calibration)");
    }
    if (map1.empty()) return gray;
    cv::Mat out;
    cv::remap(gray, out, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return out;
  }

  std::string path_;
  std::unique_ptr<rosbag::Bag> bag_;  // The messages below read from it.
  std::vector<BagImage> left_, right_;
  Rectification rect_;
  cv::Size raw_size_;
  size_t begin_, end_, next_;
  std::vector<std::optional<Pose>> gt_;
  std::optional<Trajectory> ground_truth_;
};

// "<ns>/camera_info" for "<ns>/image_raw" (and for "<ns>/image_raw/compressed").
std::string CameraInfoTopic(std::string image_topic) {
  const std::string compressed = "/compressed";
  if (image_topic.size() > compressed.size() &&
      image_topic.compare(image_topic.size() - compressed.size(), compressed.size(), compressed) ==
          0) {
    image_topic.resize(image_topic.size() - compressed.size());
  }
  const size_t slash = image_topic.find_last_of('/');
  return (slash == std::string::npos ? std::string() : image_topic.substr(0, slash)) +
         "/camera_info";
}

}  // namespace

bool HaveBagSupport() { return true; }

std::unique_ptr<Dataset> OpenBagDataset(const std::string& path, const DatasetOptions& options) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << "missing bag '" << path << "': check the path";
  }
  auto bag = std::make_unique<rosbag::Bag>();
  try {
    bag->open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw Error() << "cannot read the ROS bag '" << path << "' (" << e.what()
                  << "): the file is not a ROS 1 bag or is damaged (rosbag reindex may repair "
                  << "an unindexed one; ROS 2 bags are not read)";
  }
  std::map<std::string, std::string> topics;  // topic -> type
  {
    rosbag::View all(*bag);
    for (const rosbag::ConnectionInfo* c : all.getConnections()) topics[c->topic] = c->datatype;
  }
  std::vector<std::string> image_topics;
  for (const auto& [topic, type] : topics) {
    if (type == kImage || type == kCompressed) image_topics.push_back(topic);
  }
  if (image_topics.empty()) {
    throw Error() << "bag '" << path << "' has no images (no " << kImage << " or " << kCompressed
                  << " topic); its topics: " << TopicList(topics);
  }
  std::string left_topic = options.topic;
  if (left_topic.empty()) {
    if (image_topics.size() > 1) {
      throw Error() << "bag '" << path << "' has several image topics: choose one with --topic "
                    << "(and --right_topic for a stereo pair); its topics: " << TopicList(topics);
    }
    left_topic = image_topics.front();
  }
  const bool stereo = !options.right_topic.empty() && !options.force_mono;
  for (const std::string& topic : {left_topic, stereo ? options.right_topic : left_topic}) {
    const auto it = topics.find(topic);
    if (it == topics.end() || (it->second != kImage && it->second != kCompressed)) {
      throw Error() << "bag '" << path << "' has no image topic '" << topic
                    << "': give one of its image topics with --topic / --right_topic; its "
                    << "topics: " << TopicList(topics);
    }
  }

  // Index the images (and the camera infos) of the topics.
  std::vector<BagImage> left, right;
  std::map<std::string, sensor_msgs::CameraInfo::ConstPtr> infos;
  std::vector<std::string> wanted = {left_topic, CameraInfoTopic(left_topic)};
  if (stereo) {
    wanted.push_back(options.right_topic);
    wanted.push_back(CameraInfoTopic(options.right_topic));
  }
  std::map<int64_t, BagImage> right_by_time;
  rosbag::View view(*bag, rosbag::TopicQuery(wanted));
  for (const rosbag::MessageInstance& m : view) {
    const std::string& topic = m.getTopic();
    if (m.getDataType() == kCameraInfo) {
      if (infos.count(topic) == 0) infos[topic] = m.instantiate<sensor_msgs::CameraInfo>();
      continue;
    }
    int64_t t_ns = static_cast<int64_t>(m.getTime().toNSec());
    if (const auto image = m.instantiate<sensor_msgs::Image>()) {
      t_ns = StampNs(image->header.stamp, m.getTime());
    } else if (const auto compressed = m.instantiate<sensor_msgs::CompressedImage>()) {
      t_ns = StampNs(compressed->header.stamp, m.getTime());
    }
    const auto shared = std::make_shared<const rosbag::MessageInstance>(m);
    if (topic == left_topic) left.push_back({t_ns, shared});
    if (stereo && topic == options.right_topic) right_by_time.emplace(t_ns, BagImage{t_ns, shared});
  }
  std::sort(left.begin(), left.end(),
            [](const BagImage& a, const BagImage& b) { return a.t_ns < b.t_ns; });
  if (stereo) {
    std::vector<BagImage> paired;
    for (BagImage& image : left) {
      const auto it = right_by_time.find(image.t_ns);
      if (it == right_by_time.end()) continue;
      paired.push_back(std::move(image));
      right.push_back(it->second);
    }
    if (paired.size() < left.size()) {
      LOG(WARNING) << path << ": " << left.size() - paired.size() << " of " << left.size()
                   << " images of " << left_topic << " have no " << options.right_topic
                   << " image with the same stamp; skipped";
    }
    if (paired.empty()) {
      throw Error() << "bag '" << path << "': no image of " << left_topic << " has an image of "
                    << options.right_topic << " with the same header stamp; read it as "
                    << "monocular (drop --right_topic)";
    }
    left = std::move(paired);
  }
  for (size_t i = 1; i < left.size(); ++i) {
    if (left[i].t_ns == left[i - 1].t_ns) {
      throw Error() << "bag '" << path << "': two images of " << left_topic << " have the stamp "
                    << left[i].t_ns << " ns; dala needs increasing times";
    }
  }
  const FrameRange range = SelectFrames(left.size(), options, path);

  // Calibration: the file given, else the bag's CameraInfo.
  Rectification rect;
  cv::Size raw_size;
  if (!options.calibration_yaml.empty()) {
    const CameraCalibration calibration = ReadCameraCalibration(options.calibration_yaml);
    rect = MakeRectification(calibration, stereo);
    raw_size = cv::Size(calibration.cam0.width, calibration.cam0.height);
  } else {
    const std::string left_info = CameraInfoTopic(left_topic);
    if (infos.count(left_info) == 0 || (stereo && infos.count(CameraInfoTopic(options.right_topic)) == 0)) {
      throw Error() << "bag '" << path << "' has no " << kCameraInfo << " on " << left_info
                    << (stereo ? " and " + CameraInfoTopic(options.right_topic) : std::string())
                    << ": give the calibration with --calibration FILE (OpenCV, ROS camera_info, "
                    << "Kalibr or dala YAML)";
    }
    const sensor_msgs::CameraInfo& info0 = *infos[left_info];
    CameraCalibration calibration;
    calibration.path = path + " " + left_info;
    calibration.cam0 = CameraOfInfo(info0, calibration.path);
    raw_size = cv::Size(calibration.cam0.width, calibration.cam0.height);
    if (!stereo) {
      rect = MakeRectification(calibration, false);
    } else {
      // A calibrated ROS pair: rectify with each CameraInfo's R and P.
      const std::string right_info = CameraInfoTopic(options.right_topic);
      const sensor_msgs::CameraInfo& info1 = *infos[right_info];
      const RawCamera cam1 = CameraOfInfo(info1, path + " " + right_info);
      if (cam1.width != raw_size.width || cam1.height != raw_size.height ||
          cam1.model != calibration.cam0.model) {
        throw Error() << "bag '" << path << "': the camera infos of " << left_info << " and "
                      << right_info << " differ in image size or lens model";
      }
      const auto mat = [](const auto& a, int rows, int cols) {
        cv::Mat m(rows, cols, CV_64F);
        for (int k = 0; k < rows * cols; ++k) m.at<double>(k / cols, k % cols) = a[k];
        return m;
      };
      const cv::Mat R1 = mat(info0.R, 3, 3), R2 = mat(info1.R, 3, 3);
      const cv::Mat P1 = mat(info0.P, 3, 4), P2 = mat(info1.P, 3, 4);
      const cv::Mat K1 = P1.colRange(0, 3), K2 = P2.colRange(0, 3);
      const bool fisheye = calibration.cam0.model == LensModel::kFisheye;
      for (int cam = 0; cam < 2; ++cam) {
        const RawCamera& c = cam == 0 ? calibration.cam0 : cam1;
        cv::Mat& map1 = cam == 0 ? rect.left_map1 : rect.right_map1;
        cv::Mat& map2 = cam == 0 ? rect.left_map2 : rect.right_map2;
        if (fisheye) {
          cv::fisheye::initUndistortRectifyMap(c.K(), c.D(), cam == 0 ? R1 : R2,
                                               cam == 0 ? K1 : K2, raw_size, CV_16SC2, map1, map2);
        } else {
          cv::initUndistortRectifyMap(c.K(), c.D(), cam == 0 ? R1 : R2, cam == 0 ? K1 : K2,
                                      raw_size, CV_16SC2, map1, map2);
        }
      }
      rect.rig.left.width = raw_size.width;
      rect.rig.left.height = raw_size.height;
      rect.rig.left.fx = P1.at<double>(0, 0);
      rect.rig.left.fy = P1.at<double>(1, 1);
      rect.rig.left.cx = P1.at<double>(0, 2);
      rect.rig.left.cy = P1.at<double>(1, 2);
      rect.rig.baseline = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
      if (!(rect.rig.baseline > 0)) {
        throw Error() << "bag '" << path << "': the projection matrix P of " << right_info
                      << " gives no baseline (P[0,3] = -fx * baseline must be < 0): calibrate "
                      << "the pair (ROS camera_calibration, stereo) or give --calibration";
      }
      Eigen::Matrix3d R1e;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R1e(r, c) = R1.at<double>(r, c);
      }
      rect.T_c0_c0rect =
          Orthonormalized(MakePose(Eigen::Matrix3d(R1e.transpose()), Eigen::Vector3d::Zero()));
    }
    LOG(INFO) << path << ": calibration from the bag's " << left_info;
  }
  // Fail early on a first image of the wrong size.
  std::string why;
  const cv::Mat first = DecodeGray(*left[range.begin].message, &why);
  if (first.empty()) throw Error() << "bag '" << path << "': " << left_topic << ": " << why;
  if (first.size() != raw_size) {
    throw Error() << "bag '" << path << "': the images of " << left_topic << " are "
                  << first.cols << "x" << first.rows << ", but the calibration is for "
                  << raw_size.width << "x" << raw_size.height
                  << ": give the calibration of this camera at this resolution";
  }
  std::vector<std::optional<Pose>> gt;
  if (!options.ground_truth.empty()) {
    std::vector<int64_t> t_ns;
    for (const BagImage& image : left) t_ns.push_back(image.t_ns);
    gt = ReadGroundTruthFile(options.ground_truth, t_ns, options, rect.T_c0_c0rect);
  }
  if (!stereo) rect.rig.baseline = 0;
  return std::make_unique<BagDataset>(path, std::move(bag), std::move(left), std::move(right),
                                      std::move(rect), raw_size, range.begin, range.end,
                                      std::move(gt));
}

}  // namespace dala

#endif  // DALA_HAVE_ROSBAG
