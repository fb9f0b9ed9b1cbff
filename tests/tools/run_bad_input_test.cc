// `dala run` (the binary, DALA_BINARY) on a rendered folder with bad frames, and interrupted by a
// signal: the run goes on past a missing or truncated image (--strict stops), and a stopped run
// leaves complete outputs for the frames done.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/io/trajectory_io.h"
#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using testing::ReadAll;

// `dala run ARGS`: its exit code and stderr.
testing::DalaCliResult DalaRun(const std::string& args, const testing::TempDir& dir) {
  return testing::RunDala("run " + args + " --progress=false", dir / "dala");
}

// A rendered stereo folder: the rover loop's first `frames` frames.
std::string RenderedFolder(const testing::TempDir& dir, int frames, int width, int height) {
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = frames;
  sim.width = width;
  sim.height = height;
  sim.seed = 9;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  return dir / "seq";
}

std::string ImageName(int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.png", index);
  return name;
}

// Frame 12's left image cut to half its bytes, frame 25's right image missing: a full run with
// those two frames lost (no pose, a note naming the file) and every other frame posed.
class BadFrames : public ::testing::Test {
 protected:
  void SetUp() override {
    seq_ = RenderedFolder(dir_, 40, 480, 320);
    const std::string truncated = seq_ + "/image_0/" + ImageName(12);
    fs::resize_file(truncated, fs::file_size(truncated) / 2);
    fs::remove(seq_ + "/image_1/" + ImageName(25));
  }
  testing::TempDir dir_;
  std::string seq_;
};

TEST_F(BadFrames, AreSkippedAndReportedLost) {
  const auto r = DalaRun(seq_ + " --out " + (dir_ / "out"), dir_);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("frame 12 skipped"));
  EXPECT_THAT(r.err, HasSubstr("image_0/000012.png"));
  EXPECT_THAT(r.err, HasSubstr("frame 25 skipped"));
  EXPECT_THAT(r.err, HasSubstr("image_1/000025.png"));

  const nlohmann::json report = nlohmann::json::parse(ReadAll(dir_ / "out/report.json"));
  const nlohmann::json& frames = report.at("frames");
  ASSERT_EQ(frames.size(), 40u);
  for (const auto& [index, file] :
       {std::pair{12, "image_0/000012.png"}, std::pair{25, "image_1/000025.png"}}) {
    const nlohmann::json& f = frames.at(index);
    EXPECT_EQ(f.at("frame").get<int>(), index);
    EXPECT_EQ(f.at("status").get<std::string>(), "lost");
    EXPECT_FALSE(f.at("valid").get<bool>());
    EXPECT_TRUE(f.at("skipped").get<bool>());
    EXPECT_THAT(f.at("note").get<std::string>(), HasSubstr(file));
  }
  const nlohmann::json& summary = report.at("summary");
  EXPECT_EQ(summary.at("frames_skipped").get<int>(), 2);
  EXPECT_EQ(summary.at("tracking_failures").get<int>(), 2);  // The skipped frames only.
  EXPECT_FALSE(summary.at("interrupted").get<bool>());

  // No pose invented: both trajectory files hold the 38 other frames, at their own times.
  const Trajectory tum = ReadTrajectory(dir_ / "out/trajectory.txt");
  ASSERT_EQ(tum.size(), 38u);
  EXPECT_EQ(ReadTrajectory(dir_ / "out/trajectory_kitti.txt", TrajectoryFormat::kKitti).size(),
            38u);
  const auto t_ns = [&](int frame) {
    return NsFromSeconds(frames.at(frame).at("t").get<double>());
  };
  for (const StampedPose& p : tum.poses) {
    EXPECT_NE(p.t_ns, t_ns(12)) << "frame 12 has a pose";
    EXPECT_NE(p.t_ns, t_ns(25)) << "frame 25 has a pose";
  }
  EXPECT_EQ(tum.poses[11].t_ns, t_ns(11));
  EXPECT_EQ(tum.poses[12].t_ns, t_ns(13));
  EXPECT_EQ(tum.poses[37].t_ns, t_ns(39));
  // The frames after each gap are tracked, and the trajectory stays accurate.
  EXPECT_TRUE(frames.at(13).at("valid").get<bool>());
  EXPECT_TRUE(frames.at(26).at("valid").get<bool>());
  EXPECT_LT(summary.at("ate").at("rmse").get<double>(), 0.05);
}

