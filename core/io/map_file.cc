#include "core/io/map_file.h"

#include <glog/logging.h>

#include <Eigen/Geometry>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <type_traits>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/quantized_descriptors.h"

namespace dala {
namespace {

constexpr char kMagic[8] = {'D', 'A', 'L', 'A', 'M', 'A', 'P', '\0'};

// The format is little-endian; so is every platform dala builds on (x86-64, aarch64).
bool HostIsLittleEndian() {
  const uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

constexpr uint64_t kFnvOffset = 0xcbf29ce484222325ull;
constexpr uint64_t kFnvPrime = 0x100000001b3ull;

uint64_t Fnv1a(const char* data, size_t n, uint64_t h = kFnvOffset) {
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= kFnvPrime;
  }
  return h;
}

// Streams the body to `os` and hashes it on the way: a map is written without a second copy
// of it in memory (a 1000-keyframe map is ~0.5 GB of descriptors).
class Writer {
 public:
  explicit Writer(std::ostream* os) : os_(os) {}
  template <typename T>
  void Put(T value) {
    static_assert(std::is_trivially_copyable_v<T>);
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    PutRaw(raw, sizeof(T));
  }
  void PutRaw(const char* data, size_t n) {
    hash_ = Fnv1a(data, n, hash_);
    os_->write(data, static_cast<std::streamsize>(n));
  }
  uint64_t hash() const { return hash_; }

