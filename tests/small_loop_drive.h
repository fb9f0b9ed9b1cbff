#ifndef DALA_TESTS_SMALL_LOOP_DRIVE_H_
#define DALA_TESTS_SMALL_LOOP_DRIVE_H_

// The loop-closure tests' drive: the rendered small loop (~125 m, one lap in 150 frames, 0.83 m
// per frame) at 3 Hz, 480x320 pixels, fx = fy = 290, scene seed 3.

#include "core/sim/synthetic_sequence.h"

namespace dala {

inline sim::SimOptions SmallLoopAt3Hz(int frames) {
  sim::SimOptions sim;
  sim.preset = "small_loop";
  sim.fps = 3.0;
  sim.frames = frames;
  sim.width = 480;
  sim.height = 320;
  sim.fx = sim.fy = 290.0;
  sim.seed = 3;
  return sim;
}

}  // namespace dala

#endif  // DALA_TESTS_SMALL_LOOP_DRIVE_H_
