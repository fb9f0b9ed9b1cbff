// The suite file, the run list and its shards (tools/bench/suite.h), percentiles.
#include "tools/bench/suite.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "core/error.h"
#include "tests/test_util.h"
#include "tools/bench/evaluate_run.h"

namespace dala::bench {
namespace {

using ::testing::HasSubstr;

std::string Write(const testing::TempDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

// The message of the dala::Error that LoadBenchSuite throws (empty when it does not throw).
std::string LoadError(const std::string& path) {
  return testing::ErrorOf([&] { LoadBenchSuite(path); });
}

TEST(BenchSuite, ReadsSequencesAndConfigurations) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "data/seq06");
  Write(dir, "extra.yaml", "a: 1\n");
  const std::string path = Write(dir, "suite.yaml",
                                 "timeout_s: 120\n"
                                 "sequences:\n"
                                 "  - {name: rover, preset: rover_loop, frames: 300, seed: 7}\n"
                                 "  - {name: kitti06, path: data/seq06}\n"
                                 "  - {name: mono_only, preset: flight, mono: true}\n"
                                 "configurations:\n"
                                 "  - {name: ba-stereo, estimator: ba, mode: stereo}\n"
                                 "  - name: ekf-mono\n"
                                 "    estimator: ekf\n"
                                 "    mode: mono\n"
                                 "    config: extra.yaml\n"
                                 "    set: [\"ekf.max_landmarks=40\", \"seed=3\"]\n"
                                 "  - {name: ba-mono-x3, estimator: ba, mode: mono, draws: 3}\n");
  const BenchSuite suite = LoadBenchSuite(path);
  EXPECT_DOUBLE_EQ(suite.timeout_s, 120.0);
  ASSERT_EQ(suite.sequences.size(), 3u);
  EXPECT_EQ(suite.sequences[0].preset, "rover_loop");
  EXPECT_EQ(suite.sequences[0].frames, 300);
  EXPECT_EQ(suite.sequences[0].seed, 7);
  EXPECT_TRUE(suite.sequences[0].is_rendered());
  // Relative paths are relative to the suite file.
  EXPECT_EQ(suite.sequences[1].path, dir / "data/seq06");
  EXPECT_FALSE(suite.sequences[1].is_rendered());
  EXPECT_TRUE(suite.sequences[2].mono);
  EXPECT_EQ(suite.sequences[2].frames, 0);
  ASSERT_EQ(suite.configurations.size(), 3u);
  EXPECT_EQ(suite.configurations[0].draws, 1);
  EXPECT_EQ(suite.configurations[2].draws, 3);
  EXPECT_EQ(suite.configurations[1].estimator, "ekf");
  EXPECT_EQ(suite.configurations[1].mode, "mono");
  EXPECT_EQ(suite.configurations[1].config_file, dir / "extra.yaml");
  EXPECT_THAT(suite.configurations[1].set,
              ::testing::ElementsAre("ekf.max_landmarks=40", "seed=3"));
}

TEST(BenchSuite, ErrorsNameTheFileTheKeyAndWhatIsExpected) {
  testing::TempDir dir;
  const std::string seqs = "sequences:\n  - {name: a, preset: rover_loop}\n";
  const std::string cfgs = "configurations:\n  - {name: c, estimator: ba, mode: stereo}\n";
  struct Case {
    std::string yaml;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {seqs + "configurations:\n  - {name: c, estimator: orb, mode: stereo}\n",
       "configurations[0].estimator: unknown estimator 'orb'; expected ba or ekf"},
      {seqs + "configurations:\n  - {name: c, estimator: ba, mode: rgbd}\n",
       "configurations[0].mode: unknown mode 'rgbd'; expected stereo or mono"},
      {seqs + "configurations:\n  - {name: c, estimator: ba}\n", "configurations[0].mode: missing"},
      {"sequences:\n  - {name: a, preset: rover_loop, frams: 3}\n" + cfgs,
       "sequences[0].frams: unknown key"},
      {"sequences:\n  - {name: a, preset: rover_loop, frames: -3}\n" + cfgs,
       "sequences[0].frames: expected an integer >= 0"},
      {"sequences:\n  - {name: a, path: no/such/folder}\n" + cfgs,
       "sequences[0].path: dataset folder"},
      {"sequences:\n  - {name: a, path: ., preset: flight}\n" + cfgs,
       "sequences[0]: give exactly one of 'path'"},
      {"sequences:\n  - {name: a, preset: flight}\n  - {name: a, preset: fast}\n" + cfgs,
       "sequences[1].name: duplicate sequence name 'a'"},
      {"sequences:\n  - {name: \"a/b\", preset: flight}\n" + cfgs,
       "sequences[0].name: 'a/b' is not a valid name"},
      {seqs + "configurations:\n  - {name: c, estimator: ba, mode: mono, set: [\"novalue\"]}\n",
       "configurations[0].set[0]: expected a \"key=value\" string"},
      {seqs + "configurations:\n  - {name: c, estimator: ba, mode: mono, draws: 0}\n",
       "configurations[0].draws: expected an integer >= 1"},
      {seqs, "configurations: missing or empty"},
      {seqs + cfgs + "timeout: 3\n", "timeout: unknown key; expected one of"},
  };
  for (const Case& c : cases) {
    const std::string path = Write(dir, "suite.yaml", c.yaml);
    const std::string message = LoadError(path);
    EXPECT_THAT(message, HasSubstr(path + ": ")) << c.yaml;
    EXPECT_THAT(message, HasSubstr(c.expected)) << c.yaml;
  }
  EXPECT_THAT(LoadError(dir / "missing.yaml"), HasSubstr("the suite file does not exist"));
}

TEST(BenchSuite, DatasetFlagAddsAFolderNamedAfterIt) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "seq_06");
  BenchSuite suite;
  AddDatasetSequence(dir / "seq_06/", &suite);
  ASSERT_EQ(suite.sequences.size(), 1u);
  EXPECT_EQ(suite.sequences[0].name, "seq_06");
  EXPECT_EQ(suite.sequences[0].path, dir / "seq_06");
  EXPECT_THROW(AddDatasetSequence(dir / "seq_06", &suite), Error);  // Name taken.
  EXPECT_THROW(AddDatasetSequence(dir / "nope", &suite), Error);
}

