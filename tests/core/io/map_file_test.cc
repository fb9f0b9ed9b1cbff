#include "core/io/map_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include <fstream>
#include <iterator>
#include <random>

#include "core/error.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;

// MakeMap's thumbnails: 3 keyframes of 4x3 floats, the last bytes before the hash.
constexpr size_t kThumbnailBytes = 3 * 12 * sizeof(float);

SavedMap MakeMap(int descriptor_size) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 5.0);
  SavedMap map;
  map.descriptor_size = descriptor_size;
  map.metric = false;
  map.thumbnail_width = 4;
  map.thumbnail_height = 3;
  for (int k = 0; k < 3; ++k) {
    SavedKeyframe kf;
    for (int i = 0; i < 12; ++i) kf.thumbnail.push_back(static_cast<float>(n(rng)));
    kf.frame = FrameId(10 * k + 1);
    kf.t_ns = 1'000'000'007LL * k;
    kf.T_w_c = testing::RandomPose(rng, 1.0, 3.0);
    for (int i = 0; i < 5 + k; ++i) {
      SavedKeyframePoint p;
      p.landmark = LandmarkId(i % 2 ? 100 + i : -1);
      p.uv = Eigen::Vector2d(n(rng) + 300, n(rng) + 200);
      p.orientation = static_cast<float>(0.1 * i);
      p.scale = 1.41421356f;
      p.lambda1 = 900.f + i;
      p.lambda2 = 300.f - i;
      for (int d = 0; d < descriptor_size; ++d) {
        p.descriptor.push_back(static_cast<int8_t>(std::clamp(10.0 * n(rng), -127.0, 127.0)));
      }
      kf.points.push_back(p);
    }
    map.keyframes.push_back(kf);
  }
  for (int i = 0; i < 4; ++i) {
    map.landmarks.push_back({LandmarkId(100 + i), Eigen::Vector3d(n(rng), n(rng), n(rng)), i + 2});
  }
  return map;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}
// Replaces the trailing FNV-1a hash with the one of the (modified) body, as WriteMapFile computes
// it: a crafted file then gets past the checksum to the parser.
std::string WithValidHash(std::string bytes) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (size_t i = 0; i + 8 < bytes.size(); ++i) {
    hash ^= static_cast<unsigned char>(bytes[i]);
    hash *= 0x100000001b3ull;
  }
  std::memcpy(&bytes[bytes.size() - 8], &hash, sizeof(hash));
  return bytes;
}

// How ReadMapFile ended on a file, run in a child process whose address space may grow by at
// most 256 MB: a crash or an unbounded allocation (std::bad_alloc, std::length_error) cannot
// take the test binary down, and is told apart from a clean dala::Error.
enum class ReadOutcome { kLoaded, kDalaError, kOtherException, kCrashed };
const char* Name(ReadOutcome o) {
  switch (o) {
    case ReadOutcome::kLoaded: return "loaded";
    case ReadOutcome::kDalaError: return "dala::Error";
    case ReadOutcome::kOtherException: return "another exception (bad_alloc, length_error...)";
    case ReadOutcome::kCrashed: return "crashed";
  }
  return "?";
}
ReadOutcome ReadInChild(const std::string& path) {
  const pid_t pid = fork();
  if (pid == 0) {
#if !defined(__SANITIZE_ADDRESS__)  // ASan reserves terabytes of address space up front.
    long pages = 0;
    std::ifstream("/proc/self/statm") >> pages;
    const rlim_t cap = static_cast<rlim_t>(pages) * sysconf(_SC_PAGESIZE) + (256u << 20);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
#endif
    int code = 0;
    try {
      ReadMapFile(path);
    } catch (const Error&) {
      code = 1;
    } catch (...) {
      code = 2;
    }
    _exit(code);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status)) return ReadOutcome::kCrashed;
  const ReadOutcome outcomes[] = {ReadOutcome::kLoaded, ReadOutcome::kDalaError,
                                  ReadOutcome::kOtherException};
  return WEXITSTATUS(status) <= 2 ? outcomes[WEXITSTATUS(status)] : ReadOutcome::kCrashed;
}

std::string ReadError(const std::string& path) {
  try {
    ReadMapFile(path);
  } catch (const Error& e) {
    return e.message();
  }
  return "no error";
}

