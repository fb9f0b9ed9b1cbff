#include "backend/system_options.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::ErrorOf;

// A key that was removed is not only "unknown": the error names what replaced it, from --set
// and from a YAML file alike.
TEST(SystemOptions, ARemovedKeyNamesItsReplacement) {
  SystemOptions options;
  const std::string set_error =
      ErrorOf([&] { SetSystemOption("ba.offset_calibration_min_offset_px=0.2", &options); });
  EXPECT_NE(set_error.find("no longer exists"), std::string::npos) << set_error;
  EXPECT_NE(set_error.find("ba.offset_calibration_bias_px"), std::string::npos) << set_error;

  const std::string path = ::testing::TempDir() + "/removed_key.yaml";
  {
    std::ofstream out(path);
    out << "%YAML:1.0\n---\nba:\n  window_size: 8\n  offset_calibration_min_mean_over_sd: 3\n";
  }
  const std::string file_error = ErrorOf([&] { LoadSystemOptions(path, &options); });
  EXPECT_NE(file_error.find(path), std::string::npos) << file_error;
  EXPECT_NE(file_error.find("ba.offset_calibration_min_mean_over_sd"), std::string::npos)
      << file_error;
  EXPECT_NE(file_error.find("median"), std::string::npos) << file_error;
  std::filesystem::remove(path);
}

// The rig's known disparity offset (what `dala run` prints for later runs of the rig).
TEST(SystemOptions, AKnownDisparityOffsetIsReadAndChecked) {
  SystemOptions options;
  SetSystemOption("ba.calibrate_disparity_offset=0", &options);
  SetSystemOption("ba.disparity_offset_px=0.209", &options);
  EXPECT_EQ(options.ba.ba.disparity_offset_px, 0.209);
  EXPECT_FALSE(options.ba.ba.calibrate_disparity_offset);
  const std::string error =
      ErrorOf([&] { SetSystemOption("ba.disparity_offset_px=50", &options); });
  EXPECT_NE(error.find("disparity_offset_px"), std::string::npos) << error;
  EXPECT_NE(error.find("10 px"), std::string::npos) << error;
}

// An integer that does not fit the option is an error naming the key, never a wrapped value
// (4294967304 = 2^32 + 8 would become 8).
TEST(SystemOptions, AnIntegerOutOfRangeIsAnError) {
  SystemOptions options;
  for (const char* assignment : {"ba.window_size=4294967304", "motion.seed=-4294967304",
                                 "ba.window_size=99999999999999999999", "ba.window_size=8.5"}) {
    const std::string error = ErrorOf([&] { SetSystemOption(assignment, &options); });
    const std::string key = std::string(assignment).substr(0, std::string(assignment).find('='));
    EXPECT_NE(error.find(key), std::string::npos) << assignment << ": " << error;
    EXPECT_NE(error.find("integer"), std::string::npos) << assignment << ": " << error;
  }
  EXPECT_EQ(options.ba.ba.window_size, SystemOptions().ba.ba.window_size) << "left unchanged";
}

}  // namespace
}  // namespace dala
