#include "core/io/calibration_yaml.h"

#include "core/config.h"
#include "core/error.h"

namespace dala {

StereoRig ReadCalibrationYaml(const std::string& path) {
  const ConfigNode root = LoadConfigFile(path);
  for (const char* key : {"fx", "fy", "cx", "cy", "width", "height"}) {
    if (!root.Has(key)) {
      throw Error() << path << ": the calibration needs '" << key
                    << "' (required: fx fy cx cy width height; optional: baseline k1 k2 p1 p2 k3)";
    }
  }
  StereoRig rig;
  PinholeCamera& cam = rig.left;
  root.Read("fx", &cam.fx);
  root.Read("fy", &cam.fy);
  root.Read("cx", &cam.cx);
  root.Read("cy", &cam.cy);
  root.Read("width", &cam.width);
  root.Read("height", &cam.height);
  root.Read("baseline", &rig.baseline);
  const char* distortion_keys[5] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) root.Read(distortion_keys[i], &cam.distortion[i]);
  root.CheckNoUnknownKeys();
  std::string why;
  if (!rig.IsValid(&why)) throw Error() << path << ": invalid calibration: " << why;
  return rig;
}

}  // namespace dala