TEST(MapFileTest, RoundTripIsExact) {
  testing::TempDir dir;
  for (int descriptor_size : {0, 121}) {
    const SavedMap map = MakeMap(descriptor_size);
    WriteMapFile(dir / "m.dmap", map);
    const SavedMap back = ReadMapFile(dir / "m.dmap");
    ASSERT_EQ(back.descriptor_size, descriptor_size);
    EXPECT_EQ(back.metric, map.metric);
    EXPECT_EQ(back.thumbnail_width, 4);
    EXPECT_EQ(back.thumbnail_height, 3);
    ASSERT_EQ(back.keyframes.size(), map.keyframes.size());
    for (size_t k = 0; k < map.keyframes.size(); ++k) {
      const SavedKeyframe& a = map.keyframes[k];
      const SavedKeyframe& b = back.keyframes[k];
      EXPECT_EQ(a.frame, b.frame);
      EXPECT_EQ(a.t_ns, b.t_ns);
      EXPECT_POSE_NEAR(a.T_w_c, b.T_w_c, 1e-15);
      ASSERT_EQ(a.points.size(), b.points.size());
      for (size_t i = 0; i < a.points.size(); ++i) {
        EXPECT_EQ(a.points[i].landmark, b.points[i].landmark);
        EXPECT_EQ(a.points[i].uv, b.points[i].uv);
        EXPECT_EQ(a.points[i].orientation, b.points[i].orientation);
        EXPECT_EQ(a.points[i].scale, b.points[i].scale);
        EXPECT_EQ(a.points[i].lambda1, b.points[i].lambda1);
        EXPECT_EQ(a.points[i].lambda2, b.points[i].lambda2);
        EXPECT_EQ(a.points[i].descriptor, b.points[i].descriptor);
      }
      EXPECT_EQ(a.thumbnail, b.thumbnail);
    }
    ASSERT_EQ(back.landmarks.size(), map.landmarks.size());
    for (size_t i = 0; i < map.landmarks.size(); ++i) {
      EXPECT_EQ(back.landmarks[i].id, map.landmarks[i].id);
      EXPECT_EQ(back.landmarks[i].p_w, map.landmarks[i].p_w);
      EXPECT_EQ(back.landmarks[i].observations, map.landmarks[i].observations);
    }
  }
}

TEST(MapFileTest, EmptyMapRoundTrips) {
  testing::TempDir dir;
  WriteMapFile(dir / "e.dmap", SavedMap());
  const SavedMap back = ReadMapFile(dir / "e.dmap");
  EXPECT_TRUE(back.keyframes.empty());
  EXPECT_TRUE(back.landmarks.empty());
}

TEST(MapFileTest, BadFilesGiveClearErrors) {
  testing::TempDir dir;
  EXPECT_THAT(ReadError(dir / "missing.dmap"), HasSubstr("cannot open"));
  WriteBytes(dir / "text.dmap", "# TUM trajectory\n0 0 0 0 0 0 0 1\n");
  EXPECT_THAT(ReadError(dir / "text.dmap"), HasSubstr("not a dala map file"));

  WriteMapFile(dir / "m.dmap", MakeMap(121));
  const std::string good = ReadBytes(dir / "m.dmap");

  std::string future = good;
  future[8] = 7;  // version field
  WriteBytes(dir / "v.dmap", future);
  EXPECT_THAT(ReadError(dir / "v.dmap"), HasSubstr("version 7"));

  for (size_t cut : {good.size() - 1, good.size() / 2, size_t{20}}) {
    WriteBytes(dir / "t.dmap", good.substr(0, cut));
    EXPECT_THAT(ReadError(dir / "t.dmap"), HasSubstr("truncated")) << "cut at " << cut;
  }
  std::string flipped = good;
  flipped[good.size() / 3] ^= 0x10;
  WriteBytes(dir / "f.dmap", flipped);
  EXPECT_THAT(ReadError(dir / "f.dmap"), HasSubstr("corrupted"));
}

