// `dala bench` end to end with a fake `dala` (fake_dala.h) standing in for `dala synth` and
// `dala run`: metrics against the known injected error, failures, resume, --force, shards and
// merge, the report's plots, and the error messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>

#include "tests/test_util.h"
#include "tests/tools/bench/fake_dala.h"

namespace dala {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameBenchResults;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::ReadAll;

struct CliResult {
  int status = -1;
  std::string err;
};

int CountLines(const std::string& path) {
  std::ifstream is(path);
  int n = 0;
  for (std::string line; std::getline(is, line);) ++n;
  return n;
}

class BenchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    fake_ = dir_ / "fake_dala.sh";
    std::ofstream(fake_) << testing::kFakeDalaScript;
    fs::permissions(fake_, fs::perms::owner_all);
    suite_ = dir_ / "suite.yaml";
    std::ofstream(suite_) << "sequences:\n"
                             "  - {name: square_a, preset: rover_loop, frames: 80, seed: 1}\n"
                             "  - {name: square_b, preset: flight, frames: 80, seed: 2}\n"
                             "configurations:\n"
                             "  - {name: ba-stereo, estimator: ba, mode: stereo}\n"
                             "  - {name: ekf-stereo, estimator: ekf, mode: stereo}\n"
                             "  - {name: ekf-mono, estimator: ekf, mode: mono}\n"
                             "  - {name: ba-mono, estimator: ba, mode: mono}\n"
                             "  - {name: fails, estimator: ekf, mode: stereo, "
                             "set: [\"fake.fail=1\"]}\n"
                             "  - {name: crashes, estimator: ba, mode: stereo, "
                             "set: [\"fake.crash=1\"]}\n";
  }

  CliResult Bench(const std::string& args) {
    const std::string err = dir_ / "stderr.txt";
    const std::string cmd = std::string(DALA_BINARY) + " bench " + args + " 2>" + err;
    const int status = std::system(cmd.c_str());
    CliResult r;
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = ReadAll(err);
    return r;
  }
  CliResult BenchSuite(const std::string& out, const std::string& extra = "") {
    return Bench(suite_ + " --out " + out + " --dala " + fake_ + " " + extra);
  }

  static nlohmann::json Results(const std::string& out) {
    return nlohmann::json::parse(ReadAll(out + "/results.json"));
  }
  static std::map<std::string, nlohmann::json> ByKey(const nlohmann::json& results) {
    std::map<std::string, nlohmann::json> runs;
    for (const auto& r : results.at("runs")) {
      const std::string variant = r.value("variant", "");
      runs[r.at("sequence").get<std::string>() + (variant.empty() ? "" : "@" + variant) + "/" +
           r.at("config").get<std::string>()] = r;
    }
    return runs;
  }

  testing::TempDir dir_;
  std::string fake_, suite_;
};

