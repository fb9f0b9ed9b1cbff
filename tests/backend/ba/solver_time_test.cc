// The solvers' wall-clock limits: none by default, so that no result depends on the machine's
// load (DESIGN.md, determinism); a positive budget is an explicit opt-in.
#include "backend/ba/solver_time.h"

#include <gtest/gtest.h>

#include <string>

#include "backend/ba/pose_graph.h"
#include "backend/ba/pose_only.h"
#include "backend/ba/sliding_window_ba.h"

namespace dala {
namespace {

template <typename Options>
void ExpectNoTimeLimitByDefault(const char* name) {
  SCOPED_TRACE(name);
  Options options;
  std::string why;
  EXPECT_EQ(options.max_solver_time_in_seconds, 0.0);
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.max_solver_time_in_seconds = 0.25;  // The opt-in budget.
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.max_solver_time_in_seconds = -1.0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("max_solver_time_in_seconds must be >= 0 (0: no time limit)"),
            std::string::npos)
      << why;
}

TEST(SolverTime, NoLimitByDefaultInEverySolver) {
  ExpectNoTimeLimitByDefault<SlidingWindowBa::Options>("window BA");
  ExpectNoTimeLimitByDefault<PoseOnlyOptions>("pose-only");
  ExpectNoTimeLimitByDefault<PoseGraphOptions>("pose graph");
}

TEST(SolverTime, ZeroMeansNoLimitForCeres) {
  EXPECT_GE(CeresSolverTimeLimit(0.0), 1e9);  // Ceres's own default: no limit in practice.
  EXPECT_EQ(CeresSolverTimeLimit(0.25), 0.25);
}

}  // namespace
}  // namespace dala