TEST(BenchSuite, DefaultSuiteIsValid) {
  const BenchSuite suite =
      LoadBenchSuite(std::string(DALA_SOURCE_DIR) + "/benchmarks/default.yaml");
  // The KITTI clip is optional: present with ../shared/data, skipped with a note without it.
  EXPECT_EQ(suite.sequences.size() + suite.skipped.size(), 6u);
  EXPECT_EQ(suite.configurations.size(), 5u);
  int rendered_frames = 0;  // Every seed rendered once.
  for (const SequenceSpec& s : suite.sequences) {
    if (!s.is_rendered()) {
      EXPECT_EQ(s.starts.size(), 10u) << s.name;
      continue;
    }
    EXPECT_GT(s.frames, 0) << s.name;  // Explicit: the budget below depends on it.
    EXPECT_EQ(s.seeds.size(), 3u) << s.name;
    rendered_frames += s.frames * static_cast<int>(s.seeds.size());
  }
  EXPECT_EQ(rendered_frames, 5100);  // The budget in the suite's comment.
  // The clip's runs from start frames 0..9 of its 51 frames, whether or not it is here.
  const int clip_frames = 51 * 10 - 45;
  // The suite must run in < 15 min on 2 cores at ~30 ms per frame and run and ~0.1 s per
  // rendered frame: keep the CPU of runs and rendering under 80% of that.
  const double cpu_s = (rendered_frames + clip_frames) * 5 * 0.030 + rendered_frames * 0.1;
  EXPECT_LT(cpu_s, 0.8 * 2 * 15 * 60);
}