TEST_F(BadFrames, StrictStopsNamingTheFile) {
  // The missing image is found when the folder is opened, the truncated one when it is read.
  auto r = DalaRun(seq_ + " --strict --out " + (dir_ / "out"), dir_);
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("missing right image '" + seq_ + "/image_1/000025.png'"));
  EXPECT_FALSE(fs::exists(dir_ / "out/trajectory.txt"));
  r = DalaRun(seq_ + " --strict --max_frames 20 --out " + (dir_ / "out"), dir_);
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("cannot decode image '" + seq_ + "/image_0/000012.png'"));
  EXPECT_FALSE(fs::exists(dir_ / "out/trajectory.txt"));
  // --max_frames is honoured before the check: the bad frames are not in the run.
  r = DalaRun(seq_ + " --strict --max_frames 10 --out " + (dir_ / "out"), dir_);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, Not(HasSubstr("missing")));
  EXPECT_EQ(ReadTrajectory(dir_ / "out/trajectory.txt").size(), 10u);
}

TEST_F(BadFrames, TheFirstFrameIsNotSkipped) {
  const auto r = DalaRun(seq_ + " --first_frame 25 --out " + (dir_ / "out"), dir_);
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("image_1/000025.png"));
  EXPECT_THAT(r.err, HasSubstr("--first_frame 26"));
}

