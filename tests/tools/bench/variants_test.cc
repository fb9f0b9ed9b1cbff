// Sequences that stand for several runs: `starts` (dataset start frames), `seeds` (rendered
// presets), the --starts flag, optional dataset folders, the run list they expand into, and the
// spread statistics over them (tools/bench/suite.h, summary.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/error.h"
#include "tests/test_util.h"
#include "tools/bench/suite.h"
#include "tools/bench/summary.h"

namespace dala::bench {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::string Write(const testing::TempDir& dir, const std::string& text) {
  std::ofstream(dir / "suite.yaml") << text;
  return dir / "suite.yaml";
}

std::string LoadError(const std::string& path) {
  return testing::ErrorOf([&] { LoadBenchSuite(path); });
}

const char* kConfigs = "configurations:\n  - {name: c, estimator: ba, mode: stereo}\n";

TEST(BenchVariants, ReadsStartsAsAListOrACountAndSeedsAsAList) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "data");
  const BenchSuite suite =
      LoadBenchSuite(Write(dir,
                           "sequences:\n"
                           "  - {name: listed, path: data, starts: [10, 0, 5]}\n"
                           "  - {name: counted, path: data, starts: 3}\n"
                           "  - {name: plain, path: data}\n"
                           "  - {name: seeded, preset: flight, seeds: [3, 1, 2]}\n"
                           "  - {name: single, preset: flight, seed: 4}\n" +
                               std::string(kConfigs)));
  ASSERT_EQ(suite.sequences.size(), 5u);
  EXPECT_THAT(suite.sequences[0].starts, ElementsAre(0, 5, 10));  // Ascending.
  EXPECT_THAT(suite.sequences[1].starts, ElementsAre(0, 1, 2));
  EXPECT_TRUE(suite.sequences[2].starts.empty());
  EXPECT_THAT(suite.sequences[3].seeds, ElementsAre(1, 2, 3));
  EXPECT_TRUE(suite.sequences[4].seeds.empty());
  EXPECT_EQ(suite.sequences[4].seed, 4);
  EXPECT_TRUE(suite.skipped.empty());
}

TEST(BenchVariants, ErrorsNameTheFileAndTheKey) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "data");
  struct Case {
    std::string sequence;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"{name: a, path: data, starts: [0, -1]}",
       "sequences[0].starts[1]: expected a count N >= 1 (frames 0..N-1) or a non-empty list"},
      {"{name: a, path: data, starts: []}", "sequences[0].starts: expected a count N >= 1"},
      {"{name: a, path: data, starts: 0}", "sequences[0].starts: expected a count N >= 1"},
      {"{name: a, path: data, starts: -2}", "sequences[0].starts: expected a count N >= 1"},
      {"{name: a, path: data, starts: [1.5]}", "sequences[0].starts[0]: expected"},
      {"{name: a, path: data, starts: [\"x\"]}", "sequences[0].starts[0]: expected"},
      {"{name: a, path: data, starts: [4, 2, 4]}",
       "sequences[0].starts: 4 is listed twice; each value gives one run"},
      {"{name: a, preset: flight, seeds: []}",
       "sequences[0].seeds: expected a non-empty list of integers >= 0"},
      {"{name: a, preset: flight, seeds: 3}",
       "sequences[0].seeds: expected a non-empty list of integers >= 0"},
      {"{name: a, preset: flight, seeds: [1, -2]}", "sequences[0].seeds[1]: expected"},
      {"{name: a, preset: flight, seed: 1, seeds: [1, 2]}",
       "sequences[0].seeds: give either 'seed' (one run) or 'seeds' (one run per seed), not both"},
      {"{name: a, preset: flight, starts: [0]}",
       "sequences[0].starts: only for dataset folders ('path'), not with 'preset'"},
      {"{name: a, preset: flight, optional: true}",
       "sequences[0].optional: only for dataset folders"},
      {"{name: a, path: data, seeds: [1]}",
       "sequences[0].seeds: only for rendered presets, not with 'path'"},
      {"{name: a, path: data, optional: maybe}", "sequences[0].optional: expected true or false"},
      {"{name: a, path: absent}", "'optional: true' skips an absent folder"},
  };
  for (const Case& c : cases) {
    const std::string path = Write(dir, "sequences:\n  - " + c.sequence + "\n" + kConfigs);
    const std::string message = LoadError(path);
    EXPECT_THAT(message, HasSubstr(path + ": ")) << c.sequence;
    EXPECT_THAT(message, HasSubstr(c.expected)) << c.sequence;
  }
}

