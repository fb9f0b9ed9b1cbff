#include "tools/bench/suite.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <set>
#include <stdexcept>
#include <tuple>

#include "core/config.h"
#include "core/error.h"

namespace dala::bench {
namespace fs = std::filesystem;
namespace {

// A key inside the suite file, for messages: "suite.yaml: sequences[2].frames".
struct Where {
  std::string file;
  std::string path;
  Where At(const std::string& key) const { return {file, path.empty() ? key : path + "." + key}; }
  Where At(size_t i) const { return {file, path + "[" + std::to_string(i) + "]"}; }
  std::string str() const { return file + ": " + path; }
};

void CheckKeys(const cv::FileNode& map, const Where& where, const std::set<std::string>& known) {
  for (const std::string& key : map.keys()) {
    if (known.count(key) == 0) {
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      throw Error() << where.At(key).str() << ": unknown key; expected one of: " << list;
    }
  }
}

std::string ReadString(const cv::FileNode& map, const Where& where, const char* key,
                       bool required) {
  const cv::FileNode n = map[key];
  if (n.empty() || n.isNone()) {
    if (required) throw Error() << where.At(key).str() << ": missing; expected a string";
    return "";
  }
  if (!n.isString()) throw Error() << where.At(key).str() << ": expected a string";
  return n.string();
}

// Reads an integer >= min_value; absent keeps *value.
void ReadInt(const cv::FileNode& map, const Where& where, const char* key, int min_value,
             int* value) {
  const cv::FileNode n = map[key];
  if (n.empty() || n.isNone()) return;
  const double v = n.isInt() || n.isReal() ? n.real() : std::nan("");
  if (!(v >= min_value) || v != std::floor(v) || v > 1e9) {
    throw Error() << where.At(key).str() << ": expected an integer >= " << min_value;
  }
  *value = static_cast<int>(v);
}

bool ReadBool(const cv::FileNode& map, const Where& where, const char* key) {
  const cv::FileNode n = map[key];
  if (n.empty() || n.isNone()) return false;
  if (n.isInt()) return static_cast<int>(n) != 0;
  if (n.isString()) {
    const std::string s = n.string();
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
  }
  throw Error() << where.At(key).str() << ": expected true or false";
}

std::string Resolve(const std::string& path, const std::string& base_dir) {
  fs::path p(path);
  if (p.is_relative()) p = fs::path(base_dir) / p;
  return fs::absolute(p).lexically_normal().string();
}

void CheckName(const std::string& name, const Where& where) {
  if (!IsValidName(name)) {
    throw Error() << where.str() << ": '" << name
                  << "' is not a valid name; use letters, digits, '_', '-' and '.'";
  }
}

// Reads `starts` (a count N: 0..N-1, or a list of frames) or `seeds` (a list): ascending,
// distinct, each >= 0. Absent leaves *values empty.
void ReadIntList(const cv::FileNode& map, const Where& where, const char* key, bool count_allowed,
                 std::vector<int>* values) {
  const cv::FileNode n = map[key];
  if (n.empty() || n.isNone()) return;
  const Where w = where.At(key);
  const std::string expected = count_allowed
                                   ? "expected a count N >= 1 (frames 0..N-1) or a non-empty "
                                     "list of frame indices >= 0, e.g. [0, 5, 10]"
                                   : "expected a non-empty list of integers >= 0, e.g. [1, 2, 3]";
  if (count_allowed && (n.isInt() || n.isReal())) {
    const double v = n.real();
    if (!(v >= 1) || v != std::floor(v) || v > 1e6) throw Error() << w.str() << ": " << expected;
    for (int i = 0; i < static_cast<int>(v); ++i) values->push_back(i);
    return;
  }
  if (!n.isSeq() || n.size() == 0) throw Error() << w.str() << ": " << expected;
  for (size_t i = 0; i < n.size(); ++i) {
    const cv::FileNode e = n[static_cast<int>(i)];
    const double v = e.isInt() || e.isReal() ? e.real() : std::nan("");
    if (!(v >= 0) || v != std::floor(v) || v > 1e9) {
      throw Error() << w.At(i).str() << ": " << expected;
    }
    values->push_back(static_cast<int>(v));
  }
  std::sort(values->begin(), values->end());
  const auto dup = std::adjacent_find(values->begin(), values->end());
  if (dup != values->end()) {
    throw Error() << w.str() << ": " << *dup << " is listed twice; each value gives one run";
  }
}

SequenceSpec ReadSequence(const cv::FileNode& n, const Where& where, const std::string& base,
                          std::vector<std::string>* skipped) {
  if (!n.isMap()) {
    throw Error() << where.str()
                  << ": expected a map such as {name: rover_loop, preset: rover_loop, frames: "
                     "300} or {name: kitti06, path: /data/kitti/06}";
  }
  CheckKeys(n, where,
            {"name", "path", "preset", "frames", "seed", "seeds", "mono", "starts", "optional"});
  SequenceSpec s;
  s.name = ReadString(n, where, "name", true);
  CheckName(s.name, where.At("name"));
  const std::string path = ReadString(n, where, "path", false);
  s.preset = ReadString(n, where, "preset", false);
  if (path.empty() == s.preset.empty()) {
    throw Error() << where.str() << ": give exactly one of 'path' (a dataset folder) or "
                  << "'preset' (rendered with dala synth)";
  }
  const auto only_with = [&](std::initializer_list<const char*> keys, const char* what) {
    for (const char* key : keys) {
      if (!n[key].empty()) throw Error() << where.At(key).str() << ": only " << what;
    }
  };
  if (!path.empty()) {
    only_with({"frames", "seed", "seeds", "mono"}, "for rendered presets, not with 'path'");
    s.optional = ReadBool(n, where, "optional");
    s.path = Resolve(path, base);
    if (!fs::is_directory(s.path)) {
      if (s.optional) {
        skipped->push_back(where.str() + " (" + s.name + "): optional dataset folder " + s.path +
                           " is absent; skipped");
        return s;
      }
      throw Error() << where.At("path").str() << ": dataset folder " << s.path
                    << " does not exist (relative paths are relative to the suite file; "
                    << "'optional: true' skips an absent folder)";
    }
    ReadIntList(n, where, "starts", true, &s.starts);
  } else {
    only_with({"starts", "optional"}, "for dataset folders ('path'), not with 'preset'");
    if (!n["seed"].empty() && !n["seeds"].empty()) {
      throw Error() << where.At("seeds").str()
                    << ": give either 'seed' (one run) or 'seeds' (one run per seed), not both";
    }
    ReadIntList(n, where, "seeds", false, &s.seeds);
  }
  ReadInt(n, where, "frames", 0, &s.frames);
  ReadInt(n, where, "seed", 0, &s.seed);
  s.mono = ReadBool(n, where, "mono");
  return s;
}

ConfigSpec ReadConfig(const cv::FileNode& n, const Where& where, const std::string& base) {
  if (!n.isMap()) {
    throw Error() << where.str()
                  << ": expected a map such as {name: ba-stereo, estimator: ba, mode: stereo}";
  }
  CheckKeys(n, where, {"name", "estimator", "mode", "config", "set", "draws"});
  ConfigSpec c;
  c.name = ReadString(n, where, "name", true);
  CheckName(c.name, where.At("name"));
  c.estimator = ReadString(n, where, "estimator", true);
  if (c.estimator != "ba" && c.estimator != "ekf") {
    throw Error() << where.At("estimator").str() << ": unknown estimator '" << c.estimator
                  << "'; expected ba or ekf";
  }
  c.mode = ReadString(n, where, "mode", true);
  if (c.mode != "stereo" && c.mode != "mono") {
    throw Error() << where.At("mode").str() << ": unknown mode '" << c.mode
                  << "'; expected stereo or mono";
  }
  const std::string config = ReadString(n, where, "config", false);
  if (!config.empty()) {
    c.config_file = Resolve(config, base);
    if (!fs::is_regular_file(c.config_file)) {
      throw Error() << where.At("config").str() << ": " << c.config_file << " does not exist";
    }
  }
  ReadInt(n, where, "draws", 1, &c.draws);
  const cv::FileNode set = n["set"];
  if (!set.empty() && !set.isNone()) {
    if (!set.isSeq()) {
      throw Error() << where.At("set").str() << ": expected a list of \"key=value\" strings";
    }
    for (size_t i = 0; i < set.size(); ++i) {
      const cv::FileNode e = set[static_cast<int>(i)];
      const std::string s = e.isString() ? e.string() : "";
      const size_t eq = s.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw Error() << where.At("set").At(i).str()
                      << ": expected a \"key=value\" string (quoted), as for dala run --set";
      }
      c.set.push_back(s);
    }
  }
  return c;
}

}  // namespace