// Starts `dala run` as a child with stderr on a pipe; the signal dispositions are the defaults
// whatever the test runner inherited.
class Child {
 public:
  explicit Child(const std::vector<std::string>& args) {
    int fds[2];
    if (pipe(fds) != 0) return;
    pid_ = fork();
    if (pid_ == 0) {
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
      dup2(fds[1], STDERR_FILENO);
      const int null = open("/dev/null", O_WRONLY);
      dup2(null, STDOUT_FILENO);
      close(fds[0]);
      std::vector<char*> argv;
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    close(fds[1]);
    err_ = fdopen(fds[0], "r");
  }
  ~Child() {
    if (pid_ > 0 && status_ < 0) {
      kill(pid_, SIGKILL);
      Wait();
    }
    if (err_ != nullptr) fclose(err_);
  }
  bool started() const { return pid_ > 0 && err_ != nullptr; }
  // Reads stderr until a line contains `text`; false at its end.
  bool WaitForLine(const std::string& text) {
    char line[4096];
    while (fgets(line, sizeof(line), err_) != nullptr) {
      log_ += line;
      if (std::string(line).find(text) != std::string::npos) return true;
    }
    return false;
  }
  void Signal(int signal) { kill(pid_, signal); }
  // The exit status (-1 when killed by a signal); reads the rest of stderr first.
  int Wait() {
    WaitForLine("\x01");
    int status = 0;
    waitpid(pid_, &status, 0);
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return status_;
  }
  const std::string& log() const { return log_; }

 private:
  pid_t pid_ = -1;
  FILE* err_ = nullptr;
  std::string log_;
  int status_ = -1;
};

// SIGINT and SIGTERM after frame 50 of 150: the run stops after the current frame, writes every
// output for the frames done (atomically: no temporary left), says so, and exits 128 + signal.
TEST(RunInterrupted, BySignalWritesTheFramesDone) {
  testing::TempDir dir;
  const std::string seq = RenderedFolder(dir, 150, 320, 240);
  for (const int signal : {SIGINT, SIGTERM}) {
    const std::string out = dir / ("out" + std::to_string(signal));
    Child child({DALA_BINARY, "run", seq, "--out", out, "--progress=true"});
    ASSERT_TRUE(child.started());
    // Without a terminal the progress is a line every 50 frames.
    ASSERT_TRUE(child.WaitForLine("frame 50/150")) << child.log();
    child.Signal(signal);
    EXPECT_EQ(child.Wait(), 128 + signal) << child.log();
    EXPECT_THAT(child.log(),
                HasSubstr(signal == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM"));
    const nlohmann::json report = nlohmann::json::parse(ReadAll(out + "/report.json"));
    const nlohmann::json& summary = report.at("summary");
    EXPECT_TRUE(summary.at("interrupted").get<bool>());
    const int frames = summary.at("frames").get<int>();
    EXPECT_GE(frames, 50);
    EXPECT_LT(frames, 150);
    EXPECT_EQ(report.at("frames").size(), static_cast<size_t>(frames));
    EXPECT_EQ(ReadTrajectory(out + "/trajectory.txt").size(), static_cast<size_t>(frames));
    EXPECT_EQ(ReadTrajectory(out + "/trajectory_kitti.txt", TrajectoryFormat::kKitti).size(),
              static_cast<size_t>(frames));
    for (const char* f : {"map.ply", "map.dmap", "trajectory.png"}) {
      EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
    }
    for (const auto& entry : fs::directory_iterator(out)) {
      EXPECT_THAT(entry.path().filename().string(), Not(HasSubstr(".tmp"))) << "left over";
    }
  }
}

// SIGINT during the global BA after the last frame (ba.final_ba=always; ~7 s here): it stops,
// every output is written as a run without the global BA writes it (trajectory.txt byte for byte
// that of ba.final_ba=off), the run says so and exits 130.
TEST(RunInterrupted, DuringTheGlobalBaKeepsTheOnlineTrajectory) {
  testing::TempDir dir;
  const std::string seq = RenderedFolder(dir, 200, 480, 320);
  const std::string out = dir / "stopped";
  Child child(
      {DALA_BINARY, "run", seq, "--out", out, "--progress=false", "--set", "ba.final_ba=always"});
  ASSERT_TRUE(child.started());
  ASSERT_TRUE(child.WaitForLine("Ctrl-C stops it")) << child.log();
  child.Signal(SIGINT);
  EXPECT_EQ(child.Wait(), 128 + SIGINT) << child.log();
  EXPECT_THAT(child.log(), HasSubstr("stopped on request: poses and landmarks unchanged"));
  EXPECT_THAT(child.log(), HasSubstr("interrupted by SIGINT during the global BA: the results are "
                                     "those of ba.final_ba=off (report"));
  EXPECT_THAT(child.log(), Not(HasSubstr("NOT usable")));
  const nlohmann::json report = nlohmann::json::parse(ReadAll(out + "/report.json"));
  const nlohmann::json& summary = report.at("summary");
  EXPECT_TRUE(summary.at("interrupted").get<bool>());
  EXPECT_FALSE(summary.at("refinement").at("done").get<bool>());
  // report.html shows the printed summary: it says so too.
  EXPECT_THAT(report.at("summary_text").get<std::string>(),
              HasSubstr("the global BA after the last frame was stopped"));
  EXPECT_EQ(summary.at("frames").get<int>(), 200);
  EXPECT_EQ(summary.at("frames_with_pose").get<int>(), 200);
  EXPECT_FALSE(fs::exists(out + "/trajectory_online.txt"));
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_THAT(entry.path().filename().string(), Not(HasSubstr(".tmp"))) << "left over";
  }
  const auto online = DalaRun(seq + " --out " + (dir / "online") + " --set ba.final_ba=off", dir);
  ASSERT_EQ(online.status, 0) << online.err;
  EXPECT_EQ(ReadAll(out + "/trajectory.txt"), ReadAll(dir / "online/trajectory.txt"));
}

}  // namespace
}  // namespace dala
