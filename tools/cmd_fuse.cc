// `dala fuse RUN... --out DIR`: one trajectory from several runs over the same frames (runs that
// differ in their RANSAC draws, --set ransac_order_seed=K), each brought onto the others by a
// similarity (one camera) or a rigid transform (stereo) and averaged per frame
// (core/eval/trajectory_fusion.h). See docs/evaluation.md, "Fusing runs".
#include <gflags/gflags.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "backend/system.h"
#include "core/error.h"
#include "core/eval/statistics.h"
#include "core/eval/trajectory_fusion.h"
#include "core/io/atomic_file.h"
#include "core/io/trajectory_io.h"
#include "tools/command.h"

DECLARE_string(out);  // tools/common_flags.cc
DEFINE_string(fuse_align, "auto",
              "fuse: how each run is brought onto the others: sim3 (one camera: each run has "
              "its own unit), se3 (metric runs), none, or auto (se3 when every run folder's "
              "report.json says the scale is metric, else sim3)");

namespace dala {
namespace {

// A run: a `dala run` output folder (its trajectory.txt) or a trajectory file.
struct RunInput {
  std::string trajectory_path;
  bool metric = false;  // report.json says the run's scale is metric.
};

RunInput ReadRunInput(const std::string& path) {
  namespace fs = std::filesystem;
  if (!fs::exists(path)) throw Error() << path << ": no such run folder or trajectory file";
  RunInput input;
  if (!fs::is_directory(path)) {
    input.trajectory_path = path;
    return input;
  }
  input.trajectory_path = path + "/trajectory.txt";
  if (!fs::exists(input.trajectory_path)) {
    throw Error() << path << ": the folder has no trajectory.txt; give `dala run` output folders "
                  << "or trajectory files";
  }
  std::ifstream report(path + "/report.json");
  if (report) {
    try {
      const nlohmann::json j = nlohmann::json::parse(report);
      const std::string source = j.at("summary").at("scale_source").get<std::string>();
      input.metric = IsMetricScale(source);
    } catch (const std::exception& e) {
      throw Error() << path << "/report.json: not a `dala run` report (" << e.what() << ")";
    }
  }
  return input;
}

int RunFuse(const std::vector<std::string>& args) {
  if (args.size() < 2) {
    throw Error() << "expected at least 2 runs (folders of `dala run` or trajectory files), got "
                  << args.size() << "; see `dala fuse --help`";
  }
  if (FLAGS_out.empty()) throw Error() << "--out DIR is required (where the fused trajectory goes)";
  std::vector<RunInput> inputs;
  std::vector<Trajectory> runs;
  bool all_metric = true;
  for (const std::string& a : args) {
    inputs.push_back(ReadRunInput(a));
    all_metric = all_metric && inputs.back().metric;
    runs.push_back(ReadTrajectory(inputs.back().trajectory_path, TrajectoryFormat::kAuto));
  }
  TrajectoryFusionOptions options;
  if (FLAGS_fuse_align == "auto") {
    options.alignment = all_metric ? AlignmentType::kSE3 : AlignmentType::kSim3;
  } else if (!ParseAlignmentType(FLAGS_fuse_align, &options.alignment)) {
    throw Error() << "--fuse_align=" << FLAGS_fuse_align << ": expected auto, sim3, se3 or none";
  }
  FusedTrajectory fused;
  std::string why;
  if (!FuseTrajectories(runs, options, &fused, &why)) throw Error() << "cannot fuse: " << why;

  std::filesystem::create_directories(FLAGS_out);
  const std::string tum = FLAGS_out + "/trajectory.txt";
  const std::string kitti = FLAGS_out + "/trajectory_kitti.txt";
  WriteTrajectoryTum(tum, fused.trajectory);
  WriteTrajectoryKitti(kitti, fused.trajectory);
  const int all_runs = static_cast<int>(runs.size());
  const int in_all = static_cast<int>(std::count(fused.runs.begin(), fused.runs.end(), all_runs));
  const ErrorStatistics spread = ComputeStatistics(fused.spread);
  nlohmann::json per_run = nlohmann::json::array();
  for (size_t k = 0; k < runs.size(); ++k) {
    per_run.push_back({{"path", args[k]},
                       {"poses", runs[k].size()},
                       {"scale_onto_fused", fused.alignments[k].scale}});
  }
  const nlohmann::json report = {{"alignment", AlignmentTypeName(options.alignment)},
                                 {"runs", per_run},
                                 {"poses", fused.trajectory.size()},
                                 {"poses_in_every_run", in_all},
                                 // Per pose: how many runs had it, and the RMS distance of their
                                 // aligned positions from the mean (the first run's unit).
                                 {"runs_per_pose", fused.runs},
                                 {"spread", fused.spread},
                                 {"spread_median", spread.median},
                                 {"spread_max", spread.max}};
  WriteFileAtomically(FLAGS_out + "/fusion.json",
                      [&](std::ostream& os) { os << report.dump(1) << "\n"; });
  std::cout << "fused       " << runs.size() << " runs, " << fused.trajectory.size() << " poses ("
            << in_all << " in every run), aligned by " << AlignmentTypeName(options.alignment)
            << "\n"
            << "spread      " << std::setprecision(3) << spread.median << " median, " << spread.max
            << " max (RMS distance of the runs' positions from the mean, in the "
            << "first run's unit)\n"
            << "written     " << tum << ", " << kitti << ", " << FLAGS_out << "/fusion.json\n";
  return 0;
}

const CommandRegistrar registrar(
    {"fuse", "one trajectory from several runs over the same frames (their per-frame mean)",
     "dala fuse RUN RUN [RUN...] --out DIR [--fuse_align auto|sim3|se3|none]\n\n"
     "Each RUN is a `dala run` output folder (its trajectory.txt) or a trajectory file (TUM,\n"
     "KITTI, EuRoC). Runs that differ only in their RANSAC draws (--set ransac_order_seed=K)\n"
     "share what the data and the method get wrong but not what chance does; their mean keeps\n"
     "the first and averages the second (docs/evaluation.md, \"Fusing runs\"). Each run is\n"
     "aligned onto the mean (Sim(3) for one camera, SE(3) for metric runs), the runs averaged per\n"
     "frame (positions, and rotations by their chordal mean), a few rounds; the result is in the\n"
     "first run's world. Poses pair by timestamp; a frame some runs lack takes the mean of the\n"
     "others. Writes DIR/trajectory.txt (TUM), DIR/trajectory_kitti.txt and DIR/fusion.json\n"
     "(per frame: the runs that had it and their spread around the mean).\n\n"
     "example (three draws of one camera, then the fused run against ground truth):\n"
     "  for k in 0 1 2; do dala run DATA --mode mono --set ransac_order_seed=$k --out runs/$k; "
     "done\n"
     "  dala fuse runs/0 runs/1 runs/2 --out runs/fused\n"
     "  dala eval DATA/poses.txt runs/fused/trajectory.txt --times DATA/times.txt --align sim3",
     &RunFuse, __FILE__});

}  // namespace
}  // namespace dala
