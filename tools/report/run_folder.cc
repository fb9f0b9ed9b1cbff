#include "tools/report/run_folder.h"

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/eval/alignment.h"
#include "core/eval/evaluate.h"
#include "core/io/dataset.h"
#include "core/io/map_file.h"
#include "core/io/trajectory_io.h"

namespace dala::report {
namespace {

void RequireFile(const std::string& path, const std::string& what) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << path << ": missing (" << what
                  << "); give the --out folder of a `dala run`, or a map.dmap file";
  }
}

std::vector<Eigen::Vector3d> LandmarkPositions(const SavedMap& map) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(map.landmarks.size());
  for (const SavedLandmark& l : map.landmarks) points.push_back(l.p_w);
  return points;
}

}  // namespace

ReportInput ReportInputFromRunFolder(const std::string& dir, std::string* note) {
  note->clear();
  const std::string json_path = dir + "/report.json";
  const std::string trajectory_path = dir + "/trajectory.txt";
  const std::string map_path = dir + "/map.dmap";
  RequireFile(json_path, "the run's report.json");
  RequireFile(trajectory_path, "the run's trajectory");
  nlohmann::json report;
  {
    std::ifstream in(json_path);
    report = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  }
  if (report.is_discarded() || !report.is_object() || !report.contains("frames") ||
      !report.contains("dataset")) {
    throw Error() << json_path << ": not a report.json of `dala run` (no \"frames\" or "
                  << "\"dataset\"); run `dala run` again to write it";
  }
  ReportInput input;
  input.title = report["dataset"].value("path", dir);
  input.trajectory = ReadTrajectory(trajectory_path, TrajectoryFormat::kTum);
  input.frames = report["frames"];
  input.summary = report.value("summary", nlohmann::json::object());
  input.summary_text = report.value("summary_text", std::string());
  input.keyframes = KeyframesFromFrames(input.frames, input.trajectory);
  if (std::filesystem::is_regular_file(map_path)) {
    input.points_w = LandmarkPositions(ReadMapFile(map_path));
  } else {
    *note = map_path + " is missing: the report shows no map points";
  }
  // The ground truth, from the dataset again.
  try {
    DatasetOptions options;
    options.format = ParseDatasetFormat(report["dataset"].value("format", std::string("auto")));
    options.allow_missing_images = true;
    // The absolute path when report.json has it (the run may have been given a relative one).
    const std::string dataset_path = report["dataset"].value("absolute_path", input.title);
    const std::unique_ptr<Dataset> dataset = OpenDataset(dataset_path, options);
    const PinholeCamera& camera = dataset->rig().left;
    if (camera.width > 0 && camera.height > 0) {
      input.image_aspect = static_cast<double>(camera.width) / camera.height;
    }
    if (dataset->ground_truth() && !dataset->ground_truth()->empty()) {
      EvalOptions eval;
      eval.alignment = report.value("mode", std::string()) == "mono" ? AlignmentType::kSim3
                                                                     : AlignmentType::kSE3;
      input.ground_truth = dataset->ground_truth();
      input.evaluation = Evaluate(*input.ground_truth, input.trajectory, eval);
    }
  } catch (const Error& e) {
    *note = "no ground truth shown: the dataset " +
            report["dataset"].value("absolute_path", input.title) + " could not be opened again (" +
            e.what() + ")";
  }
  return input;
}

ReportInput ReportInputFromMapFile(const std::string& path) {
  const SavedMap map = ReadMapFile(path);
  ReportInput input;
  input.title = path;
  input.points_w = LandmarkPositions(map);
  for (const SavedKeyframe& k : map.keyframes) input.keyframes.push_back({k.frame.value, k.T_w_c});
  if (map.thumbnail_width > 0 && map.thumbnail_height > 0) {
    input.image_aspect = static_cast<double>(map.thumbnail_width) / map.thumbnail_height;
  }
  input.summary_text = "saved map " + path + ": " + std::to_string(map.keyframes.size()) +
                       " keyframes, " + std::to_string(map.landmarks.size()) + " landmarks, " +
                       (map.metric ? "metric" : "arbitrary unit (one camera)") + "\n";
  return input;
}

}  // namespace dala::report
