// The Slurm job array of docs/benchmarking.md, run for real on a single-node Slurm started on
// localhost (tests/tools/bench/slurm_local.sh: munged, slurmctld, slurmd): the documented
// bench.sbatch and merge.sbatch, taken from the docs, shard a suite with seeds and starts over
// the array tasks, a dependent job merges them, and the merged report equals a one-machine
// `dala bench` of the same suite. The fake `dala` (fake_dala.h) makes the runs instant. Skips
// where Slurm cannot run (not installed: scripts/install_deps.sh --test; not root; slurmd fails).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>

#include "tests/test_util.h"
#include "tests/tools/bench/fake_dala.h"

namespace dala {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameBenchResults;
using ::testing::HasSubstr;
using testing::ReadAll;

struct Shell {
  int status = -1;
  std::string out;  // stdout and stderr
};

// Runs `cmd` with /bin/sh; its stdout and stderr together.
Shell Sh(const std::string& cmd) {
  Shell r;
  FILE* pipe = popen(("(" + cmd + ") 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof(buf), pipe)) > 0;) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The `index`-th ```bash block after `anchor` in the markdown `md`.
std::string BashBlockAfter(const std::string& md, const std::string& anchor, int index) {
  size_t at = md.find(anchor);
  if (at == std::string::npos) return "";
  for (int i = 0; i <= index; ++i) {
    at = md.find("```bash\n", at);
    if (at == std::string::npos) return "";
    at += 8;
    if (i == index) return md.substr(at, md.find("```", at) - at);
  }
  return "";
}

// Replaces the one occurrence of `from` in `text` (0 or several: the docs changed, the test
// says so instead of testing something else).
::testing::AssertionResult ReplaceOnce(std::string* text, const std::string& from,
                                       const std::string& to) {
  const size_t at = text->find(from);
  if (at == std::string::npos || text->find(from, at + 1) != std::string::npos) {
    return ::testing::AssertionFailure() << "'" << from << "' is not in the script exactly once:\n"
                                         << *text;
  }
  text->replace(at, from.size(), to);
  return ::testing::AssertionSuccess();
}

class BenchSlurm : public ::testing::Test {
 protected:
  void SetUp() override {
    // The munge socket path must stay short (sun_path): the cluster gets its own /tmp folder.
    char tmpl[] = "/tmp/dala_slurm_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    cluster_ = tmpl;
    conf_ = cluster_ + "/slurm.conf";
  }
  void TearDown() override {
    if (started_) {
      const Shell s = Sh("bash " + Quote(script_) + " stop " + Quote(cluster_));
      EXPECT_EQ(s.status, 0) << s.out;
      // Nothing of the cluster is left running.
      const Shell left =
          Sh("grep -lzxF " + Quote("SLURM_CONF=" + conf_) + " /proc/[0-9]*/environ 2>/dev/null");
      EXPECT_EQ(left.out, "") << "still running after stop";
    }
    fs::remove_all(cluster_);
  }

  // A Slurm command (or a shell line) against the test cluster, in `cwd`, with `env` before it.
  Shell Slurm(const std::string& cmd, const std::string& cwd = "/",
              const std::string& env = "") const {
    return Sh("cd " + Quote(cwd) + " && SLURM_CONF=" + Quote(conf_) + " " + env + " " + cmd);
  }

  // The job id that `sbatch --parsable` printed ("ID" or "ID;cluster").
  static std::string JobId(const Shell& sbatch) {
    return sbatch.out.substr(0, sbatch.out.find_first_of(";\n"));
  }

  // Waits (at most `timeout_s`) until every job of `jid` (an array: every task) is COMPLETED;
  // false with the reason in `why` when one failed, never ran or the time was up.
  bool WaitCompleted(const std::string& jid, int timeout_s, std::string* why) const {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
    for (;;) {
      // No accounting storage: the state from scontrol, kept for MinJobAge (300 s).
      const std::string state = Slurm("scontrol -o show job " + jid).out;
      const std::regex job_state("JobState=([A-Z_]+)");
      int jobs = 0, completed = 0;
      for (auto it = std::sregex_iterator(state.begin(), state.end(), job_state);
           it != std::sregex_iterator(); ++it) {
        ++jobs;
        const std::string st = (*it)[1];
        completed += st == "COMPLETED";
        if (st == "FAILED" || st == "CANCELLED" || st == "TIMEOUT" || st == "NODE_FAIL" ||
            st == "OUT_OF_MEMORY") {
          *why = "job " + jid + " " + st + ":\n" + state;
          return false;
        }
      }
      if (jobs > 0 && completed == jobs) return true;
      if (state.find("DependencyNeverSatisfied") != std::string::npos) {
        *why = "job " + jid + ": a job it depends on failed:\n" + state;
        return false;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        *why = "job " + jid + " not done after " + std::to_string(timeout_s) + " s:\n" + state;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }

  const std::string script_ = std::string(DALA_SOURCE_DIR) + "/tests/tools/bench/slurm_local.sh";
  std::string cluster_, conf_;
  bool started_ = false;
  testing::TempDir dir_;
};

TEST_F(BenchSlurm, ShardedJobArrayMergesIntoTheOneMachineReport) {
  // The scripts as docs/benchmarking.md shows them.
  const std::string md = ReadAll(std::string(DALA_SOURCE_DIR) + "/docs/benchmarking.md");
  std::string bench_sbatch = BashBlockAfter(md, "**Slurm job array**", 0);
  const std::string merge_sbatch = BashBlockAfter(md, "**Slurm job array**", 1);
  ASSERT_THAT(bench_sbatch, HasSubstr("#SBATCH --array=0-7"));
  ASSERT_THAT(bench_sbatch, HasSubstr("dala bench benchmarks/default.yaml --out"));
  ASSERT_THAT(merge_sbatch, HasSubstr("dala bench merge "));

  // Start the cluster: exit 3 says Slurm cannot run here (the reason on stderr).
  const Shell start = Sh("DALA_SLURM_MAX_S=240 bash " + Quote(script_) + " start " +
                         Quote(cluster_) + " " + std::to_string(getpid()));
  started_ = true;  // Whatever happened, TearDown makes sure nothing is left.
  if (start.status == 3) {
    std::string reason = start.out;
    const size_t at = reason.find("cannot run Slurm here: ");
    if (at != std::string::npos) reason = reason.substr(at + 23);
    GTEST_SKIP() << "a local Slurm cannot run here: " << reason;
  }
  ASSERT_EQ(start.status, 0) << start.out;
  ASSERT_THAT(start.out, HasSubstr("SLURM_CONF=" + conf_));

  // The submission folder, as on a cluster: `dala` on PATH, benchmarks/default.yaml there (a
  // suite with seeds and starts, two configurations, one failing variant), $SCRATCH shared.
  const std::string work = dir_ / "work", bin = dir_ / "bin", scratch = dir_ / "scratch";
  const std::string fake = dir_ / "fake_dala.sh";
  for (const std::string& d : {work + "/benchmarks", bin, scratch}) fs::create_directories(d);
  std::ofstream(fake) << testing::kFakeDalaScript;
  fs::permissions(fake, fs::perms::owner_all);
  fs::create_symlink(DALA_BINARY, bin + "/dala");
  fs::create_directories(dir_ / "gen/sequences");
  ASSERT_EQ(
      Sh(Quote(fake) + " synth --out " + Quote(dir_ / "gen/sequences/x") + " --frames 80").status,
      0);
  fs::rename(dir_ / "gen/sequences/x", work + "/benchmarks/clip");
  std::ofstream(work + "/benchmarks/default.yaml")
      << "name: slurm-test\n"
         "sequences:\n"
         "  - {name: clip, path: clip, starts: [8, 0, 4]}\n"
         "  - {name: scene, preset: flight, frames: 80, seeds: [1, 2]}\n"
         "configurations:\n"
         "  - {name: ba-stereo, estimator: ba, mode: stereo, "
         "set: [\"fake.seed_error=1\", \"fake.fail_start=8\"]}\n"
         "  - {name: ekf-mono, estimator: ekf, mode: mono}\n";
  // (3 starts + 2 seeds) x 2 configurations = 10 runs over the 8 array tasks.

  // The one edit: the fake `dala` for the runs (the real one would take minutes).
  ASSERT_TRUE(ReplaceOnce(&bench_sbatch, "--jobs \"$SLURM_CPUS_PER_TASK\"",
                          "--jobs \"$SLURM_CPUS_PER_TASK\" --dala " + Quote(fake)));
  std::ofstream(work + "/bench.sbatch") << bench_sbatch;
  std::ofstream(work + "/merge.sbatch") << merge_sbatch;

  // Submitted as the docs' comment says; sbatch passes its environment on to the jobs.
  const std::string env = "PATH=" + Quote(bin) + ":\"$PATH\" SCRATCH=" + Quote(scratch);
  const Shell array = Slurm("sbatch --parsable bench.sbatch", work, env);
  ASSERT_EQ(array.status, 0) << array.out;
  const std::string jid = JobId(array);
  ASSERT_TRUE(std::regex_match(jid, std::regex("[0-9]+"))) << array.out;
  const Shell merge =
      Slurm("sbatch --parsable --dependency=afterok:" + jid + " merge.sbatch", work, env);
  ASSERT_EQ(merge.status, 0) << merge.out;

  // Meanwhile, the one-machine run of the same suite.
  const std::string whole = dir_ / "whole";
  const Shell one = Sh("cd " + Quote(work) + " && PATH=" + Quote(bin) +
                       ":\"$PATH\" dala bench benchmarks/default.yaml --out " + Quote(whole) +
                       " --jobs 2 --dala " + Quote(fake));
  ASSERT_EQ(one.status, 0) << one.out;

  const std::string merged = scratch + "/bench/all";
  const auto logs = [&] {
    return Sh("tail -n 20 " + Quote(work) + "/slurm-*.out; " + "tail -n 20 " +
              Quote(cluster_ + "/log/slurmctld.log"))
        .out;
  };
  std::string why;
  ASSERT_TRUE(WaitCompleted(JobId(merge), 150, &why)) << why << logs();

  // Eight array tasks, one shard each, all exited 0 (`dala bench` records failed runs).
  const Shell tasks = Slurm("scontrol -o show job " + jid);
  std::set<std::string> shards;
  std::set<std::string> keys;
  for (int i = 0; i < 8; ++i) {
    const std::string part = scratch + "/bench/part" + std::to_string(i);
    ASSERT_TRUE(fs::exists(part + "/results.json")) << part << "\n" << logs();
    const nlohmann::json r = nlohmann::json::parse(ReadAll(part + "/results.json"));
    shards.insert(r["shard"].get<std::string>());
    for (const auto& run : r["runs"]) {
      EXPECT_EQ(run["index"].get<int>() % 8, i);
      EXPECT_TRUE(keys.insert(run["run_dir"].get<std::string>()).second) << run["run_dir"];
    }
  }
  EXPECT_EQ(shards.size(), 8u);
  EXPECT_TRUE(shards.count("7/8"));
  EXPECT_EQ(keys.size(), 10u);
  std::smatch m;
  int exited_ok = 0;
  for (auto it = tasks.out.cbegin();
       std::regex_search(it, tasks.out.cend(), m, std::regex(" ExitCode=(\\d+):(\\d+)"));
       it = m.suffix().first) {
    EXPECT_EQ(m[0], " ExitCode=0:0") << tasks.out;
    ++exited_ok;
  }
  EXPECT_EQ(exited_ok, 8) << tasks.out;

  // The merged report equals the one-machine one (ExpectSameBenchResults, as the merge test).
  ASSERT_TRUE(fs::exists(merged + "/results.json")) << logs();
  const nlohmann::json b = nlohmann::json::parse(ReadAll(merged + "/results.json"));
  EXPECT_EQ(b["runs_total"], 10);
  ASSERT_EQ(b["runs"].size(), 10u);
  EXPECT_EQ(b["merged_from"].size(), 8u);
  EXPECT_EQ(b["summary"].size(), 4u);
  ExpectSameBenchResults(whole, merged);
  EXPECT_THAT(ReadAll(merged + "/summary.csv"),
              HasSubstr("clip,ba-stereo,3,1,0.1200,0.1000,start0,0.1400,start4,start8: failed\n"));
  EXPECT_TRUE(fs::exists(merged + "/runs/scene@seed2/ba-stereo/eval.png"));
  EXPECT_TRUE(fs::exists(merged + "/report.html"));

  // A task resubmitted alone (as the docs say) resumes its shard: shard 3 of 8 again, nothing
  // rerun; a merge after it gives the same report.
  const std::string part3 = scratch + "/bench/part3";
  const std::string calls = ReadAll(part3 + "/run_calls.txt");
  ASSERT_NE(calls, "");
  const Shell again = Slurm("sbatch --parsable --array=3 bench.sbatch", work, env);
  ASSERT_EQ(again.status, 0) << again.out;
  const Shell remerge =
      Slurm("sbatch --parsable --dependency=afterok:" + JobId(again) + " merge.sbatch", work, env);
  ASSERT_EQ(remerge.status, 0) << remerge.out;
  ASSERT_TRUE(WaitCompleted(JobId(remerge), 60, &why)) << why << logs();
  EXPECT_EQ(nlohmann::json::parse(ReadAll(part3 + "/results.json"))["shard"], "3/8");
  EXPECT_EQ(ReadAll(part3 + "/run_calls.txt"), calls);
  EXPECT_EQ(ReadAll(whole + "/summary.csv"), ReadAll(merged + "/summary.csv"));
}

}  // namespace
}  // namespace dala
