#include "core/config.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/core.hpp>
#include <sstream>

#include "core/error.h"
#include "core/yaml_single_document.h"

namespace dala {
namespace {

const char* TypeName(const cv::FileNode& n) {
  if (n.isInt() || n.isReal()) return "a number";
  if (n.isString()) return "a string";
  if (n.isSeq()) return "a sequence";
  if (n.isMap()) return "a map";
  return "nothing";
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

ConfigNode CheckedRoot(const ConfigNode& root) {
  if (!root.node().isMap() && !root.empty()) {
    throw Error() << root.file() << ": the top level must be a map of 'key: value' options";
  }
  return root;
}

}  // namespace

ConfigNode::ConfigNode(std::shared_ptr<Shared> shared, cv::FileNode node, std::string key_path)
    : shared_(std::move(shared)), node_(std::move(node)), key_path_(std::move(key_path)) {}

const std::string& ConfigNode::file() const {
  static const std::string kNone = "<no file>";
  return shared_ ? shared_->file : kNone;
}

std::string ConfigNode::Where(const char* key) const {
  std::string where = file() + ": ";
  std::string path = key_path_;
  if (key != nullptr) path += (path.empty() ? "" : ".") + std::string(key);
  return where + (path.empty() ? "<top level>" : "'" + path + "'");
}

cv::FileNode ConfigNode::Lookup(const char* key) const {
  known_->insert(key);
  if (!node_.isMap()) return cv::FileNode();
  return node_[key];
}

bool ConfigNode::Has(const char* key) const {
  if (!node_.isMap()) return false;
  const cv::FileNode n = node_[key];
  return !n.empty() && !n.isNone();
}

double ConfigNode::ReadNumber(const char* key, const cv::FileNode& n, const char* expected) const {
  if (!n.isInt() && !n.isReal()) {
    throw Error() << Where(key) << ": expected " << expected << ", got " << TypeName(n);
  }
  return n.isInt() ? static_cast<double>(static_cast<int>(n)) : static_cast<double>(n);
}

void ConfigNode::Read(const char* key, double* v) const {
  const cv::FileNode n = Lookup(key);
  if (n.empty() || n.isNone()) return;
  *v = ReadNumber(key, n, "a number");
}

void ConfigNode::Read(const char* key, float* v) const {
  double d = *v;
  Read(key, &d);
  *v = static_cast<float>(d);
}

void ConfigNode::Read(const char* key, int64_t* v) const {
  const cv::FileNode n = Lookup(key);
  if (n.empty() || n.isNone()) return;
  if (n.isString()) {
    // cv::FileStorage keeps integers in 32 bits; larger values are written quoted.
    const std::string s = static_cast<std::string>(n);
    size_t used = 0;
    try {
      const long long parsed = std::stoll(s, &used);
      if (used == s.size()) {
        *v = parsed;
        return;
      }
    } catch (const std::exception&) {
    }
    throw Error() << Where(key) << ": expected an integer, got '" << s << "'";
  }
  const double d = ReadNumber(key, n, "an integer");
  // Integers above 2^31 are stored as reals by cv::FileStorage: accept whole values to 2^53.
  if (d != std::floor(d) || std::abs(d) > 9007199254740992.0) {
    throw Error() << Where(key) << ": expected an integer, got " << d;
  }
  *v = static_cast<int64_t>(d);
}

void ConfigNode::Read(const char* key, int* v) const {
  int64_t i = *v;
  Read(key, &i);
  if (i < std::numeric_limits<int>::min() || i > std::numeric_limits<int>::max()) {
    throw Error() << Where(key) << ": " << i << " does not fit in a 32-bit int";
  }
  *v = static_cast<int>(i);
}

void ConfigNode::Read(const char* key, bool* v) const {
  const cv::FileNode n = Lookup(key);
  if (n.empty() || n.isNone()) return;
  if (n.isInt()) {
    const int i = static_cast<int>(n);
    if (i == 0 || i == 1) {
      *v = i == 1;
      return;
    }
  } else if (n.isString()) {
    const std::string s = Lower(static_cast<std::string>(n));
    if (s == "true" || s == "yes" || s == "on") {
      *v = true;
      return;
    }
    if (s == "false" || s == "no" || s == "off") {
      *v = false;
      return;
    }
  }
  throw Error() << Where(key) << ": expected a boolean (true/false), got "
                << (n.isString() ? "'" + static_cast<std::string>(n) + "'" : TypeName(n));
}

void ConfigNode::Read(const char* key, std::string* v) const {
  const cv::FileNode n = Lookup(key);
  if (n.empty() || n.isNone()) return;
  if (!n.isString()) {
    throw Error() << Where(key) << ": expected a string, got " << TypeName(n)
                  << " (quote it: key: \"value\")";
  }
  *v = static_cast<std::string>(n);
}

void ConfigNode::Read(const char* key, std::vector<double>* v) const {
  const cv::FileNode n = Lookup(key);
  if (n.empty() || n.isNone()) return;
  if (!n.isSeq()) {
    throw Error() << Where(key) << ": expected a sequence of numbers [a, b, ...], got "
                  << TypeName(n);
  }
  std::vector<double> values;
  for (const cv::FileNode& item : n) {
    if (!item.isInt() && !item.isReal()) {
      throw Error() << Where(key) << ": expected a sequence of numbers, item " << values.size()
                    << " is " << TypeName(item);
    }
    values.push_back(item.isInt() ? static_cast<double>(static_cast<int>(item))
                                  : static_cast<double>(item));
  }
  *v = std::move(values);
}

ConfigNode ConfigNode::Child(const char* key) const {
  const cv::FileNode n = Lookup(key);
  const std::string path = key_path_.empty() ? key : key_path_ + "." + key;
  if (n.empty() || n.isNone()) return ConfigNode(shared_, cv::FileNode(), path);
  if (!n.isMap()) {
    throw Error() << Where(key) << ": expected a map of options, got " << TypeName(n);
  }
  return ConfigNode(shared_, n, path);
}

void ConfigNode::CheckNoUnknownKeys() const {
  if (!node_.isMap()) return;
  std::vector<std::string> unknown;
  for (const std::string& key : node_.keys()) {
    if (known_->count(key) == 0) unknown.push_back(key);
  }
  if (unknown.empty()) return;
  Error error;
  error << Where() << ": unknown key" << (unknown.size() > 1 ? "s" : "") << " ";
  for (size_t i = 0; i < unknown.size(); ++i) error << (i ? ", " : "") << "'" << unknown[i] << "'";
  error << "; known keys here: ";
  if (known_->empty()) error << "(none)";
  bool first = true;
  for (const std::string& key : *known_) {
    error << (first ? "" : ", ") << key;
    first = false;
  }
  error << ". Fix the spelling or remove the key";
  throw error;
}

ConfigNode LoadConfigFile(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw Error() << "missing config file '" << path << "': check the path";
  }
  std::ifstream is(path);
  if (!is) throw Error() << "cannot read config file '" << path << "': permission?";
  std::ostringstream text;
  text << is.rdbuf();
  return ParseConfigString(text.str(), path);
}

ConfigNode ParseConfigString(const std::string& yaml, const std::string& name) {
  auto shared = std::make_shared<ConfigNode::Shared>();
  shared->file = name;
  CheckSingleYamlDocument(yaml, name);  // OpenCV's parser would hang on what follows a document.
  try {
    // cv::FileStorage recognises YAML text only by its "%YAML:1.0" header; add it when absent
    // (OpenCV's line numbers in parse errors then count it as line 1).
    const std::string text = yaml.rfind("%YAML", 0) == 0 ? yaml : "%YAML:1.0\n" + yaml;
    shared->storage.open(
        text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw Error() << name << ": not valid YAML (" << e.err << ")";
  } catch (const std::exception& e) {
    // OpenCV's parser has bugs of its own: an empty key in a flow map ("{a: 1, : 2}") ends in
    // std::length_error. Whatever it throws, the file is what the user must fix.
    throw Error() << name << ": not valid YAML (OpenCV's parser failed: " << e.what()
                  << "); check the file's syntax, e.g. an empty key";
  }
  if (!shared->storage.isOpened()) throw Error() << name << ": cannot parse as YAML";
  return CheckedRoot(ConfigNode(shared, shared->storage.root(), ""));
}

}  // namespace dala
