#ifndef DALA_CORE_EVAL_STATISTICS_H_
#define DALA_CORE_EVAL_STATISTICS_H_

#include <cstddef>
#include <vector>

namespace dala {

// Summary statistics of a list of non-negative errors, with the definitions evo uses (numpy):
//   rmse = sqrt(sum e_i^2 / n), mean = sum e_i / n, median = middle value (mean of the two middle
//   values when n is even), std = sqrt(sum (e_i - mean)^2 / n) (population, ddof = 0), min, max.
// All fields are 0 when the list is empty (count says so).
struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;
  double min = 0.0;
  double max = 0.0;
};

ErrorStatistics ComputeStatistics(const std::vector<double>& errors);

}  // namespace dala

#endif  // DALA_CORE_EVAL_STATISTICS_H_
