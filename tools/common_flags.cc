// Flags shared by several commands (gflags are global: one definition each). A command that
// uses one DECLAREs it and mentions it in its usage text; `dala CMD --help` then lists it.
#include <gflags/gflags.h>

DEFINE_string(out, "", "output path: a folder (synth, run, bench) or an image file (match)");
DEFINE_bool(json, false, "print one JSON object on stdout instead of the human-readable text");