TEST_F(BenchCli, RecordsMetricsOfEveryRunAndItsFailures) {
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out, "--jobs 3");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("[12/12]"));
  EXPECT_THAT(r.err, HasSubstr("square_a/crashes  crashed"));

  const nlohmann::json results = Results(out);
  EXPECT_EQ(results.at("runs_total").get<int>(), 12);
  ASSERT_EQ(results.at("runs").size(), 12u);
  // Sorted run order whatever the completion order.
  for (size_t k = 0; k < 12; ++k) EXPECT_EQ(results["runs"][k]["index"].get<size_t>(), k);
  const auto runs = ByKey(results);
  for (const char* seq : {"square_a", "square_b"}) {
    const std::string s = seq;
    for (const char* cfg : {"ba-stereo", "ekf-stereo"}) {
      const nlohmann::json& run = runs.at(s + "/" + cfg);
      EXPECT_EQ(run["status"], "ok") << run.dump(1);
      EXPECT_EQ(run["alignment"], "se3");
      // The injected +-0.1 m offset, invisible to the SE(3) alignment.
      EXPECT_NEAR(run["ate_rmse"].get<double>(), 0.1, 1e-6);
      EXPECT_NEAR(run["ate_max"].get<double>(), 0.1, 1e-6);
      EXPECT_NEAR(run["scale"].get<double>(), 1.0, 1e-12);
      // 1 frame: |s_i+1 - s_i| d = 0.2 m on 40 of the 79 pairs, 0 on the others.
      EXPECT_NEAR(run["rpe_trans"].get<double>(), 0.2 * std::sqrt(40.0 / 79.0), 1e-6);
      // 10 frames: s alternates between +1 and -1 every 10 frames: 0.2 m on every pair.
      EXPECT_NEAR(run["rpe10_trans"].get<double>(), 0.2, 1e-6);
      EXPECT_NEAR(run["path_length_m"].get<double>(), 158.0, 1e-6);
      EXPECT_TRUE(run["t_err_percent"].is_number());  // 158 m: 100 m segments exist.
      // Times 10 + (i % 10) ms: median 14.5, p95 and max 19 (numpy percentile).
      EXPECT_DOUBLE_EQ(run["ms_median"].get<double>(), 14.5);
      EXPECT_DOUBLE_EQ(run["ms_p95"].get<double>(), 19.0);
      EXPECT_DOUBLE_EQ(run["ms_max"].get<double>(), 19.0);
      EXPECT_EQ(run["landmarks"], 4321);
      EXPECT_EQ(run["keyframes"], 16);
      EXPECT_EQ(run["keyframes_in_map"], 12);
      EXPECT_EQ(run["disparity_offset_px"], 0.25);
      EXPECT_EQ(run["tracking_failures"], 1);
      EXPECT_EQ(run["frames"], 80);
      EXPECT_EQ(run["pairs"], 80);
      EXPECT_GT(run["peak_rss_mb"].get<double>(), 0.5);
      EXPECT_GT(run["wall_s"].get<double>(), 0.0);
      EXPECT_EQ(run["error"], "");
      EXPECT_TRUE(fs::exists(out + "/" + run["plot_trajectory"].get<std::string>()));
      EXPECT_TRUE(fs::exists(out + "/" + run["plot_timing"].get<std::string>()));
      EXPECT_TRUE(fs::exists(out + "/runs/" + s + "/" + cfg + "/log.txt"));
    }
    const nlohmann::json& mono = runs.at(s + "/ekf-mono");
    EXPECT_EQ(mono["status"], "ok");
    EXPECT_EQ(mono["alignment"], "sim3");
    EXPECT_LT(mono["ate_rmse"].get<double>(), 1e-6);  // Doubled positions: Sim(3) removes it.
    EXPECT_NEAR(mono["scale"].get<double>(), 0.5, 1e-9);
    EXPECT_LT(mono["t_err_percent"].get<double>(), 1e-6);  // On the scaled estimate.
    EXPECT_EQ(mono["estimator"], "ekf");
    EXPECT_EQ(mono["mode"], "mono");

    const nlohmann::json& fails = runs.at(s + "/fails");
    EXPECT_EQ(fails["status"], "failed");
    EXPECT_EQ(fails["exit_code"], 1);
    EXPECT_THAT(fails["error"].get<std::string>(), HasSubstr("the fake estimator diverged"));
    EXPECT_TRUE(fails["ate_rmse"].is_null());
    const nlohmann::json& crash = runs.at(s + "/crashes");
    EXPECT_EQ(crash["status"], "crashed");
    EXPECT_EQ(crash["signal"], 11);
    EXPECT_THAT(crash["error"].get<std::string>(), HasSubstr("signal 11"));
    const nlohmann::json& unsupported = runs.at(s + "/ba-mono");
    EXPECT_EQ(unsupported["status"], "unsupported");
    EXPECT_THAT(unsupported["error"].get<std::string>(), HasSubstr("is not supported"));
  }
  // Each preset rendered once.
  EXPECT_EQ(CountLines(out + "/synth_calls.txt"), 2);
  EXPECT_TRUE(fs::exists(out + "/sequences/square_a/poses.txt"));

  // CSV: header + one line per run (the errors span lines inside quotes, so count records by
  // the sequence name at a line start).
  const std::string csv = ReadAll(out + "/results.csv");
  EXPECT_EQ(csv.rfind("sequence,config,variant,start,seed,estimator,mode,status,ate_rmse,", 0), 0u);
  EXPECT_THAT(csv, HasSubstr("square_a,ba-stereo,,,1,ba,stereo,ok,0.1000,"));
  const std::string md = ReadAll(out + "/results.md");
  EXPECT_THAT(md, HasSubstr("| sequence | ba-mono | ba-stereo | crashes | ekf-mono | ekf-stereo "
                            "| fails |"));
  EXPECT_THAT(md, HasSubstr("| square_a | unsupported | 0.1000 | crashed | **0.0000** | 0.1000 "
                            "| failed |"));

  // The HTML references only existing PNGs, among them every run's plots.
  const std::string html = ReadAll(out + "/report.html");
  const std::regex src("src=\"([^\"]+)\"");
  std::set<std::string> pngs;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), src); it != std::sregex_iterator();
       ++it) {
    const std::string rel = (*it)[1];
    EXPECT_TRUE(fs::is_regular_file(out + "/" + rel)) << rel;
    EXPECT_EQ(rel.substr(rel.size() - 4), ".png");
    pngs.insert(rel);
  }
  EXPECT_EQ(pngs.size(), 6u * 2u + 2u * 2u);  // 6 ok runs x 2 plots + 2 sequences x 2.
  EXPECT_TRUE(pngs.count("runs/square_b/ekf-mono/eval.png"));
  EXPECT_TRUE(pngs.count("plots/square_a_ate.png"));
  EXPECT_THAT(html, HasSubstr("the fake estimator diverged"));
  // Each run that wrote its report.html is linked from its row and its card.
  EXPECT_THAT(html, HasSubstr("<td><a href=\"runs/square_a/ba-stereo/report.html\">3D</a></td>"));
  EXPECT_THAT(html, HasSubstr("<a href=\"runs/square_b/ekf-mono/report.html\">report.html</a>"));
  EXPECT_THAT(html, Not(HasSubstr("runs/square_a/fails/report.html")));
}