bool IsValidName(const std::string& name) {
  if (name.empty() || name == "." || name == "..") return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

BenchSuite LoadBenchSuite(const std::string& path) {
  if (!fs::is_regular_file(path)) {
    throw Error() << path << ": the suite file does not exist (see docs/benchmarking.md; "
                  << "the default suite is benchmarks/default.yaml)";
  }
  const ConfigNode root = LoadConfigFile(path);  // Keeps the parsed document alive.
  const cv::FileNode& top = root.node();
  const Where where{path, ""};
  if (!top.isMap()) throw Error() << path << ": expected a map with sequences and configurations";
  CheckKeys(top, where, {"name", "timeout_s", "sequences", "configurations"});
  const std::string base = fs::absolute(path).parent_path().string();

  BenchSuite suite;
  suite.file = fs::absolute(path).lexically_normal().string();
  const cv::FileNode timeout = top["timeout_s"];
  if (!timeout.empty() && !timeout.isNone()) {
    if (!(timeout.isInt() || timeout.isReal()) || timeout.real() < 0) {
      throw Error() << where.At("timeout_s").str() << ": expected seconds >= 0 (0 = no timeout)";
    }
    suite.timeout_s = timeout.real();
  }
  for (const char* key : {"sequences", "configurations"}) {
    const cv::FileNode list = top[key];
    if (!list.isSeq() || list.size() == 0) {
      throw Error() << where.At(key).str() << ": missing or empty; expected a list of maps";
    }
  }
  std::set<std::string> names;
  const cv::FileNode sequences = top["sequences"];
  for (size_t i = 0; i < sequences.size(); ++i) {
    const Where w = where.At("sequences").At(i);
    const size_t skipped = suite.skipped.size();
    SequenceSpec s = ReadSequence(sequences[static_cast<int>(i)], w, base, &suite.skipped);
    if (!names.insert(s.name).second) {
      throw Error() << w.At("name").str() << ": duplicate sequence name '" << s.name << "'";
    }
    if (suite.skipped.size() == skipped) suite.sequences.push_back(std::move(s));
  }
  if (suite.sequences.empty()) {
    throw Error() << where.At("sequences").str()
                  << ": every sequence is optional and absent; nothing to run";
  }
  names.clear();
  const cv::FileNode configurations = top["configurations"];
  for (size_t i = 0; i < configurations.size(); ++i) {
    const Where w = where.At("configurations").At(i);
    suite.configurations.push_back(ReadConfig(configurations[static_cast<int>(i)], w, base));
    if (!names.insert(suite.configurations.back().name).second) {
      throw Error() << w.At("name").str() << ": duplicate configuration name '"
                    << suite.configurations.back().name << "'";
    }
  }
  return suite;
}

void AddDatasetSequence(const std::string& folder, BenchSuite* suite) {
  if (!fs::is_directory(folder)) {
    throw Error() << "--dataset=" << folder << ": the dataset folder does not exist";
  }
  SequenceSpec s;
  s.path = fs::absolute(folder).lexically_normal().string();
  if (!s.path.empty() && s.path.back() == '/') s.path.pop_back();
  s.name = fs::path(s.path).filename().string();
  if (!IsValidName(s.name)) {
    throw Error() << "--dataset=" << folder << ": the folder name '" << s.name
                  << "' cannot name a sequence; use letters, digits, '_', '-' and '.'";
  }
  for (const SequenceSpec& other : suite->sequences) {
    if (other.name == s.name) {
      throw Error() << "--dataset=" << folder << ": a sequence named '" << s.name
                    << "' is already in the suite; rename the folder or link it under another name";
    }
  }
  suite->sequences.push_back(s);
}

std::vector<int> ParseStartsFlag(const std::string& text) {
  const std::string usage = "--starts=" + text +
                            ": expected a count N (start frames 0..N-1) or a comma-separated "
                            "list of start frames, e.g. 0,5,10 (one frame F: \"F,\")";
  std::vector<int> values;
  const bool is_list = text.find(',') != std::string::npos;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find(',', pos);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(pos, end - pos);
    pos = end + 1;
    if (item.empty() && is_list && pos >= text.size()) break;  // "F," : a list of one.
    size_t used = 0;
    int v = -1;
    try {
      v = std::stoi(item, &used);
    } catch (const std::exception&) {
      throw Error() << usage;
    }
    if (used != item.size() || v < 0) throw Error() << usage;
    values.push_back(v);
  }
  if (values.empty()) throw Error() << usage;
  if (!is_list) {
    if (values[0] < 1) throw Error() << usage;
    const int count = values[0];
    values.clear();
    for (int i = 0; i < count; ++i) values.push_back(i);
  }
  std::sort(values.begin(), values.end());
  if (std::adjacent_find(values.begin(), values.end()) != values.end()) {
    throw Error() << "--starts=" << text << ": a start frame is listed twice";
  }
  return values;
}

