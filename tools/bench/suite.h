#ifndef DALA_TOOLS_BENCH_SUITE_H_
#define DALA_TOOLS_BENCH_SUITE_H_

// A benchmark suite: which sequences, which estimator configurations. docs/benchmarking.md
// describes the YAML format:
//
//   timeout_s: 900                  # optional, per run; 0 = none
//   sequences:
//     - {name: rover_loop, preset: rover_loop, frames: 1000, seed: 1}   # rendered by dala synth
//     - {name: kitti06, path: /data/kitti/sequences/06}                 # a dataset folder
//     - {name: flight, preset: flight, frames: 200, seeds: [1, 2, 3]}    # one run per seed
//     - {name: k06, path: ../data/k06, starts: 10, optional: true}      # start frames 0..9
//   configurations:
//     - {name: ba-stereo, estimator: ba, mode: stereo}
//     - {name: ekf-mono, estimator: ekf, mode: mono, set: ["ekf.max_landmarks=40"]}
//
// A sequence with `seeds` (rendered) or `starts` (dataset) stands for several variants, one run
// each per configuration: the spread over start frames and seeds is what a user meets, one run
// is a sample of it. The run list is every variant x configuration, sorted by (sequence name,
// variant, configuration name), so that run k (and with it the shard k mod n) is the same on
// every machine.

#include <string>
#include <vector>

namespace dala::bench {

struct SequenceSpec {
  std::string name;    // Folder name under DIR/sequences and DIR/runs: [A-Za-z0-9_.-]+.
  std::string path;    // A dataset folder (absolute); empty for a rendered preset.
  std::string preset;  // `dala synth --preset`; empty for a dataset folder.
  int frames = 0;      // `dala synth --frames` (0: the preset's default length).
  int seed = 1;        // `dala synth --seed`.
  bool mono = false;   // `dala synth --mono` (left camera only).
  // Rendered presets: one variant per seed (ascending, distinct); empty: `seed` alone, one run.
  std::vector<int> seeds;
  // Dataset folders: one variant per start frame (`dala run --first_frame`, ascending,
  // distinct); empty: one run from the first frame.
  std::vector<int> starts;
  // A dataset folder that may be absent (e.g. shared data not on every clone): skipped with a
  // note instead of an error.
  bool optional = false;

  bool is_rendered() const { return !preset.empty(); }
};

struct ConfigSpec {
  std::string name;              // Folder name under DIR/runs/SEQ: [A-Za-z0-9_.-]+.
  std::string estimator = "ba";  // "ba" or "ekf".
  std::string mode = "stereo";   // "stereo" or "mono".
  std::string config_file;       // `dala run --config` (absolute), optional.
  std::vector<std::string> set;  // `dala run --set key=value`, in order.
  int draws = 1;                 // `dala run --draws N` (1: one run, no flag given).
};

struct BenchSuite {
  std::string file;        // Where it was read from (messages, results.json).
  double timeout_s = 0.0;  // Per run; 0 = no timeout.
  std::vector<SequenceSpec> sequences;
  std::vector<ConfigSpec> configurations;
  // Why optional sequences were left out (absent folders), for the user to read.
  std::vector<std::string> skipped;
};

// Reads a suite file. Relative `path` and `config` entries are relative to the suite file's
// folder. Throws dala::Error naming the file and key ("suite.yaml: sequences[2].frames: expected
// a positive integer") on a malformed file, an unknown key, a duplicate name, an unknown
// estimator or mode, a bad `starts`/`seeds` list, or a dataset folder that does not exist
// (unless the sequence is `optional`: then it is left out and noted in `skipped`).
BenchSuite LoadBenchSuite(const std::string& path);

// Adds a dataset folder given on the command line (`--dataset PATH`) as a sequence named after
// the folder. Throws dala::Error when it does not exist or its name is already taken.
void AddDatasetSequence(const std::string& folder, BenchSuite* suite);

// Parses the `--starts` flag: "N" is a count (start frames 0..N-1), "a,b,c" a list (one start
// frame F: "F,"). Throws dala::Error naming the flag.
std::vector<int> ParseStartsFlag(const std::string& text);

// Sets the start frames of every dataset sequence (`--starts`). Returns how many it changed.
int SetDatasetStarts(const std::vector<int>& starts, BenchSuite* suite);

// One run: a variant of a sequence (a seed or a start frame) under a configuration.
struct BenchRun {
  int index = 0;  // Position in the full sorted run list.
  // The variant's sequence: for a seed variant, `seed` is that seed and `seeds` is cleared.
  SequenceSpec sequence;
  // "seed2", "start3", or empty for a sequence without `seeds`/`starts`. Its folders are
  // NAME@VARIANT ('@' is not allowed in names, so the split is unambiguous).
  std::string variant;
  int first_frame = 0;  // `dala run --first_frame` when the variant is a start frame.
  ConfigSpec config;

  // NAME or NAME@VARIANT: the folder under DIR/runs (and DIR/sequences for a rendered preset).
  std::string folder_name() const { return VariantFolderName(sequence.name, variant); }
  std::string key() const { return folder_name() + "/" + config.name; }
  bool has_start() const { return variant.rfind("start", 0) == 0; }
  static std::string VariantFolderName(const std::string& name, const std::string& variant) {
    return variant.empty() ? name : name + "@" + variant;
  }
};

// Every variant x configuration, sorted by (sequence name, variant: seeds and starts in
// ascending order, configuration name).
std::vector<BenchRun> MakeRunList(const BenchSuite& suite);

// A shard "i/n" (0 <= i < n) of the run list.
struct Shard {
  int index = 0;
  int count = 1;
  std::string ToString() const { return std::to_string(index) + "/" + std::to_string(count); }
};
// Parses "i/n"; throws dala::Error for anything else.
Shard ParseShard(const std::string& text);
// The runs of a shard: run k belongs to shard k mod n. The shards partition the list.
std::vector<BenchRun> SelectShard(const std::vector<BenchRun>& runs, const Shard& shard);

// True for names usable as folder names: non-empty, [A-Za-z0-9_.-]+, not "." or "..".
bool IsValidName(const std::string& name);

}  // namespace dala::bench

#endif  // DALA_TOOLS_BENCH_SUITE_H_
