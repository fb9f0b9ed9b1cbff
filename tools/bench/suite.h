#ifndef DALA_TOOLS_BENCH_SUITE_H_
#define DALA_TOOLS_BENCH_SUITE_H_

// A benchmark suite: which sequences, which estimator configurations. docs/benchmarking.md
// describes the YAML format:
//
//   timeout_s: 900                  # optional, per run; 0 = none
//   sequences:
//     - {name: rover_loop, preset: rover_loop, frames: 1000, seed: 1}   # rendered by dala synth
//     - {name: kitti06, path: /data/kitti/sequences/06}                 # a dataset folder
//   configurations:
//     - {name: ba-stereo, estimator: ba, mode: stereo}
//     - {name: ekf-mono, estimator: ekf, mode: mono, set: ["ekf.max_landmarks=40"]}
//
// The run list is every sequence x configuration, sorted by (sequence, configuration) name, so
// that run k (and with it the shard k mod n) is the same on every machine.

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

  bool is_rendered() const { return !preset.empty(); }
};

struct ConfigSpec {
  std::string name;              // Folder name under DIR/runs/SEQ: [A-Za-z0-9_.-]+.
  std::string estimator = "ba";  // "ba" or "ekf".
  std::string mode = "stereo";   // "stereo" or "mono".
  std::string config_file;       // `dala run --config` (absolute), optional.
  std::vector<std::string> set;  // `dala run --set key=value`, in order.
};

struct BenchSuite {
  std::string file;        // Where it was read from (messages, results.json).
  double timeout_s = 0.0;  // Per run; 0 = no timeout.
  std::vector<SequenceSpec> sequences;
  std::vector<ConfigSpec> configurations;
};

// Reads a suite file. Relative `path` and `config` entries are relative to the suite file's
// folder. Throws dala::Error naming the file and key ("suite.yaml: sequences[2].frames: expected
// a positive integer") on a malformed file, an unknown key, a duplicate name, an unknown
// estimator or mode, or a dataset folder that does not exist.
BenchSuite LoadBenchSuite(const std::string& path);

// Adds a dataset folder given on the command line (`--dataset PATH`) as a sequence named after
// the folder. Throws dala::Error when it does not exist or its name is already taken.
void AddDatasetSequence(const std::string& folder, BenchSuite* suite);

// One run: a sequence under a configuration.
struct BenchRun {
  int index = 0;  // Position in the full sorted run list.
  SequenceSpec sequence;
  ConfigSpec config;
  std::string key() const { return sequence.name + "/" + config.name; }
};

// Every sequence x configuration, sorted by (sequence name, configuration name).
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