TEST(BenchVariants, AnAbsentOptionalDatasetIsSkippedWithANote) {
  testing::TempDir dir;
  const std::string path = Write(dir,
                                 "sequences:\n"
                                 "  - {name: shared, path: ../no/such/clip, starts: 10, "
                                 "optional: true}\n"
                                 "  - {name: r, preset: flight}\n" +
                                     std::string(kConfigs));
  const BenchSuite suite = LoadBenchSuite(path);
  ASSERT_EQ(suite.sequences.size(), 1u);
  EXPECT_EQ(suite.sequences[0].name, "r");
  ASSERT_EQ(suite.skipped.size(), 1u);
  EXPECT_THAT(suite.skipped[0], HasSubstr(path + ": sequences[0] (shared): optional dataset "
                                                 "folder "));
  EXPECT_THAT(suite.skipped[0], HasSubstr("no/such/clip is absent; skipped"));

  // A present optional folder is an ordinary sequence.
  std::filesystem::create_directories(dir / "clip");
  const BenchSuite present = LoadBenchSuite(
      Write(dir, "sequences:\n  - {name: shared, path: clip, starts: 2, optional: true}\n" +
                     std::string(kConfigs)));
  ASSERT_EQ(present.sequences.size(), 1u);
  EXPECT_TRUE(present.sequences[0].optional);
  EXPECT_THAT(present.sequences[0].starts, ElementsAre(0, 1));

  // Nothing left to run is an error.
  EXPECT_THAT(LoadError(Write(dir, "sequences:\n  - {name: s, path: gone, optional: true}\n" +
                                       std::string(kConfigs))),
              HasSubstr("sequences: every sequence is optional and absent; nothing to run"));
}

BenchSuite VariantSuite() {
  BenchSuite suite;
  SequenceSpec data;
  data.name = "kitti";
  data.path = "/data/kitti";
  data.starts = {0, 2, 10};  // 10 after 2: numeric order, not text order.
  SequenceSpec seeded;
  seeded.name = "flight";
  seeded.preset = "flight";
  seeded.seeds = {1, 2};
  SequenceSpec plain;
  plain.name = "rotation";
  plain.preset = "rotation";
  plain.seed = 5;
  suite.sequences = {data, seeded, plain};
  for (const char* name : {"ekf", "ba"}) {
    ConfigSpec c;
    c.name = name;
    suite.configurations.push_back(c);
  }
  return suite;
}