TEST_F(BenchCli, ResumesFinishedRunsAndForceRerunsThem) {
  const std::string out = dir_ / "out";
  ASSERT_EQ(BenchSuite(out, "--jobs 2").status, 0);
  EXPECT_EQ(CountLines(out + "/run_calls.txt"), 12);
  const std::string marker = out + "/runs/square_a/ba-stereo/bench_done.json";
  ASSERT_TRUE(fs::exists(marker));
  const auto stamp = fs::last_write_time(marker);
  const nlohmann::json first = Results(out);

  // Again: the 6 ok runs are reused; the 6 that did not finish (fails, crashes, ba-mono) rerun.
  const CliResult again = BenchSuite(out, "--jobs 2");
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(CountLines(out + "/run_calls.txt"), 12 + 6);
  EXPECT_EQ(fs::last_write_time(marker), stamp);
  EXPECT_THAT(again.err, HasSubstr("square_a/ba-stereo  ok"));
  EXPECT_THAT(again.err, HasSubstr("[done before, skipped]"));
  EXPECT_THAT(again.err, HasSubstr("(6 reused)"));
  EXPECT_EQ(CountLines(out + "/synth_calls.txt"), 2);  // Sequences not rendered again.
  const auto a = ByKey(first), b = ByKey(Results(out));
  for (const auto& [key, run] : a) {
    if (run["status"] == "ok") {
      EXPECT_EQ(run, b.at(key)) << key;  // Reused verbatim.
    }
  }

  // A changed configuration is not reused.
  std::ofstream(suite_, std::ios::app) << "  - {name: extra, estimator: ekf, mode: stereo}\n";
  ASSERT_EQ(BenchSuite(out).status, 0);
  EXPECT_EQ(CountLines(out + "/run_calls.txt"), 18 + 2 + 6);  // extra x 2 + the not-ok again.

  // Nor is one whose draws changed (`dala run --draws`).
  std::string suite = testing::ReadAll(suite_);
  const std::string before = "{name: ba-stereo, estimator: ba, mode: stereo}";
  ASSERT_NE(suite.find(before), std::string::npos);
  suite.replace(suite.find(before), before.size(),
                "{name: ba-stereo, estimator: ba, mode: stereo, draws: 2}");
  std::ofstream(suite_) << suite;
  ASSERT_EQ(BenchSuite(out).status, 0);
  EXPECT_EQ(CountLines(out + "/run_calls.txt"), 26 + 2 + 6);  // ba-stereo x 2 + the not-ok.

  ASSERT_EQ(BenchSuite(out, "--force").status, 0);
  EXPECT_EQ(CountLines(out + "/run_calls.txt"), 34 + 14);
  EXPECT_NE(fs::last_write_time(marker), stamp);
}