int SetDatasetStarts(const std::vector<int>& starts, BenchSuite* suite) {
  int changed = 0;
  for (SequenceSpec& s : suite->sequences) {
    if (s.is_rendered()) continue;
    s.starts = starts;
    ++changed;
  }
  return changed;
}

namespace {

// The runs of one sequence under one configuration, in variant order.
void AppendVariants(const SequenceSpec& s, const ConfigSpec& c, std::vector<BenchRun>* runs) {
  if (!s.seeds.empty()) {
    for (const int seed : s.seeds) {
      BenchRun r{0, s, "seed" + std::to_string(seed), 0, c};
      r.sequence.seed = seed;
      r.sequence.seeds.clear();
      runs->push_back(r);
    }
  } else if (!s.starts.empty()) {
    for (const int start : s.starts) {
      BenchRun r{0, s, "start" + std::to_string(start), start, c};
      r.sequence.starts.clear();
      runs->push_back(r);
    }
  } else {
    runs->push_back({0, s, "", 0, c});
  }
}

// The position of a variant in its sequence's list (seeds and starts are ascending).
int VariantOrder(const BenchRun& r) {
  return r.variant.empty() ? 0 : r.has_start() ? r.first_frame : r.sequence.seed;
}

}  // namespace

std::vector<BenchRun> MakeRunList(const BenchSuite& suite) {
  std::vector<BenchRun> runs;
  for (const SequenceSpec& s : suite.sequences) {
    for (const ConfigSpec& c : suite.configurations) AppendVariants(s, c, &runs);
  }
  std::sort(runs.begin(), runs.end(), [](const BenchRun& a, const BenchRun& b) {
    const int va = VariantOrder(a), vb = VariantOrder(b);
    return std::tie(a.sequence.name, va, a.config.name) <
           std::tie(b.sequence.name, vb, b.config.name);
  });
  for (size_t k = 0; k < runs.size(); ++k) runs[k].index = static_cast<int>(k);
  return runs;
}

Shard ParseShard(const std::string& text) {
  Shard shard;
  const size_t slash = text.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    size_t used = 0;
    shard.index = std::stoi(text.substr(0, slash), &used);
    if (used != slash) throw std::invalid_argument("trailing");
    const std::string n = text.substr(slash + 1);
    shard.count = std::stoi(n, &used);
    if (used != n.size()) throw std::invalid_argument("trailing");
  } catch (const std::exception&) {
    throw Error() << "--shard=" << text << ": expected i/n, e.g. 0/4 (shard i of n, 0-based)";
  }
  if (shard.count < 1 || shard.index < 0 || shard.index >= shard.count) {
    throw Error() << "--shard=" << text << ": expected 0 <= i < n";
  }
  return shard;
}

std::vector<BenchRun> SelectShard(const std::vector<BenchRun>& runs, const Shard& shard) {
  std::vector<BenchRun> selected;
  for (const BenchRun& r : runs) {
    if (r.index % shard.count == shard.index) selected.push_back(r);
  }
  return selected;
}

}  // namespace dala::bench
