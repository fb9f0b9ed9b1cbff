// Child processes (tools/bench/subprocess.h), the line chart and the CSV of the results.
#include "tools/bench/subprocess.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "tests/test_util.h"
#include "tools/bench/line_chart.h"
#include "tools/bench/report_writer.h"

namespace dala::bench {
namespace {

using ::testing::HasSubstr;

std::string ReadText(const std::string& path) {
  std::ifstream is(path);
  return std::string(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
}

SubprocessResult Shell(const std::string& script, const std::string& log, double timeout = 0) {
  SubprocessOptions options;
  options.log_path = log;
  options.timeout_s = timeout;
  return RunSubprocess({"/bin/sh", "-c", script}, options);
}

TEST(Subprocess, ReportsExitStatusAndCapturesBothStreams) {
  testing::TempDir dir;
  const SubprocessResult r = Shell("echo out; echo err >&2; exit 3", dir / "log.txt");
  EXPECT_TRUE(r.started);
  EXPECT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_FALSE(r.signaled);
  EXPECT_GT(r.peak_rss_mb, 0.1);  // A shell uses at least a few hundred KiB.
  EXPECT_EQ(ReadText(dir / "log.txt"), "out\nerr\n");
}

TEST(Subprocess, ReportsACrash) {
  testing::TempDir dir;
  const SubprocessResult r = Shell("echo before; kill -SEGV $$", dir / "log.txt");
  EXPECT_TRUE(r.signaled);
  EXPECT_EQ(r.signal, SIGSEGV);
  EXPECT_FALSE(r.exited);
  EXPECT_FALSE(r.timed_out);
}

TEST(Subprocess, KillsAfterTheTimeout) {
  testing::TempDir dir;
  const SubprocessResult r = Shell("exec sleep 30", dir / "log.txt", 0.2);
  EXPECT_TRUE(r.timed_out);
  EXPECT_TRUE(r.signaled);
  EXPECT_EQ(r.signal, SIGKILL);
  EXPECT_LT(r.wall_s, 5.0);
  EXPECT_GE(r.wall_s, 0.2);
}

TEST(Subprocess, AMissingExecutableIsAFailedRunWithItsReason) {
  testing::TempDir dir;
  SubprocessOptions options;
  options.log_path = dir / "log.txt";
  const SubprocessResult r = RunSubprocess({dir / "no_such_program", "x"}, options);
  EXPECT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 127);
  EXPECT_THAT(ReadText(dir / "log.txt"), HasSubstr("No such file or directory"));
  // A log that cannot be opened: not started, with the reason.
  options.log_path = dir / "missing_folder/log.txt";
  const SubprocessResult bad = RunSubprocess({"/bin/true"}, options);
  EXPECT_FALSE(bad.started);
  EXPECT_THAT(bad.error, HasSubstr("cannot open the log"));
}

TEST(Subprocess, ShellJoinQuotesWhatNeedsIt) {
  EXPECT_EQ(ShellJoin({"/bin/dala", "run", "a b", "--set", "k=v", "it's", ""}),
            "/bin/dala run 'a b' --set k=v 'it'\\''s' ''");
}

TEST(Subprocess, TailOfFileKeepsTheLastNonEmptyLines) {
  testing::TempDir dir;
  std::ofstream(dir / "f.txt") << "1\n2\n\n3\n4\n  \n";
  EXPECT_EQ(TailOfFile(dir / "f.txt", 2), "3\n4");
  EXPECT_EQ(TailOfFile(dir / "missing.txt"), "");
}

TEST(LineChart, WritesAPngOfTheRequestedSize) {
  testing::TempDir dir;
  LineChartOptions options;
  options.title = "t";
  options.width = 640;
  options.height = 300;
  DrawLineChart({{"a", {0, 1, 2}, {1, 3, 2}}, {"b", {0, 2}, {0.5, 0.5}}}, options, dir / "c.png");
  const cv::Mat img = cv::imread(dir / "c.png");
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 640);
  EXPECT_EQ(img.rows, 300);
  // Not blank: the series are drawn in colour.
  int coloured = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      coloured += std::abs(p[0] - p[2]) > 60;
    }
  }
  EXPECT_GT(coloured, 200);
  DrawLineChart({}, options, dir / "empty.png");  // "no data", still a valid image.
  EXPECT_FALSE(cv::imread(dir / "empty.png").empty());
  EXPECT_THROW(DrawLineChart({}, options, dir / "no/such/dir/c.png"), Error);
}

TEST(ResultsCsv, QuotesFieldsWithCommasQuotesAndNewlines) {
  BenchRunResult r;
  r.sequence = "s";
  r.config = "c";
  r.status = "failed";
  r.error = "exit 1: \"bad\", really\nsecond line";
  r.ate_rmse = 0.123456;
  const std::string csv = ResultsCsv({r});
  EXPECT_THAT(csv, HasSubstr("s,c,,,,,,failed,0.1235,"));
  EXPECT_THAT(csv, HasSubstr(",\"exit 1: \"\"bad\"\", really\nsecond line\"\n"));
}

}  // namespace
}  // namespace dala::bench