TEST_F(BenchCli, ShardsPartitionTheRunsAndMergeReproducesTheWhole) {
  const std::string whole = dir_ / "whole";
  ASSERT_EQ(BenchSuite(whole, "--jobs 2").status, 0);
  std::set<std::string> seen;
  std::string dirs;
  for (int i = 0; i < 3; ++i) {
    const std::string out = dir_ / ("part" + std::to_string(i));
    const CliResult r = BenchSuite(out, "--shard " + std::to_string(i) + "/3");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json part = Results(out);
    EXPECT_EQ(part["shard"], std::to_string(i) + "/3");
    EXPECT_EQ(part["runs"].size(), 4u);
    for (const auto& [key, run] : ByKey(part)) {
      EXPECT_EQ(run["index"].get<int>() % 3, i);
      EXPECT_TRUE(seen.insert(key).second) << key << " in two shards";
    }
    dirs += " " + out;
  }
  EXPECT_EQ(seen.size(), 12u);

  const std::string merged = dir_ / "merged";
  const CliResult m = Bench("merge" + dirs + " --out " + merged);
  ASSERT_EQ(m.status, 0) << m.err;
  const nlohmann::json a = Results(whole), b = Results(merged);
  ASSERT_EQ(a["runs"].size(), b["runs"].size());
  for (size_t k = 0; k < a["runs"].size(); ++k) {
    nlohmann::json x = a["runs"][k], y = b["runs"][k];
    for (const char* volatile_key : {"wall_s", "peak_rss_mb", "command", "error"}) {
      x.erase(volatile_key);  // Time, memory and paths differ between two executions.
      y.erase(volatile_key);
    }
    EXPECT_EQ(x, y) << k;
  }
  // The merged report's plots were copied along.
  const std::string html = ReadAll(merged + "/report.html");
  EXPECT_THAT(html, HasSubstr("src=\"runs/square_b/ba-stereo/eval.png\""));
  EXPECT_TRUE(fs::exists(merged + "/runs/square_b/ba-stereo/eval.png"));
  EXPECT_TRUE(fs::exists(merged + "/plots/square_b_ate.png"));
  EXPECT_EQ(ReadAll(whole + "/results.md").substr(0, 200).find("shard"), std::string::npos);

  // A run in two folders is refused.
  const CliResult twice = Bench("merge " + whole + dirs + " --out " + (dir_ / "bad"));
  EXPECT_EQ(twice.status, 2);
  EXPECT_THAT(twice.err, HasSubstr("is in both"));
}

TEST_F(BenchCli, KillsARunAfterTheTimeout) {
  std::ofstream(suite_) << "sequences:\n  - {name: s, preset: fast, frames: 8}\n"
                           "configurations:\n"
                           "  - {name: slow, estimator: ba, mode: stereo, "
                           "set: [\"fake.sleep=20\"]}\n"
                           "  - {name: quick, estimator: ba, mode: stereo}\n";
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out, "--run_timeout 0.3 --jobs 2");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto runs = ByKey(Results(out));
  EXPECT_EQ(runs.at("s/slow")["status"], "timeout");
  EXPECT_LT(runs.at("s/slow")["wall_s"].get<double>(), 5.0);
  EXPECT_EQ(runs.at("s/quick")["status"], "ok");
}