TEST(BenchRunList, IsSortedAndShardsPartitionIt) {
  BenchSuite suite;
  for (const char* name : {"zeta", "alpha", "mid"}) {
    SequenceSpec s;
    s.name = name;
    s.preset = "fast";
    suite.sequences.push_back(s);
  }
  for (const char* name : {"ekf-stereo", "ba-stereo"}) {
    ConfigSpec c;
    c.name = name;
    suite.configurations.push_back(c);
  }
  const std::vector<BenchRun> runs = MakeRunList(suite);
  ASSERT_EQ(runs.size(), 6u);
  std::vector<std::string> keys;
  for (const BenchRun& r : runs) keys.push_back(r.key());
  EXPECT_THAT(keys, ::testing::ElementsAre("alpha/ba-stereo", "alpha/ekf-stereo", "mid/ba-stereo",
                                           "mid/ekf-stereo", "zeta/ba-stereo", "zeta/ekf-stereo"));
  for (int n = 1; n <= 7; ++n) {
    std::multiset<std::string> seen;
    for (int i = 0; i < n; ++i) {
      for (const BenchRun& r : SelectShard(runs, {i, n})) {
        EXPECT_EQ(r.index % n, i);
        seen.insert(r.key());
      }
    }
    EXPECT_EQ(seen, std::multiset<std::string>(keys.begin(), keys.end())) << "n = " << n;
  }
}

TEST(BenchShard, ParsesIOverN) {
  const Shard s = ParseShard("2/5");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 5);
  EXPECT_EQ(s.ToString(), "2/5");
  for (const char* bad : {"5/5", "-1/3", "1", "a/b", "1/0", "1/2x", ""}) {
    EXPECT_THROW(ParseShard(bad), Error) << bad;
  }
}

TEST(BenchPercentile, InterpolatesLikeNumpy) {
  EXPECT_FALSE(Percentile({}, 50).has_value());
  EXPECT_DOUBLE_EQ(*Percentile({3.0}, 95), 3.0);
  EXPECT_DOUBLE_EQ(*Percentile({4, 1, 3, 2}, 50), 2.5);
  // numpy.percentile([1..10], 95) = 9.55
  EXPECT_NEAR(*Percentile({10, 9, 8, 7, 6, 5, 4, 3, 2, 1}, 95), 9.55, 1e-12);
  EXPECT_DOUBLE_EQ(*Percentile({1, 2, 3}, 100), 3.0);
  EXPECT_DOUBLE_EQ(*Percentile({1, 2, 3}, 0), 1.0);
}

}  // namespace
}  // namespace dala::bench

namespace dala::bench {
namespace {

TEST(BenchGroundTruth, KittiFolderUsesPosesAndTimes) {
  DALA_SKIP_WITHOUT_SHARED_DATA("kitti06_0000-0050");
  std::string why;
  const auto gt = LoadGroundTruth(testing::SharedDataDir() + "/kitti06_0000-0050", &why);
  ASSERT_TRUE(gt.has_value()) << why;
  EXPECT_EQ(gt->size(), 51u);
  EXPECT_TRUE(gt->has_timestamps);
  EXPECT_EQ(gt->poses[10].t_ns, 1000000000);  // times.txt: 0.1 s steps.
  EXPECT_GT(gt->PathLength(), 40.0);
}

TEST(BenchGroundTruth, EurocFolderGoesThroughOpenDataset) {
  DALA_SKIP_WITHOUT_SHARED_DATA("euroc_v101_micro");
  std::string why;
  const auto gt = LoadGroundTruth(testing::SharedDataDir() + "/euroc_v101_micro", &why);
  ASSERT_TRUE(gt.has_value()) << why;
  EXPECT_GT(gt->size(), 10u);  // Interpolated at (most of) the 20 frame times.
  EXPECT_LE(gt->size(), 20u);
  EXPECT_TRUE(gt->has_timestamps);
}

TEST(BenchGroundTruth, AFolderWithoutOneSaysWhy) {
  testing::TempDir dir;
  std::string why;
  EXPECT_FALSE(LoadGroundTruth(dir.path(), &why).has_value());
  EXPECT_THAT(why, HasSubstr(dir.path()));
}

}  // namespace
}  // namespace dala::bench