// A crafted file with a valid checksum and descriptor size 0xFFFFFFFF: a clear error (it used
// to pass the size check as int -1 and abort in std::vector::resize with std::length_error).
TEST(MapFileTest, HugeDescriptorSizeWithAValidChecksumIsAClearError) {
  testing::TempDir dir;
  WriteMapFile(dir / "m.dmap", MakeMap(121));
  std::string bytes = ReadBytes(dir / "m.dmap");
  for (size_t i = 12; i < 16; ++i) bytes[i] = static_cast<char>(0xFF);  // After magic, version.
  WriteBytes(dir / "crafted.dmap", WithValidHash(bytes));
  EXPECT_THAT(ReadError(dir / "crafted.dmap"), HasSubstr("implausible descriptor size 4294967295"));
}

// A map from a stranger, cut at every 1/16 of its length: a dala::Error each time, in a child
// process whose memory is capped (never a crash or a large allocation).
TEST(MapFileTest, FileCutAtEverySixteenthIsAnError) {
  testing::TempDir dir;
  WriteMapFile(dir / "m.dmap", MakeMap(121));
  const std::string good = ReadBytes(dir / "m.dmap");
  for (size_t k = 0; k < 16; ++k) {
    const size_t cut = good.size() * k / 16;
    WriteBytes(dir / "cut.dmap", good.substr(0, cut));
    EXPECT_EQ(ReadInChild(dir / "cut.dmap"), ReadOutcome::kDalaError)
        << "cut at " << cut << " of " << good.size() << " bytes";
    // The same cut with a checksum that matches what is left: still refused, as truncated.
    if (cut >= 24) {
      WriteBytes(dir / "cut.dmap", WithValidHash(good.substr(0, cut)));
      EXPECT_THAT(ReadError(dir / "cut.dmap"), HasSubstr("corrupted")) << "cut at " << cut;
      EXPECT_EQ(ReadInChild(dir / "cut.dmap"), ReadOutcome::kDalaError) << "cut at " << cut;
    }
  }
}

// Flipped bytes: refused by the checksum; with the checksum made valid again, the parser either
// loads the map (a flipped coordinate or descriptor value is still a map) or refuses it with a
// dala::Error; a flipped count or size is always refused. Never a crash or a large allocation.
TEST(MapFileTest, FlippedBytesNeverCrashOrAllocateWithoutBound) {
  testing::TempDir dir;
  WriteMapFile(dir / "m.dmap", MakeMap(121));
  const std::string good = ReadBytes(dir / "m.dmap");
  std::vector<size_t> positions;
  for (size_t k = 0; k < 16; ++k) positions.push_back(good.size() * k / 16);
  // The counts and sizes: descriptor size, keyframe count, the first keyframe's point count
  // (after its ids and pose), the landmark count (4 landmarks of 36 bytes before the metric flag
  // and the thumbnail size), the thumbnail width and height.
  const size_t first_points = 8 + 4 + 4 + 8 + 8 + 8 + 56;
  const size_t tail = 8 + kThumbnailBytes;  // The thumbnails and the hash.
  const size_t landmarks = good.size() - tail - 12 - 4 * 36 - 8;
  const size_t thumbnail_size = good.size() - tail - 8;
  const std::vector<size_t> counts = {12, 15, 16, 20, 23, first_points, first_points + 7,
                                      landmarks, landmarks + 7, thumbnail_size,
                                      thumbnail_size + 3, thumbnail_size + 4, thumbnail_size + 7};
  positions.insert(positions.end(), counts.begin(), counts.end());
  for (size_t pos : positions) {
    for (unsigned char mask : {0x01, 0x80, 0xFF}) {
      std::string flipped = good;
      flipped[pos] = static_cast<char>(flipped[pos] ^ mask);
      WriteBytes(dir / "f.dmap", flipped);
      EXPECT_THAT(ReadError(dir / "f.dmap"), ::testing::AnyOf(HasSubstr("hash mismatch"),
                                                              HasSubstr("not a dala map"),
                                                              HasSubstr("version")))
          << "byte " << pos << " ^ " << int{mask};
      WriteBytes(dir / "f.dmap", WithValidHash(flipped));
      const ReadOutcome outcome = ReadInChild(dir / "f.dmap");
      const bool is_count = std::find(counts.begin(), counts.end(), pos) != counts.end();
      if (is_count) {
        EXPECT_EQ(outcome, ReadOutcome::kDalaError) << "count byte " << pos << " ^ " << int{mask};
      } else {
        EXPECT_TRUE(outcome == ReadOutcome::kLoaded || outcome == ReadOutcome::kDalaError)
            << "byte " << pos << " ^ " << int{mask} << ": " << Name(outcome);
      }
    }
  }
}