TEST_F(BenchCli, ASequenceThatCannotBeRenderedFailsItsRunsOnly) {
  std::ofstream(suite_) << "sequences:\n  - {name: good, preset: fast, frames: 8}\n"
                           "  - {name: bad, preset: broken, frames: 8}\n"
                           "configurations:\n  - {name: ba-stereo, estimator: ba, mode: stereo}\n";
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("sequence bad: FAILED"));
  const auto runs = ByKey(Results(out));
  EXPECT_EQ(runs.at("good/ba-stereo")["status"], "ok");
  EXPECT_EQ(runs.at("bad/ba-stereo")["status"], "failed");
  EXPECT_THAT(runs.at("bad/ba-stereo")["error"].get<std::string>(),
              HasSubstr("unknown preset 'broken'"));
  EXPECT_FALSE(fs::exists(out + "/sequences/bad"));  // Nothing half-rendered left as done.
}

TEST_F(BenchCli, AddsDatasetFoldersFromTheCommandLine) {
  // A KITTI-like folder with ground truth, as `dala synth` writes (made by the fake).
  const std::string data = dir_ / "mydata";
  fs::create_directories(dir_ / "gen/sequences");
  const std::string synth =
      fake_ + " synth --out " + (dir_ / "gen/sequences/x") + " --frames 40 >/dev/null";
  ASSERT_EQ(std::system(synth.c_str()), 0);
  fs::rename(dir_ / "gen/sequences/x", data);
  std::ofstream(suite_) << "sequences:\n  - {name: s, preset: fast, frames: 40}\n"
                           "configurations:\n  - {name: ba-stereo, estimator: ba, mode: stereo}\n";
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out, "--dataset " + data + " --dataset " + data + "/");
  EXPECT_EQ(r.status, 2);  // The same folder twice: the name is taken.
  EXPECT_THAT(r.err, HasSubstr("a sequence named 'mydata' is already in the suite"));
  const CliResult ok = BenchSuite(out, "--dataset " + data);
  ASSERT_EQ(ok.status, 0) << ok.err;
  const auto runs = ByKey(Results(out));
  ASSERT_TRUE(runs.count("mydata/ba-stereo"));
  EXPECT_NEAR(runs.at("mydata/ba-stereo")["ate_rmse"].get<double>(), 0.1, 1e-6);
  EXPECT_THAT(runs.at("mydata/ba-stereo")["command"].get<std::string>(),
              HasSubstr(" run " + data + " --out "));
}

// A KITTI-like folder with ground truth of `frames` frames, as `dala synth` writes (made by the
// fake), at dir/name.
std::string MakeDataset(const testing::TempDir& dir, const std::string& fake,
                        const std::string& name, int frames) {
  fs::create_directories(dir / "gen/sequences");
  const std::string synth = fake + " synth --out " + (dir / "gen/sequences/x") + " --frames " +
                            std::to_string(frames) + " >/dev/null";
  EXPECT_EQ(std::system(synth.c_str()), 0);
  fs::rename(dir / "gen/sequences/x", dir / name);
  return dir / name;
}

// Rendered seeds and dataset start frames: one run each, the spread over them in the tables.
class BenchVariantsCli : public BenchCli {
 protected:
  void SetUp() override {
    BenchCli::SetUp();
    data_ = MakeDataset(dir_, fake_, "clip", 80);
    // Starts that are multiples of 4 keep the fake's ATE exact: 0.1 + 0.01 F m. Seeds: the fake
    // adds 0.05 m per seed above 1 under fake.seed_error=1. fake.fail_start=8 fails start 8.
    std::ofstream(suite_) << "sequences:\n"
                             "  - {name: clip, path: clip, starts: [8, 0, 4]}\n"
                             "  - {name: gone, path: no/such/folder, starts: 3, optional: true}\n"
                             "  - {name: scene, preset: flight, frames: 80, seeds: [1, 2, 3]}\n"
                             "configurations:\n"
                             "  - {name: ba-stereo, estimator: ba, mode: stereo, "
                             "set: [\"fake.seed_error=1\", \"fake.fail_start=8\"]}\n"
                             "  - {name: ekf-mono, estimator: ekf, mode: mono}\n";
  }
  std::string data_;
};