 private:
  std::ostream* os_;
  uint64_t hash_ = kFnvOffset;
};

// Reads the body (everything but the trailing hash) with bounds checks.
class Reader {
 public:
  Reader(const std::string& path, const std::string& bytes, size_t end)
      : path_(path), bytes_(bytes), end_(end) {}
  template <typename T>
  T Get(const char* what) {
    T value;
    if (end_ - pos_ < sizeof(T)) {
      throw Error() << path_ << ": truncated map file (ends inside " << what << " at byte " << pos_
                    << "); write it again with SaveMap";
    }
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // A count of items of at least `min_item_bytes` each must fit in what remains.
  uint64_t GetCount(const char* what, size_t min_item_bytes) {
    const uint64_t n = Get<uint64_t>(what);
    if (min_item_bytes > 0 && n > (end_ - pos_) / min_item_bytes) {
      throw Error() << path_ << ": corrupted map file: " << n << " " << what
                    << " do not fit in the remaining " << (end_ - pos_) << " bytes";
    }
    return n;
  }
  size_t pos() const { return pos_; }

 private:
  const std::string& path_;
  const std::string& bytes_;
  size_t end_;
  size_t pos_ = 0;
};

void PutPose(const Pose& T, Writer* w) {
  const Eigen::Quaterniond q(T.rotation());
  for (double v : {q.x(), q.y(), q.z(), q.w()}) w->Put(v);
  for (int i = 0; i < 3; ++i) w->Put(T.translation()[i]);
}

Pose GetPose(Reader* r) {
  double v[7];
  for (double& x : v) x = r->Get<double>("a keyframe pose");
  Eigen::Quaterniond q(v[3], v[0], v[1], v[2]);
  const double norm = q.norm();
  if (!(norm > 0.5 && norm < 2.0)) {
    throw Error() << "keyframe pose with quaternion norm " << norm;
  }
  return MakePose(q.normalized(), Eigen::Vector3d(v[4], v[5], v[6]));
}

}  // namespace

void WriteMapFile(const std::string& path, const SavedMap& map,
                  const std::vector<SavedKeyframe>& keyframes) {
  if (!map.keyframes.empty()) {
    throw Error() << path << ": the keyframes are given twice (in the map and beside it)";
  }
  CHECK(HostIsLittleEndian()) << "dala map files are little-endian";
  if (map.descriptor_size < 0) throw Error() << path << ": negative descriptor size";
  for (const SavedKeyframe& kf : keyframes) {
    for (const SavedKeyframePoint& p : kf.points) {
      const bool has = !p.descriptor.empty();
      if ((has && static_cast<int>(p.descriptor.size()) != map.descriptor_size) ||
          (!has && map.descriptor_size != 0)) {
        throw Error() << path << ": keyframe " << kf.frame << " has a point with "
                      << p.descriptor.size() << " descriptor values, the map declares "
                      << map.descriptor_size;
      }
    }
  }
  // The reader's limits: a map this writes must read back.
  if (map.descriptor_size > static_cast<int>(kMaxDescriptorSize)) {
    throw Error() << path << ": descriptor size " << map.descriptor_size << " above "
                  << kMaxDescriptorSize;
  }
  if (map.thumbnail_width < 0 || map.thumbnail_height < 0 ||
      map.thumbnail_width > static_cast<int>(kMaxThumbnailSide) ||
      map.thumbnail_height > static_cast<int>(kMaxThumbnailSide)) {
    throw Error() << path << ": thumbnail size " << map.thumbnail_width << "x"
                  << map.thumbnail_height << " outside 0.." << kMaxThumbnailSide;
  }
  const size_t thumbnail_size = static_cast<size_t>(map.thumbnail_width) * map.thumbnail_height;
  for (const SavedKeyframe& kf : keyframes) {
    if (kf.thumbnail.size() != thumbnail_size) {
      throw Error() << path << ": keyframe " << kf.frame << " has a thumbnail of "
                    << kf.thumbnail.size() << " values, the map declares " << map.thumbnail_width
                    << "x" << map.thumbnail_height;
    }
  }
  WriteFileAtomically(path, [&](std::ostream& os) {
    Writer w(&os);
    w.PutRaw(kMagic, sizeof(kMagic));
    w.Put<uint32_t>(MapFileVersion::kCurrent);
    w.Put<uint32_t>(static_cast<uint32_t>(map.descriptor_size));
    w.Put<uint64_t>(keyframes.size());
    for (const SavedKeyframe& kf : keyframes) {
      w.Put<int64_t>(kf.frame.value);
      w.Put<int64_t>(kf.t_ns);
      PutPose(kf.T_w_c, &w);
      w.Put<uint64_t>(kf.points.size());
      for (const SavedKeyframePoint& p : kf.points) {
        w.Put<int64_t>(p.landmark.value);
        w.Put(p.uv.x());
        w.Put(p.uv.y());
        w.Put(p.orientation);
        w.Put(p.scale);
        w.Put(p.lambda1);
        w.Put(p.lambda2);
        w.PutRaw(reinterpret_cast<const char*>(p.descriptor.data()), p.descriptor.size());
      }
    }
    w.Put<uint64_t>(map.landmarks.size());
    for (const SavedLandmark& l : map.landmarks) {
      w.Put<int64_t>(l.id.value);
      for (int i = 0; i < 3; ++i) w.Put(l.p_w[i]);
      w.Put<int32_t>(l.observations);
    }
    w.Put<uint32_t>(map.metric ? 1 : 0);
    w.Put<uint32_t>(static_cast<uint32_t>(map.thumbnail_width));
    w.Put<uint32_t>(static_cast<uint32_t>(map.thumbnail_height));
    for (const SavedKeyframe& kf : keyframes) {
      w.PutRaw(reinterpret_cast<const char*>(kf.thumbnail.data()),
               kf.thumbnail.size() * sizeof(float));
    }
    const uint64_t hash = w.hash();
    os.write(reinterpret_cast<const char*>(&hash), sizeof(hash));
  });
}

void WriteMapFile(const std::string& path, const SavedMap& map) {
  SavedMap header = map;
  header.keyframes.clear();
  WriteMapFile(path, header, map.keyframes);
}

SavedMap ReadMapFile(const std::string& path) {
  CHECK(HostIsLittleEndian()) << "dala map files are little-endian";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error() << path << ": cannot open the map file (does it exist?)";
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw Error() << path << ": not a dala map file (no DALAMAP header); maps are written by "
                  << "System::SaveMap";
  }
  if (bytes.size() < sizeof(kMagic) + 8 + 8) {
    throw Error() << path << ": truncated map file (" << bytes.size() << " bytes)";
  }
  uint32_t version;
  std::memcpy(&version, bytes.data() + sizeof(kMagic), sizeof(version));
  if (version != MapFileVersion::kCurrent && version != MapFileVersion::kFloatDescriptors) {
    throw Error() << path << ": map file version " << version << "; this build reads versions "
                  << MapFileVersion::kFloatDescriptors << " and " << MapFileVersion::kCurrent
                  << " only (save the map again with this build)";
  }
  const bool float_descriptors = version == MapFileVersion::kFloatDescriptors;
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t stored_hash;
  std::memcpy(&stored_hash, bytes.data() + body, sizeof(stored_hash));
  if (Fnv1a(bytes.data(), body) != stored_hash) {
    throw Error() << path << ": corrupted or truncated map file (hash mismatch); write it again "
                  << "with SaveMap";
  }

