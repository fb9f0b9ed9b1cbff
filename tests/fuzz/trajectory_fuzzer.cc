// Fuzzes the trajectory reader (what `dala eval` reads): TUM, KITTI and EuRoC csv files, the
// format either detected or forced. The first input byte picks the format; the rest is the file.
#include "core/io/trajectory_io.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  if (size == 0) return 0;
  using dala::TrajectoryFormat;
  const TrajectoryFormat formats[] = {TrajectoryFormat::kAuto, TrajectoryFormat::kTum,
                                      TrajectoryFormat::kKitti, TrajectoryFormat::kEurocCsv};
  const TrajectoryFormat format = formats[data[0] % 4];
  const std::string path = dala::fuzz::WriteScratchFile("trajectory.txt", data + 1, size - 1);
  dala::fuzz::ExpectOnlyDalaErrors([&] {
    dala::Trajectory trajectory = dala::ReadTrajectory(path, format);
    // A KITTI file gets its times from a times.txt, here the same bytes read as one.
    if (!trajectory.has_timestamps) dala::ApplyTimes(path, &trajectory);
  });
  return 0;
}