TEST(BenchVariants, RunListExpandsEveryVariantInAFixedOrder) {
  const std::vector<BenchRun> runs = MakeRunList(VariantSuite());
  std::vector<std::string> keys;
  for (const BenchRun& r : runs) keys.push_back(r.key());
  EXPECT_THAT(keys, ElementsAre("flight@seed1/ba", "flight@seed1/ekf", "flight@seed2/ba",
                                "flight@seed2/ekf", "kitti@start0/ba", "kitti@start0/ekf",
                                "kitti@start2/ba", "kitti@start2/ekf", "kitti@start10/ba",
                                "kitti@start10/ekf", "rotation/ba", "rotation/ekf"));
  for (size_t k = 0; k < runs.size(); ++k) EXPECT_EQ(runs[k].index, static_cast<int>(k));
  // The variant's own seed or start frame, and no list left on it.
  EXPECT_EQ(runs[2].sequence.seed, 2);
  EXPECT_TRUE(runs[2].sequence.seeds.empty());
  EXPECT_FALSE(runs[2].has_start());
  EXPECT_EQ(runs[8].first_frame, 10);
  EXPECT_TRUE(runs[8].has_start());
  EXPECT_EQ(runs[8].folder_name(), "kitti@start10");
  EXPECT_EQ(runs[10].variant, "");
  EXPECT_EQ(runs[10].sequence.seed, 5);
  EXPECT_EQ(runs[10].folder_name(), "rotation");

  // The same list whatever the order of the suite's entries: shards agree across machines.
  BenchSuite shuffled = VariantSuite();
  std::reverse(shuffled.sequences.begin(), shuffled.sequences.end());
  std::reverse(shuffled.configurations.begin(), shuffled.configurations.end());
  std::vector<std::string> again;
  for (const BenchRun& r : MakeRunList(shuffled)) again.push_back(r.key());
  EXPECT_EQ(again, keys);

  // Shards partition the variants.
  for (int n = 1; n <= 5; ++n) {
    std::multiset<std::string> seen;
    for (int i = 0; i < n; ++i) {
      for (const BenchRun& r : SelectShard(runs, {i, n})) seen.insert(r.key());
    }
    EXPECT_EQ(seen, std::multiset<std::string>(keys.begin(), keys.end())) << "n = " << n;
  }
}

TEST(BenchVariants, StartsFlagIsACountOrAList) {
  EXPECT_THAT(ParseStartsFlag("3"), ElementsAre(0, 1, 2));
  EXPECT_THAT(ParseStartsFlag("10,0,5"), ElementsAre(0, 5, 10));
  EXPECT_THAT(ParseStartsFlag("7,"), ElementsAre(7));
  EXPECT_THAT(ParseStartsFlag("0,"), ElementsAre(0));
  for (const char* bad : {"", "0", "-1", "a", "3x", "1,,2", "1,-2", ",", "2,2"}) {
    try {
      ParseStartsFlag(bad);
      ADD_FAILURE() << "accepted --starts=" << bad;
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), HasSubstr(std::string("--starts=") + bad + ":")) << bad;
    }
  }
}

TEST(BenchVariants, StartsFlagSetsEveryDatasetSequenceOnly) {
  BenchSuite suite = VariantSuite();
  SequenceSpec extra;
  extra.name = "added";
  extra.path = "/data/added";
  suite.sequences.push_back(extra);
  EXPECT_EQ(SetDatasetStarts({0, 4}, &suite), 2);
  EXPECT_THAT(suite.sequences[0].starts, ElementsAre(0, 4));  // Overridden.
  EXPECT_THAT(suite.sequences[3].starts, ElementsAre(0, 4));  // Set.
  EXPECT_TRUE(suite.sequences[1].starts.empty());             // Rendered: untouched.
  EXPECT_THAT(suite.sequences[1].seeds, ElementsAre(1, 2));
  EXPECT_EQ(MakeRunList(suite).size(), (2u + 2u + 1u + 2u) * 2u);
}

BenchRunResult Row(const std::string& seq, const std::string& config, const std::string& variant,
                   const std::string& status, std::optional<double> ate) {
  BenchRunResult r;
  r.sequence = seq;
  r.config = config;
  r.variant = variant;
  r.status = status;
  r.ate_rmse = ate;
  return r;
}