  Reader r(path, bytes, body);
  SavedMap map;
  try {
    for (size_t i = 0; i < sizeof(kMagic); ++i) r.Get<char>("the header");
    r.Get<uint32_t>("the version");
    // Checked while unsigned: 0xFFFFFFFF cast to int is -1, which passed a signed check.
    const uint32_t descriptor_size = r.Get<uint32_t>("the descriptor size");
    if (descriptor_size > kMaxDescriptorSize) {
      throw Error() << path << ": implausible descriptor size " << descriptor_size;
    }
    map.descriptor_size = static_cast<int>(descriptor_size);
    const size_t point_bytes =
        8 + 16 + 16 + (float_descriptors ? 4 : 1) * static_cast<size_t>(map.descriptor_size);
    std::vector<float> float_descriptor(map.descriptor_size);
    const uint64_t num_keyframes = r.GetCount("keyframes", 8 + 8 + 56 + 8);
    map.keyframes.resize(num_keyframes);
    for (SavedKeyframe& kf : map.keyframes) {
      kf.frame = FrameId(r.Get<int64_t>("a keyframe"));
      kf.t_ns = r.Get<int64_t>("a keyframe");
      kf.T_w_c = GetPose(&r);
      kf.points.resize(r.GetCount("keyframe points", point_bytes));
      for (SavedKeyframePoint& p : kf.points) {
        p.landmark = LandmarkId(r.Get<int64_t>("a point"));
        p.uv.x() = r.Get<double>("a point");
        p.uv.y() = r.Get<double>("a point");
        p.orientation = r.Get<float>("a point");
        p.scale = r.Get<float>("a point");
        p.lambda1 = r.Get<float>("a point");
        p.lambda2 = r.Get<float>("a point");
        p.descriptor.resize(map.descriptor_size);
        if (float_descriptors) {
          for (float& d : float_descriptor) d = r.Get<float>("a descriptor");
          if (map.descriptor_size > 0) {
            QuantizeDescriptor(float_descriptor.data(), map.descriptor_size, p.descriptor.data());
          }
        } else {
          for (int8_t& d : p.descriptor) d = r.Get<int8_t>("a descriptor");
        }
      }
    }
    map.landmarks.resize(r.GetCount("landmarks", 8 + 24 + 4));
    for (SavedLandmark& l : map.landmarks) {
      l.id = LandmarkId(r.Get<int64_t>("a landmark"));
      for (int i = 0; i < 3; ++i) l.p_w[i] = r.Get<double>("a landmark");
      l.observations = r.Get<int32_t>("a landmark");
    }
    const uint32_t metric = r.Get<uint32_t>("the metric flag");
    if (metric > 1) throw Error() << path << ": metric flag " << metric << " is not 0 or 1";
    map.metric = metric == 1;
    // Checked while unsigned, each and their product against the bytes left.
    const uint32_t width = r.Get<uint32_t>("the thumbnail size");
    const uint32_t height = r.Get<uint32_t>("the thumbnail size");
    if (width > kMaxThumbnailSide || height > kMaxThumbnailSide) {
      throw Error() << path << ": implausible thumbnail size " << width << "x" << height;
    }
    const size_t thumbnail_bytes = sizeof(float) * static_cast<size_t>(width) * height;
    if (thumbnail_bytes > 0 && map.keyframes.size() > (body - r.pos()) / thumbnail_bytes) {
      throw Error() << path << ": corrupted map file: " << map.keyframes.size() << " thumbnails of "
                    << width << "x" << height << " do not fit in the remaining "
                    << (body - r.pos()) << " bytes";
    }
    map.thumbnail_width = static_cast<int>(width);
    map.thumbnail_height = static_cast<int>(height);
    for (SavedKeyframe& kf : map.keyframes) {
      kf.thumbnail.resize(static_cast<size_t>(width) * height);
      for (float& v : kf.thumbnail) v = r.Get<float>("a thumbnail");
    }
  } catch (const Error& e) {
    const std::string message = e.message();
    if (message.rfind(path, 0) == 0) throw;
    throw Error() << path << ": corrupted map file: " << message;
  }
  if (r.pos() != body) {
    throw Error() << path << ": corrupted map file: " << (body - r.pos())
                  << " unexpected bytes after the thumbnails";
  }
  return map;
}

}  // namespace dala
