// report.html in a real browser: Debian's headless Chromium opens the report of a `dala run` on a
// rendered sequence (WebGL through SwiftShader, no GPU): the page reports itself ready with no
// script error, the screenshot's 3D view holds the estimated path's colour, and another time in
// the URL (#t=) moves the camera marker. Skips, saying so, where /usr/bin/chromium is absent
// (scripts/install_deps.sh --test installs it).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>

#include "core/sim/dataset_writer.h"
#include "core/sim/synthetic_sequence.h"
#include "tests/dala_cli.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ReadAll;

constexpr char kChromium[] = "/usr/bin/chromium";
// The page's colours (tools/report/page/report.js), BGR.
const cv::Vec3b kPathBgr(0x30, 0x30, 0xff);
const cv::Vec3b kMarkerBgr(0xff, 0x00, 0xff);
// The screenshot's 3D view: left of the 440 px side panel, between the tool and time bars.
const cv::Rect kViewArea(0, 40, 1200 - 460, 800 - 80);

int System(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ChromiumFlags(const testing::TempDir& dir, const std::string& profile) {
  return std::string(kChromium) +
         " --headless=new --no-sandbox --disable-gpu --use-gl=swiftshader"
         " --enable-unsafe-swiftshader --disable-background-networking --disable-component-update"
         " --disable-sync --no-first-run --user-data-dir=" +
         (dir / profile) + " --window-size=1200,800";
}

// A screenshot of `url`; the browser's log (console messages included) goes to `log`.
cv::Mat Screenshot(const testing::TempDir& dir, const std::string& url, const std::string& name,
                   std::string* log) {
  const std::string png = dir / (name + ".png");
  const std::string log_file = dir / (name + ".log");
  System("timeout 120 " + ChromiumFlags(dir, "profile_" + name) +
         " --enable-logging=stderr --v=0 --screenshot=" + png + " '" + url + "' > " + log_file +
         " 2>&1");
  *log = ReadAll(log_file);
  return cv::imread(png, cv::IMREAD_COLOR);
}

// Pixels of the view area within `tolerance` of `bgr` (per channel), and their centroid.
int CountColour(const cv::Mat& image, const cv::Vec3b& bgr, int tolerance,
                cv::Point2d* centroid = nullptr) {
  int n = 0;
  cv::Point2d sum(0, 0);
  const cv::Rect area = kViewArea & cv::Rect(0, 0, image.cols, image.rows);
  for (int y = area.y; y < area.y + area.height; ++y) {
    for (int x = area.x; x < area.x + area.width; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - bgr[0]) <= tolerance && std::abs(p[1] - bgr[1]) <= tolerance &&
          std::abs(p[2] - bgr[2]) <= tolerance) {
        ++n;
        sum += cv::Point2d(x, y);
      }
    }
  }
  if (centroid != nullptr && n > 0) *centroid = sum / n;
  return n;
}

TEST(ReportBrowser, DrawsThePathAndMovesTheMarkerWithTheTime) {
  if (!std::filesystem::exists(kChromium)) {
    GTEST_SKIP() << kChromium << " is absent: no browser to open report.html in (install it: "
                 << "scripts/install_deps.sh --test, or apt-get install chromium)";
  }
  testing::TempDir dir;
  sim::SimOptions sim;
  sim.preset = "rover_loop";
  sim.frames = 80;
  sim.width = 320;
  sim.height = 240;
  sim.seed = 3;
  sim::WriteSyntheticDataset(sim, dir / "seq", false);
  const testing::DalaCliResult run = testing::RunDala(
      "run " + (dir / "seq") + " --out " + (dir / "run") + " --progress=false", dir / "run");
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string html = dir / "run/report.html";
  ASSERT_TRUE(std::filesystem::exists(html));
  const std::string url = "file://" + html;

  // (a) The page ran to its end: its title says ready (WebGL present, no exception).
  System("timeout 120 " + ChromiumFlags(dir, "profile_dom") + " --dump-dom '" + url + "' > " +
         (dir / "dom.html") + " 2> /dev/null");
  const std::string dom = ReadAll(dir / "dom.html");
  EXPECT_NE(dom.find("<title>dala report: ready</title>"), std::string::npos)
      << "the page did not report itself ready; its title: "
      << dom.substr(dom.find("<title>"), 120);

  std::string log_early, log_late;
  const cv::Mat early = Screenshot(dir, url + "#t=0.1", "early", &log_early);
  const cv::Mat late = Screenshot(dir, url + "#t=0.9", "late", &log_late);
  ASSERT_FALSE(early.empty()) << "no screenshot; the browser said:\n" << log_early;
  ASSERT_FALSE(late.empty()) << "no screenshot; the browser said:\n" << log_late;
  for (const std::string* log : {&log_early, &log_late}) {
    EXPECT_EQ(log->find("Uncaught"), std::string::npos) << *log;
    EXPECT_EQ(log->find("ERROR:CONSOLE"), std::string::npos) << *log;
  }

  // (b) The 3D view is drawn: the estimated path's colour is in it.
  EXPECT_GT(CountColour(early, kPathBgr, 12), 30) << "no path in the 3D view";

  // (c) The camera marker moves with the time in the URL.
  cv::Point2d at_early, at_late;
  ASSERT_GT(CountColour(early, kMarkerBgr, 12, &at_early), 20) << "no camera marker at t=0.1";
  ASSERT_GT(CountColour(late, kMarkerBgr, 12, &at_late), 20) << "no camera marker at t=0.9";
  EXPECT_GT(cv::norm(at_late - at_early), 20.0)
      << "the marker stayed at (" << at_early.x << ", " << at_early.y << ")";
}

}  // namespace
}  // namespace dala