TEST_F(BenchVariantsCli, RunsEverySeedAndStartAndSummarisesTheirSpread) {
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out, "--jobs 2");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("sequences[1] (gone): optional dataset folder "));
  EXPECT_THAT(r.err, HasSubstr("is absent; skipped"));
  EXPECT_THAT(r.err, HasSubstr("[12/12]"));

  const nlohmann::json results = Results(out);
  EXPECT_EQ(results["runs_total"], 12);
  const auto runs = ByKey(results);
  ASSERT_EQ(runs.size(), 12u);
  // Run order: sequence, variant (numeric), configuration.
  std::vector<std::string> order;
  for (const auto& run : results["runs"]) {
    order.push_back(run["sequence"].get<std::string>() + "@" + run["variant"].get<std::string>());
  }
  EXPECT_EQ(order[0], "clip@start0");
  EXPECT_EQ(order[2], "clip@start4");
  EXPECT_EQ(order[4], "clip@start8");
  EXPECT_EQ(order[6], "scene@seed1");
  EXPECT_EQ(order[11], "scene@seed3");

  // Dataset starts: --first_frame F, the folder runs/clip@startF, the fake's ATE 0.1 + 0.01 F.
  const nlohmann::json& start4 = runs.at("clip@start4/ba-stereo");
  EXPECT_EQ(start4["status"], "ok");
  EXPECT_EQ(start4["start"], 4);
  EXPECT_TRUE(start4["seed"].is_null());
  EXPECT_EQ(start4["run_dir"], "runs/clip@start4/ba-stereo");
  EXPECT_THAT(start4["command"].get<std::string>(), HasSubstr(" --first_frame 4"));
  EXPECT_NEAR(start4["ate_rmse"].get<double>(), 0.14, 1e-6);
  EXPECT_EQ(start4["frames"], 76);
  EXPECT_THAT(runs.at("clip@start0/ba-stereo")["command"].get<std::string>(),
              HasSubstr(" --first_frame 0"));
  EXPECT_EQ(runs.at("clip@start8/ba-stereo")["status"], "failed");
  // Seeds: each rendered once into sequences/scene@seedS, and run there.
  const nlohmann::json& seed3 = runs.at("scene@seed3/ba-stereo");
  EXPECT_EQ(seed3["seed"], 3);
  EXPECT_NEAR(seed3["ate_rmse"].get<double>(), 0.2, 1e-6);
  EXPECT_THAT(seed3["command"].get<std::string>(), HasSubstr("/sequences/scene@seed3 --out "));
  EXPECT_THAT(seed3["command"].get<std::string>(), ::testing::Not(HasSubstr("--first_frame")));
  EXPECT_EQ(CountLines(out + "/synth_calls.txt"), 3);
  for (const char* seed : {"1", "2", "3"}) {
    EXPECT_THAT(ReadAll(out + "/sequences/scene@seed" + std::string(seed) + "/synth.yaml"),
                HasSubstr(std::string("seed: ") + seed));
  }

  // The summary: runs, failures, median, best and worst with the run that gave them.
  std::map<std::string, nlohmann::json> summary;
  for (const auto& s : results["summary"]) {
    summary[s["sequence"].get<std::string>() + "/" + s["config"].get<std::string>()] = s;
  }
  ASSERT_EQ(summary.size(), 4u);
  const nlohmann::json& clip = summary.at("clip/ba-stereo");
  EXPECT_EQ(clip["runs"], 3);
  EXPECT_EQ(clip["ok"], 2);
  EXPECT_EQ(clip["not_ok"], 1);
  EXPECT_EQ(clip["not_ok_runs"], nlohmann::json::array({"start8: failed"}));
  EXPECT_NEAR(clip["ate_median"].get<double>(), 0.12, 1e-6);  // Of 0.10 and 0.14.
  EXPECT_NEAR(clip["ate_worst"].get<double>(), 0.14, 1e-6);
  EXPECT_EQ(clip["ate_worst_variant"], "start4");
  EXPECT_EQ(clip["ate_best_variant"], "start0");
  const nlohmann::json& scene = summary.at("scene/ba-stereo");
  EXPECT_EQ(scene["runs"], 3);
  EXPECT_EQ(scene["not_ok"], 0);
  EXPECT_NEAR(scene["ate_median"].get<double>(), 0.15, 1e-6);
  EXPECT_EQ(scene["ate_worst_variant"], "seed3");
  EXPECT_EQ(scene["ate_best_variant"], "seed1");

  const std::string md = ReadAll(out + "/results.md");
  EXPECT_THAT(md, HasSubstr("| sequence | config | runs | failed | ATE median [m] | best [m] | "
                            "best run | worst [m] | worst run | failed runs |"));
  EXPECT_THAT(md, HasSubstr("| clip | ba-stereo | 3 | 1 | 0.1200 | 0.1000 | start0 | 0.1400 | "
                            "start4 | start8: failed |"));
  EXPECT_THAT(md, HasSubstr("| scene | ba-stereo | 3 | 0 | 0.1500 | 0.1000 | seed1 | 0.2000 | "
                            "seed3 |  |"));
  // Every run's ATE, and the medians side by side with the failures counted.
  EXPECT_THAT(md, HasSubstr("| clip | start8 | failed | "));
  EXPECT_THAT(md, HasSubstr("| clip | 0.1200 (1/3 failed) | "));
  EXPECT_EQ(ReadAll(out + "/summary.csv").rfind("sequence,config,runs,not_ok,ate_median,", 0), 0u);
  EXPECT_THAT(ReadAll(out + "/summary.csv"),
              HasSubstr("clip,ba-stereo,3,1,0.1200,0.1000,start0,0.1400,start4,start8: failed\n"));

  // The report draws the spread of each sequence and links only existing files.
  const std::string html = ReadAll(out + "/report.html");
  EXPECT_THAT(html, HasSubstr("src=\"plots/clip_ate_spread.png\""));
  EXPECT_THAT(html, HasSubstr("src=\"plots/scene_ate_spread.png\""));
  EXPECT_THAT(html, HasSubstr("src=\"runs/clip@start4/ba-stereo/eval.png\""));
  EXPECT_THAT(html, HasSubstr("ba-stereo @ start8"));
  const std::regex src("src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), src); it != std::sregex_iterator();
       ++it) {
    EXPECT_TRUE(fs::is_regular_file(out + "/" + std::string((*it)[1]))) << (*it)[1];
  }
}

