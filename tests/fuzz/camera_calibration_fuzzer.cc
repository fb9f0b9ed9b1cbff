// Fuzzes the calibration files dala reads by content (--calibration: OpenCV, ROS camera_info,
// Kalibr camchain, dala's own) and the rectification built from them.
#include "core/io/camera_calibration.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  dala::fuzz::QuietLogging();
  const std::string path = dala::fuzz::WriteScratchFile("camera.yaml", data, size);
  dala::fuzz::ExpectOnlyDalaErrors([&] {
    const dala::CameraCalibration c = dala::ReadCameraCalibration(path);
    // Small images only: the maps cost width x height.
    if (c.cam0.width <= 64 && c.cam0.height <= 64) {
      dala::MakeRectification(c, c.is_stereo());
    }
  });
  return 0;
}
