#ifndef DALA_BACKEND_BA_SOLVER_TIME_H_
#define DALA_BACKEND_BA_SOLVER_TIME_H_

// The wall-clock limit of the Ceres solves (BA window, pose-only, pose graph).
//
// A solve stopped by its time limit stops wherever the machine's load let it get, so the result
// depends on timing and the run is no longer deterministic (DESIGN.md). dala's options therefore
// default to 0 = no time limit: the iteration limits (max_num_iterations) bound the work, the same
// on every machine. A positive value is an opt-in budget (e.g. for a real-time use that prefers a
// late answer cut short to a late answer), documented as non-deterministic.

namespace dala {

// What ceres::Solver::Options::max_solver_time_in_seconds gets for an option value `seconds`:
// itself when positive, else Ceres's own default of 1e9 s (no limit in practice).
inline double CeresSolverTimeLimit(double seconds) { return seconds > 0.0 ? seconds : 1e9; }

}  // namespace dala

#endif  // DALA_BACKEND_BA_SOLVER_TIME_H_
