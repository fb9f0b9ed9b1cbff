// The `--out` flag shared by several commands (dala synth, dala run, dala bench). gflags allows
// one DEFINE per flag name in the binary: this file holds it until cmd_synth.cc (which DEFINEs
// `out` too) is merged; then delete this file and keep cmd_synth.cc's definition.
#include <gflags/gflags.h>

DEFINE_string(out, "", "output folder (created if missing)");