TEST_F(BenchVariantsCli, StartsFlagSetsTheStartsOfEveryDatasetSequence) {
  const std::string other = MakeDataset(dir_, fake_, "other", 40);
  const std::string out = dir_ / "out";
  const CliResult r = BenchSuite(out, "--dataset " + other + " --starts 0,4");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto runs = ByKey(Results(out));
  // clip: 2 starts (the suite's 3 overridden), other: 2 starts, scene: 3 seeds; x 2 configs.
  EXPECT_EQ(runs.size(), (2u + 2u + 3u) * 2u);
  EXPECT_TRUE(runs.count("clip@start4/ekf-mono"));
  EXPECT_FALSE(runs.count("clip@start8/ba-stereo"));
  EXPECT_NEAR(runs.at("other@start4/ba-stereo")["ate_rmse"].get<double>(), 0.14, 1e-6);
  EXPECT_EQ(runs.at("other@start4/ba-stereo")["frames"], 36);

  const CliResult count = BenchSuite(dir_ / "out3", "--starts 3");
  ASSERT_EQ(count.status, 0) << count.err;
  const auto three = ByKey(Results(dir_ / "out3"));
  for (const char* key :
       {"clip@start0/ba-stereo", "clip@start1/ba-stereo", "clip@start2/ba-stereo"}) {
    EXPECT_TRUE(three.count(key)) << key;
  }
  EXPECT_EQ(three.size(), (3u + 3u) * 2u);

  const CliResult bad = BenchSuite(dir_ / "bad", "--starts 0,-4");
  EXPECT_EQ(bad.status, 2);
  EXPECT_THAT(bad.err, HasSubstr("--starts=0,-4: expected a count N"));
}

