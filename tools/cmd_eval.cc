// `dala eval GT EST`: compares an estimated trajectory with ground truth (ATE, RPE, KITTI
// segment errors), as evo_ape / evo_rpe and the KITTI devkit do. See docs/evaluation.md.
#include <gflags/gflags.h>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/eval/alignment.h"
#include "core/eval/evaluate.h"
#include "core/eval/plot.h"
#include "core/io/trajectory_io.h"
#include "tools/command.h"

DEFINE_string(align, "se3",
              "Alignment of the estimate onto the ground truth before the ATE: "
              "se3 (rigid, Umeyama), sim3 (with scale, for monocular), none");
DEFINE_double(delta, 1.0, "RPE step, in --delta_unit");
DEFINE_string(delta_unit, "f", "Unit of the RPE step: f (frames) or m (metres of path)");
DEFINE_double(max_diff, 0.01,
              "Maximum time difference in seconds for two stamps to be "
              "associated (TUM/evo association)");
DEFINE_string(plot, "", "Write a PNG plot (top view and ATE along the path) to this file");
DECLARE_bool(json);  // tools/common_flags.cc
DECLARE_string(times);  // tools/common_flags.cc
DEFINE_string(format_gt, "auto", "Format of the ground truth file: auto, tum, kitti, euroc");
DEFINE_string(format_est, "auto", "Format of the estimate file: auto, tum, kitti, euroc");

namespace dala {
namespace {

Trajectory ReadInput(const std::string& path, const std::string& format, const char* role) {
  if (!std::filesystem::exists(path)) {
    throw Error() << path << ": the " << role << " file does not exist";
  }
  if (std::filesystem::is_directory(path)) {
    throw Error() << path << ": the " << role << " is a folder; give the trajectory file";
  }
  return ReadTrajectory(path, ParseTrajectoryFormat(format));
}

int RunEval(const std::vector<std::string>& args) {
  if (args.size() != 2) {
    throw Error() << "expected 2 arguments (GT EST), got " << args.size()
                  << "; see `dala eval --help`";
  }
  EvalOptions options;
  if (!ParseAlignmentType(FLAGS_align, &options.alignment)) {
    throw Error() << "--align=" << FLAGS_align << ": expected se3, sim3 or none";
  }
  if (!ParseDeltaUnit(FLAGS_delta_unit, &options.rpe_delta_unit)) {
    throw Error() << "--delta_unit=" << FLAGS_delta_unit << ": expected f (frames) or m (metres)";
  }
  options.rpe_delta = FLAGS_delta;
  options.max_time_diff_s = FLAGS_max_diff;
  std::string why;
  if (!options.IsValid(&why)) {
    throw Error() << "invalid options (--delta, --delta_unit, --max_diff): " << why;
  }

  Trajectory gt = ReadInput(args[0], FLAGS_format_gt, "ground truth");
  Trajectory est = ReadInput(args[1], FLAGS_format_est, "estimate");
  if (!FLAGS_times.empty()) {
    if (gt.has_timestamps && est.has_timestamps) {
      throw Error() << "--times=" << FLAGS_times
                    << ": both files carry timestamps; --times is for KITTI files only";
    }
    if (!gt.has_timestamps) ApplyTimes(FLAGS_times, &gt);
    if (!est.has_timestamps) ApplyTimes(FLAGS_times, &est);
  }

  const EvalResult result = Evaluate(gt, est, options);
  if (!result.ok) {
    throw Error() << args[0] << " vs " << args[1] << ": " << result.error;
  }
  if (!FLAGS_plot.empty()) {
    PlotEvaluation(gt, AlignTrajectory(est, result.alignment), result, FLAGS_plot);
  }
  if (FLAGS_json) {
    std::cout << EvalResultToJson(result).dump(2) << std::endl;
  } else {
    std::cout << "ground truth: " << args[0] << " (" << gt.size() << " poses)\n"
              << "estimate:     " << args[1] << " (" << est.size() << " poses)\n"
              << EvalResultToTable(result);
    if (!FLAGS_plot.empty()) std::cout << "plot written to " << FLAGS_plot << "\n";
  }
  return 0;
}

const CommandRegistrar registrar(
    {"eval", "compare a trajectory with ground truth (ATE, RPE, KITTI segment errors)",
     "dala eval GT EST [--align se3|sim3|none] [--delta N --delta_unit f|m] [--max_diff S]\n"
     "                 [--plot FILE.png] [--json] [--times TIMES.txt]\n"
     "                 [--format_gt auto|tum|kitti|euroc] [--format_est ...]\n\n"
     "Formats are detected from the content (TUM, KITTI, EuRoC csv). Timestamped files are\n"
     "associated by time (closest stamps within --max_diff, each used once); KITTI files, which\n"
     "have no stamps, pair row by row (equal lengths) unless --times gives their stamps.\n"
     "Metrics (docs/evaluation.md): ATE after alignment (evo_ape), RPE over --delta (evo_rpe,\n"
     "consecutive pairs), and the KITTI devkit segment errors (100..800 m, unaligned) when the\n"
     "path is long enough. Dashes and underscores in flag names are equivalent.\n\n"
     "examples:\n"
     "  dala eval poses/00.txt results/00.txt --plot 00.png\n"
     "  dala eval groundtruth.txt traj.txt --align sim3 --max_diff 0.02 --json\n"
     "  dala eval data.csv traj.txt --delta 1 --delta_unit m",
     &RunEval, __FILE__});

}  // namespace
}  // namespace dala
