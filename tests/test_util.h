#ifndef DALA_TESTS_TEST_UTIL_H_
#define DALA_TESTS_TEST_UTIL_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/geometry.h"

namespace dala::testing {

// Folder of the shared real recordings; tests that need it call DALA_SKIP_WITHOUT_SHARED_DATA().
inline std::string SharedDataDir() { return DALA_SHARED_DATA_DIR; }
inline bool HaveSharedData(const std::string& sub) {
  return std::filesystem::exists(SharedDataDir() + "/" + sub);
}
#define DALA_SKIP_WITHOUT_SHARED_DATA(sub)                                                    \
  if (!::dala::testing::HaveSharedData(sub))                                                  \
  GTEST_SKIP() << "shared data '" << ::dala::testing::SharedDataDir() << "/" << (sub)         \
               << "' is absent (it sits beside the project as ../shared/data); skipping"

// The message of the dala::Error that f throws ("" when it throws none).
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The whole file as a string ("" when it cannot be read).
inline std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A fresh temporary folder per test, removed at the end.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            (std::string("dala_") + (info ? info->test_suite_name() : "t") + "_" +
             (info ? info->name() : "x") + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string path() const { return path_.string(); }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline Pose RandomPose(std::mt19937& rng, double rot_scale = 1.0, double trans_scale = 5.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int i = 0; i < 6; ++i) xi[i] = n(rng) * (i < 3 ? rot_scale : trans_scale);
  return ExpSE3(xi);
}

// An end-to-end accuracy bound, anchored to the best value recorded for it (it is not raised
// when a change makes the result worse): EXPECT measured < 1.5 x best, and one line
//   [ bound ] Suite.Test | quantity | measured | best | bound | unit
// in the test's output, from which scripts/e2e_bounds_table.py writes docs/reliability.md's
// table of bounds (and CI checks that table's bounds against these lines).
inline void ExpectWithinBound(const std::string& quantity, double measured, double best,
                              const std::string& unit) {
  const double bound = 1.5 * best;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::ostringstream line;
  line.precision(6);
  line << "[ bound ] " << info->test_suite_name() << "." << info->name() << " | " << quantity
       << " | " << measured << " | " << best << " | " << bound << " | " << unit;
  std::cout << line.str() << std::endl;
  EXPECT_LT(measured, bound) << quantity << ": " << measured << " " << unit << ", bound 1.5 x "
                             << best << " (the best recorded)";
}

#define EXPECT_POSE_NEAR(A, B, tol)                                                          \
  EXPECT_LT(((A).matrix() - (B).matrix()).cwiseAbs().maxCoeff(), (tol))                     \
      << "A=\n" << (A).matrix() << "\nB=\n" << (B).matrix()

}  // namespace dala::testing

#endif  // DALA_TESTS_TEST_UTIL_H_