// Every count and size field set to extreme values, with a valid checksum: a dala::Error, never
// a std::length_error or a multi-GB allocation (0xFFFFFFFF as a descriptor size must not pass
// the size check as int -1 and abort in std::vector::resize).
TEST(MapFileTest, ExtremeCountsWithAValidChecksumAreErrors) {
  testing::TempDir dir;
  WriteMapFile(dir / "m.dmap", MakeMap(121));
  const std::string good = ReadBytes(dir / "m.dmap");
  const size_t first_points = 8 + 4 + 4 + 8 + 8 + 8 + 56;
  const size_t tail = 8 + kThumbnailBytes;
  const size_t landmarks = good.size() - tail - 12 - 4 * 36 - 8;
  const size_t metric = good.size() - tail - 12;  // The metric flag, then width and height.
  struct Field {
    size_t offset, size;
  };
  for (const Field f : {Field{12, 4}, Field{16, 8}, Field{first_points, 8}, Field{landmarks, 8},
                        Field{metric + 4, 4}, Field{metric + 8, 4}}) {
    for (const uint64_t value : {~0ull, 1ull << 63, (1ull << 31) - 1, 1ull << 31, 1ull << 32,
                                 0x1000000ull}) {
      std::string crafted = good;
      std::memcpy(&crafted[f.offset], &value, f.size);  // Little-endian: the low bytes.
      WriteBytes(dir / "c.dmap", WithValidHash(crafted));
      const ReadOutcome outcome = ReadInChild(dir / "c.dmap");
      EXPECT_EQ(outcome, ReadOutcome::kDalaError)
          << "field at byte " << f.offset << " = " << value << ": " << Name(outcome);
    }
  }
}

// The fuzzer's seeds (tests/fuzz/corpus/map_file_fuzzer) are maps of the versions the reader
// accepts, so that fuzzing starts from inputs that reach every field.
TEST(MapFileTest, FuzzSeedsAreValidMaps) {
  const std::filesystem::path dir =
      std::filesystem::path(DALA_SOURCE_DIR) / "tests/fuzz/corpus/map_file_fuzzer";
  int seeds = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_NO_THROW(ReadMapFile(entry.path().string())) << entry.path();
    ++seeds;
  }
  EXPECT_GE(seeds, 3);
  const SavedMap d4 = ReadMapFile((dir / "two_keyframes_d4.dmap").string());
  EXPECT_EQ(d4.thumbnail_width * d4.thumbnail_height, 4);
  EXPECT_EQ(d4.keyframes.at(1).points.at(1).lambda1, 901.f);
  // two_keyframes_d4.dmap is version 2 (float descriptors), two_keyframes_d4_v3.dmap the same
  // map written again by this build: the reader quantises version 2's descriptors as the writer
  // of version 3 stores them.
  EXPECT_EQ(ReadBytes((dir / "two_keyframes_d4.dmap").string())[8], 2);
  EXPECT_EQ(ReadBytes((dir / "two_keyframes_d4_v3.dmap").string())[8], 3);
  const SavedMap v3 = ReadMapFile((dir / "two_keyframes_d4_v3.dmap").string());
  ASSERT_EQ(v3.keyframes.size(), d4.keyframes.size());
  for (size_t k = 0; k < v3.keyframes.size(); ++k) {
    ASSERT_EQ(v3.keyframes[k].points.size(), d4.keyframes[k].points.size());
    for (size_t i = 0; i < v3.keyframes[k].points.size(); ++i) {
      EXPECT_EQ(v3.keyframes[k].points[i].descriptor, d4.keyframes[k].points[i].descriptor);
      EXPECT_EQ(v3.keyframes[k].points[i].descriptor.size(), 4u);
    }
  }
}

TEST(MapFileTest, DescriptorSizeMismatchIsRefusedAndWritesNothing) {
  testing::TempDir dir;
  SavedMap map = MakeMap(121);
  map.keyframes[1].points[2].descriptor.pop_back();
  EXPECT_THROW(WriteMapFile(dir / "bad.dmap", map), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.dmap"));
}

}  // namespace
}  // namespace dala