TEST_F(BenchVariantsCli, ShardsOfVariantsMergeIntoTheOneMachineResults) {
  const std::string whole = dir_ / "whole";
  ASSERT_EQ(BenchSuite(whole, "--jobs 2").status, 0);
  std::string dirs;
  std::set<std::string> seen;
  for (int i = 0; i < 5; ++i) {
    const std::string out = dir_ / ("part" + std::to_string(i));
    const CliResult r = BenchSuite(out, "--shard " + std::to_string(i) + "/5");
    ASSERT_EQ(r.status, 0) << r.err;
    for (const auto& [key, run] : ByKey(Results(out))) {
      EXPECT_EQ(run["index"].get<int>() % 5, i);
      EXPECT_TRUE(seen.insert(key).second) << key << " in two shards";
    }
    dirs += " " + out;
  }
  EXPECT_EQ(seen.size(), 12u);
  const std::string merged = dir_ / "merged";
  const CliResult m = Bench("merge" + dirs + " --out " + merged);
  ASSERT_EQ(m.status, 0) << m.err;

  ExpectSameBenchResults(whole, merged);
  EXPECT_EQ(Results(merged)["summary"].size(), 4u);
  EXPECT_THAT(ReadAll(merged + "/results.md"), HasSubstr("| clip | start8 | failed |"));
  EXPECT_TRUE(fs::exists(merged + "/runs/scene@seed2/ba-stereo/eval.png"));
  EXPECT_TRUE(fs::exists(merged + "/plots/scene_ate_spread.png"));
}

TEST_F(BenchCli, ClearErrors) {
  const std::string out = dir_ / "out";
  std::ofstream(dir_ / "bad.yaml") << "sequences:\n  - {name: a, preset: fast}\n"
                                      "configurations:\n  - {name: c, estimator: orb, "
                                      "mode: stereo}\n";
  struct Case {
    std::string args;
    std::string expected;
  };
  std::ofstream(dir_ / "a_file") << "x";
  const std::vector<Case> cases = {
      {(dir_ / "bad.yaml") + " --out " + out + " --dala " + fake_,
       "bad.yaml: configurations[0].estimator: unknown estimator 'orb'; expected ba or ekf"},
      {suite_ + " --dala " + fake_, "--out DIR is required"},
      {suite_ + " --out " + (dir_ / "a_file/sub") + " --dala " + fake_,
       "cannot create the output folder"},
      {suite_ + " --out " + out + " --dala " + (dir_ / "nope"), "not an executable file"},
      {suite_ + " --out " + out + " --dala " + fake_ + " --dataset " + (dir_ / "nowhere"),
       "the dataset folder does not exist"},
      {suite_ + " --out " + out + " --dala " + fake_ + " --shard 3/3", "expected 0 <= i < n"},
      {suite_ + " --out " + out + " --dala " + fake_ + " --jobs 0", "--jobs must be >= 1"},
      {(dir_ / "missing.yaml") + " --out " + out, "the suite file does not exist"},
      {"merge " + (dir_ / "nothing") + " --out " + out, "results.json: missing"},
  };
  for (const Case& c : cases) {
    const CliResult r = Bench(c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.expected)) << c.args;
  }
}

}  // namespace
}  // namespace dala
