// `dala match` end to end: runs the CLI binary on a generated pair with a known homography.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "tests/frontend/test_images.h"
#include "tests/test_util.h"

namespace dala {
namespace {

class CmdMatchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const cv::Mat a = testing::MakeTexturedImage(400, 300, 17);
    H_ = testing::SimilarityAboutCentre(a.size(), 1.2, 1.2);
    ASSERT_TRUE(cv::imwrite(dir_ / "a.png", a));
    ASSERT_TRUE(cv::imwrite(dir_ / "b.png", testing::Warp(a, H_)));
    std::ofstream t(dir_ / "H.txt");
    t.precision(17);
    for (int k = 0; k < 9; ++k) t << H_.at<double>(k / 3, k % 3) << (k % 3 == 2 ? "\n" : " ");
  }
  // Runs a shell command; returns its exit status, and its stdout and stderr in *out.
  int RunShell(const std::string& cmd, std::string* out) {
    const std::string file = dir_ / "cmd_output.txt";
    const int status = std::system((cmd + " > " + file + " 2>&1").c_str());
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    *out = ss.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string Dala(const std::string& args) { return std::string(DALA_BINARY) + " match " + args; }
  testing::TempDir dir_;
  cv::Mat H_;
};

TEST_F(CmdMatchTest, JsonReportsPrecisionAgainstTheHomography) {
  std::string out;
  ASSERT_EQ(RunShell(Dala(dir_ / "a.png" + " " + dir_ / "b.png" + " --homography " +
                          dir_ / "H.txt" + " --json --out " + dir_ / "m.png"),
                     &out),
            0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_GT(j["matches"].get<int>(), 150);
  EXPECT_GT(j["precision"].get<double>(), 0.95);
  EXPECT_LE(j["correct"].get<int>(), j["matches"].get<int>());
  EXPECT_TRUE(j.contains("ms"));
  EXPECT_FALSE(cv::imread(dir_ / "m.png").empty());
}

TEST_F(CmdMatchTest, ClearErrors) {
  std::string out;
  EXPECT_EQ(RunShell(Dala(dir_ / "a.png" + " " + dir_ / "missing.png"), &out), 2);
  EXPECT_NE(out.find("missing.png"), std::string::npos) << out;
  std::ofstream(dir_ / "bad.txt") << "1 2 3\n";
  EXPECT_EQ(
      RunShell(Dala(dir_ / "a.png" + " " + dir_ / "b.png" + " --homography " + dir_ / "bad.txt"),
               &out),
      2);
  EXPECT_NE(out.find("9 numbers"), std::string::npos) << out;
  std::ofstream(dir_ / "notimage.png") << "hello";
  EXPECT_EQ(RunShell(Dala(dir_ / "a.png" + " " + dir_ / "notimage.png"), &out), 2);
  EXPECT_NE(out.find("decode"), std::string::npos) << out;
  EXPECT_EQ(RunShell(Dala(dir_ / "a.png"), &out), 2);
}

}  // namespace
}  // namespace dala
