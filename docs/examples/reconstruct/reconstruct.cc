// dala library example: reconstruct the camera trajectory of a dataset folder with dala::System,
// using only the installed public headers (see docs/api.md). It is the `dala run` job in ~80
// lines, without the CLI: open a dataset, track every frame, write the trajectory (TUM) and the
// map, and evaluate against the ground truth when the dataset has one.
//
//   reconstruct DATASET_DIR OUT_PREFIX [options.yaml]
//     -> OUT_PREFIX.txt (TUM trajectory, every frame), OUT_PREFIX.dmap (map, dala binary format)
//
// Build it against an installed dala (docs/api.md):
//   cmake -S docs/examples/reconstruct -B build-example -DCMAKE_PREFIX_PATH=/where/dala/is
//   cmake --build build-example

#include <cstdio>
#include <exception>
#include <string>

#include "backend/system.h"          // dala::System, dala::SystemOptions
#include "core/error.h"              // dala::Error
#include "core/eval/evaluate.h"      // dala::Evaluate
#include "core/io/dataset.h"         // dala::OpenDataset
#include "core/io/trajectory_io.h"   // dala::WriteTrajectoryTum

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr,
                 "usage: %s DATASET_DIR OUT_PREFIX [options.yaml]\n"
                 "  DATASET_DIR: KITTI, EuRoC, TUM or dala-synthetic folder (dala synth)\n"
                 "  writes OUT_PREFIX.txt (TUM trajectory) and OUT_PREFIX.dmap (map)\n",
                 argv[0]);
    return 2;
  }
  try {
    const std::unique_ptr<dala::Dataset> dataset = dala::OpenDataset(argv[1]);
    dala::SystemOptions options;  // stereo sliding-window BA; options.yaml may change it.
    if (!dataset->is_stereo()) options.mode = "mono";
    if (argc == 4) dala::LoadSystemOptions(argv[3], &options);

    dala::System system(dataset->rig(), options);
    dala::Frame frame;
    size_t done = 0, lost = 0;
    while (dataset->Next(&frame)) {
      const dala::TrackResult result = system.Track(frame);
      if (!result.valid) ++lost;
      if (++done % 50 == 0 || done == dataset->size()) {
        const Eigen::Vector3d t = result.T_w_c.translation();
        std::fprintf(stderr, "frame %zu/%zu  %s  t_w_c = (%.2f, %.2f, %.2f)\n", done,
                     dataset->size(), dala::TrackingStatusName(result.status), t.x(), t.y(),
                     t.z());
      }
    }
    const std::string prefix = argv[2];
    dala::WriteTrajectoryTum(prefix + ".txt", system.trajectory());
    system.SaveMap(prefix + ".dmap");
    std::printf("%zu frames (%zu not estimated), %zu keyframes, %zu landmarks\n", done, lost,
                system.keyframes().size(), system.map().size());

    if (dataset->ground_truth()) {
      dala::EvalOptions eval;
      if (options.mode == "mono") eval.alignment = dala::AlignmentType::kSim3;
      const dala::EvalResult r = dala::Evaluate(*dataset->ground_truth(), system.trajectory(), eval);
      if (r.ok) {
        std::printf("ATE RMSE %.4f m over %.1f m of path\n", r.ate.translation.rmse,
                    r.gt_path_length_m);
      } else {
        std::printf("no evaluation: %s\n", r.error.c_str());
      }
    }
    return 0;
  } catch (const dala::Error& e) {  // Bad input: the message says what and how to fix it.
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
