#ifndef DALA_CORE_CONFIG_H_
#define DALA_CORE_CONFIG_H_

// Loading option structs from YAML (OpenCV cv::FileStorage), with strict keys.
//
// Options are plain structs with their defaults in code; a YAML file only overrides. A component
// reads its struct from a node, field by field; a key absent from the file leaves the default.
// After reading, CheckNoUnknownKeys() rejects any key the component did not ask for, so a typo
// ("max_feature" for "max_features") is an error naming the file, the key and the known keys,
// never a silently ignored setting.
//
//   ConfigNode root = LoadConfigFile("run.yaml");
//   ConfigNode harris = root.Child("harris");          // absent -> an empty node, all defaults
//   harris.Read("max_features", &options.max_features);
//   harris.Read("sigma", &options.sigma);
//   harris.CheckNoUnknownKeys();
//   root.CheckNoUnknownKeys();                          // after all children were asked for
//
// A ConfigNode is a cheap handle: copies share the underlying file and the record of the keys
// read. Each Child() call starts a fresh record, so take a section's node once and pass it
// around. Not thread-safe.

#include <cstdint>
#include <memory>
#include <opencv2/core/persistence.hpp>
#include <set>
#include <string>
#include <vector>

namespace dala {

class ConfigNode {
 public:
  ConfigNode() = default;

  // Each Read records `key` as known; when the key is present its value replaces *v, otherwise
  // *v is left as is. cv::FileStorage holds integers in 32 bits (a larger literal wraps):
  // write an int64 beyond 2^31 quoted ("5000000000"). Throws dala::Error (file, key path, expected
  // type) on a value of the wrong type or out of range. Booleans accept true/false, yes/no, on/off
  // (any case) and 0/1.
  void Read(const char* key, double* v) const;
  void Read(const char* key, float* v) const;
  void Read(const char* key, int* v) const;
  void Read(const char* key, int64_t* v) const;
  void Read(const char* key, bool* v) const;
  void Read(const char* key, std::string* v) const;
  // A YAML sequence of numbers, e.g. [1.0, 2, 3]; replaces the whole vector.
  void Read(const char* key, std::vector<double>* v) const;

  // True when the node has this key (does not record it as known).
  bool Has(const char* key) const;
  // The child map `key`, recorded as known. An absent key gives an empty node whose reads keep
  // the defaults. Throws dala::Error when the key holds something other than a map.
  ConfigNode Child(const char* key) const;
  // Throws dala::Error listing the keys present in this map that no Read/Child asked for, with
  // the known keys. A non-map node (e.g. empty) has no unknown keys.
  void CheckNoUnknownKeys() const;

  bool empty() const { return node_.empty() || node_.isNone(); }
  // "file.yaml: harris.max_features" style location, for messages.
  std::string Where(const char* key = nullptr) const;
  const std::string& file() const;
  const cv::FileNode& node() const { return node_; }

 private:
  friend ConfigNode LoadConfigFile(const std::string& path);
  friend ConfigNode ParseConfigString(const std::string& yaml, const std::string& name);

  struct Shared {
    cv::FileStorage storage;  // Keeps the parsed document alive.
    std::string file;
  };
  ConfigNode(std::shared_ptr<Shared> shared, cv::FileNode node, std::string key_path);
  cv::FileNode Lookup(const char* key) const;  // Records the key as known.
  double ReadNumber(const char* key, const cv::FileNode& n, const char* expected) const;

  std::shared_ptr<Shared> shared_;
  cv::FileNode node_;
  std::string key_path_;  // "" at the root, "a.b" below.
  std::shared_ptr<std::set<std::string>> known_ = std::make_shared<std::set<std::string>>();
};

// Opens a YAML file through cv::FileStorage (the "%YAML:1.0" header is optional). Throws
// dala::Error on a missing or unparsable file, or when the top level is not a map.
ConfigNode LoadConfigFile(const std::string& path);
// Same, from text in memory; `name` stands for the file in messages.
ConfigNode ParseConfigString(const std::string& yaml, const std::string& name = "<string>");

}  // namespace dala

#endif  // DALA_CORE_CONFIG_H_
