// Flags shared by several commands (gflags are global: one definition each). A command that
// uses one DECLAREs it and mentions it in its usage text; `dala CMD --help` then lists it.
#include <gflags/gflags.h>

DEFINE_string(out, "", "output path: a folder (synth, run, bench, fuse) or an image file (match)");
DEFINE_bool(json, false, "print one JSON object on stdout instead of the human-readable text");
DEFINE_double(fps, 0.0,
              "frame rate (Hz). synth: of the rendering (0: 10 Hz); run: gives frame i of an "
              "image folder or a video the time i / fps (0: times from the source)");
DEFINE_string(times, "",
              "a times file (one time in seconds per line, KITTI times.txt). eval: applied to "
              "the KITTI file(s), which have no stamps, so that they associate by time; run: "
              "the times of an image folder's images");
DEFINE_string(right_folder, "",
              "run, calibrate: image folder of the right camera (a stereo pair of folders)");
DEFINE_string(stereo_layout, "mono",
              "run, calibrate: layout of a video's frames: mono, or side_by_side (stereo: the "
              "left camera in the left half)");