TEST(BenchSpread, MedianBestAndWorstWithTheRunThatGaveThem) {
  const std::vector<BenchRunResult> rows = {
      Row("k", "ba", "start0", kStatusOk, 0.3),
      Row("k", "ba", "start1", kStatusOk, 0.1),
      Row("k", "ba", "start2", kStatusOk, 0.7),  // Odd count: median 0.3.
      Row("k", "ekf", "start0", kStatusOk, 0.2),
      Row("k", "ekf", "start1", kStatusTimeout, std::nullopt),
      Row("k", "ekf", "start2", kStatusOk, 0.6),
      Row("k", "ekf", "start3", kStatusOk, 0.4),
      Row("k", "ekf", "start4", kStatusOk, 1.0),  // Even count (4 ok): median (0.4+0.6)/2.
      Row("a", "ba", "", kStatusOk, 0.5),
      Row("m", "ba", "seed1", kStatusFailed, std::nullopt),
      Row("m", "ba", "seed2", kStatusCrashed, std::nullopt),
  };
  const std::vector<SpreadSummary> s = SummarizeAte(rows);
  ASSERT_EQ(s.size(), 4u);  // Sorted by (sequence, configuration).
  EXPECT_EQ(s[0].sequence, "a");
  EXPECT_EQ(s[1].sequence + "/" + s[1].config, "k/ba");
  EXPECT_EQ(s[2].sequence + "/" + s[2].config, "k/ekf");
  EXPECT_EQ(s[3].sequence, "m");

  EXPECT_EQ(s[0].runs, 1);
  EXPECT_DOUBLE_EQ(*s[0].median, 0.5);
  EXPECT_EQ(s[0].worst_variant, "");

  EXPECT_EQ(s[1].runs, 3);
  EXPECT_EQ(s[1].ok, 3);
  EXPECT_TRUE(s[1].not_ok.empty());
  EXPECT_DOUBLE_EQ(*s[1].median, 0.3);
  EXPECT_DOUBLE_EQ(*s[1].best, 0.1);
  EXPECT_EQ(s[1].best_variant, "start1");
  EXPECT_DOUBLE_EQ(*s[1].worst, 0.7);
  EXPECT_EQ(s[1].worst_variant, "start2");

  EXPECT_EQ(s[2].runs, 5);
  EXPECT_EQ(s[2].ok, 4);
  EXPECT_EQ(s[2].values, 4);
  EXPECT_THAT(s[2].not_ok, ElementsAre("start1: timeout"));  // Counted, not dropped.
  EXPECT_DOUBLE_EQ(*s[2].median, 0.5);
  EXPECT_DOUBLE_EQ(*s[2].worst, 1.0);
  EXPECT_EQ(s[2].worst_variant, "start4");
  EXPECT_EQ(s[2].best_variant, "start0");

  EXPECT_EQ(s[3].ok, 0);
  EXPECT_THAT(s[3].not_ok, ElementsAre("seed1: failed", "seed2: crashed"));
  EXPECT_FALSE(s[3].median.has_value());
  EXPECT_FALSE(s[3].worst.has_value());

  const nlohmann::json j = AteSummaryJson(s[2]);
  EXPECT_EQ(j["not_ok"], 1);
  EXPECT_EQ(j["ate_worst_variant"], "start4");
  EXPECT_TRUE(AteSummaryJson(s[3])["ate_median"].is_null());
}

TEST(BenchSpread, TiesGoToTheFirstRunAndOkRunsWithoutAValueAreNotInTheSample) {
  const std::vector<BenchRunResult> rows = {
      Row("k", "ba", "seed1", kStatusOk, 0.2), Row("k", "ba", "seed2", kStatusOk, std::nullopt),
      Row("k", "ba", "seed3", kStatusOk, 0.2), Row("k", "ba", "seed4", kStatusOk, 0.2)};
  const SpreadSummary s = SummarizeAte(rows).at(0);
  EXPECT_EQ(s.ok, 4);
  EXPECT_EQ(s.values, 3);
  EXPECT_EQ(s.best_variant, "seed1");
  EXPECT_EQ(s.worst_variant, "seed1");
  EXPECT_DOUBLE_EQ(*s.median, 0.2);
}

}  // namespace
}  // namespace dala::bench
