#ifndef DALA_CORE_EVAL_PLOT_H_
#define DALA_CORE_EVAL_PLOT_H_

#include <string>

#include "core/eval/evaluate.h"
#include "core/trajectory.h"

namespace dala {

// Draws an evaluation as a PNG (OpenCV, no plotting library):
//  - top: a top view of the ground truth and of the aligned estimate, on the two world axes with
//    the largest extent of the ground truth, equal aspect, metre ticks, start markers, legend;
//  - bottom: the ATE translation error of every pair against the distance travelled along the
//    ground truth, with the RMSE as a dashed line.
// `aligned_est` is the estimate mapped into the ground truth world
// (AlignTrajectory(est, result.alignment)). The file is written atomically; throws dala::Error
// naming the path when it cannot be written. CHECKs result.ok.
void PlotEvaluation(const Trajectory& gt, const Trajectory& aligned_est, const EvalResult& result,
                    const std::string& png_path);

}  // namespace dala

#endif  // DALA_CORE_EVAL_PLOT_H_
