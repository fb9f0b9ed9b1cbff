#include "core/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

struct HarrisLikeOptions {
  int max_features = 500;
  double sigma = 1.0;
  float threshold = 0.01f;
  bool subpixel = true;
  std::string mode = "fast";
  int64_t seed = 42;
  std::vector<double> weights = {1, 2};
};

void ReadHarris(const ConfigNode& node, HarrisLikeOptions* o) {
  node.Read("max_features", &o->max_features);
  node.Read("sigma", &o->sigma);
  node.Read("threshold", &o->threshold);
  node.Read("subpixel", &o->subpixel);
  node.Read("mode", &o->mode);
  node.Read("seed", &o->seed);
  node.Read("weights", &o->weights);
  node.CheckNoUnknownKeys();
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(Config, ReadsValuesAndKeepsDefaultsForAbsentKeys) {
  TempDir dir;
  {
    std::ofstream os(dir / "run.yaml");
    os << "%YAML:1.0\nharris:\n  max_features: 800\n  sigma: 1.5\n  subpixel: false\n"
          "  mode: \"exact\"\n  seed: \"5000000000\"\n  weights: [0.5, 3]\nverbose: 1\n";
  }
  const ConfigNode root = LoadConfigFile(dir / "run.yaml");
  HarrisLikeOptions o;
  ReadHarris(root.Child("harris"), &o);
  bool verbose = false;
  root.Read("verbose", &verbose);
  root.CheckNoUnknownKeys();
  EXPECT_EQ(o.max_features, 800);
  EXPECT_EQ(o.sigma, 1.5);
  EXPECT_FLOAT_EQ(o.threshold, 0.01f);  // Default kept.
  EXPECT_FALSE(o.subpixel);
  EXPECT_EQ(o.mode, "exact");
  EXPECT_EQ(o.seed, 5000000000LL);
  EXPECT_EQ(o.weights, (std::vector<double>{0.5, 3.0}));
  EXPECT_TRUE(verbose);
}

TEST(Config, AbsentChildKeepsAllDefaults) {
  const ConfigNode root = ParseConfigString("%YAML:1.0\nother: 1\n");
  HarrisLikeOptions o;
  const ConfigNode harris = root.Child("harris");
  EXPECT_TRUE(harris.empty());
  ReadHarris(harris, &o);
  EXPECT_EQ(o.max_features, 500);
  EXPECT_EQ(o.mode, "fast");
  root.Read("other", &o.max_features);
  EXPECT_EQ(o.max_features, 1);
}

TEST(Config, HeaderIsOptional) {
  TempDir dir;
  {
    std::ofstream os(dir / "plain.yaml");
    os << "a: 2.5\nb: yes\n";
  }
  for (const ConfigNode& root :
       {ParseConfigString("a: 2.5\nb: yes\n"), LoadConfigFile(dir / "plain.yaml")}) {
    double a = 0;
    bool b = false;
    root.Read("a", &a);
    root.Read("b", &b);
    EXPECT_EQ(a, 2.5);
    EXPECT_TRUE(b);
  }
}

TEST(Config, UnknownKeyNamesFileKeyAndKnownKeys) {
  const ConfigNode root =
      ParseConfigString("%YAML:1.0\nharris:\n  max_feature: 800\n  sigma: 2\n", "cfg.yaml");
  HarrisLikeOptions o;
  const std::string msg = ErrorOf([&] { ReadHarris(root.Child("harris"), &o); });
  EXPECT_THAT(msg, HasSubstr("cfg.yaml"));
  EXPECT_THAT(msg, HasSubstr("'harris'"));
  EXPECT_THAT(msg, HasSubstr("'max_feature'"));
  EXPECT_THAT(msg, HasSubstr("max_features"));  // In the list of known keys.
  EXPECT_THAT(msg, HasSubstr("sigma"));
}

TEST(Config, UnknownTopLevelSectionIsRejected) {
  const ConfigNode root = ParseConfigString("%YAML:1.0\nharis:\n  sigma: 2\n", "cfg.yaml");
  HarrisLikeOptions o;
  ReadHarris(root.Child("harris"), &o);
  EXPECT_THAT(ErrorOf([&] { root.CheckNoUnknownKeys(); }), HasSubstr("unknown key 'haris'"));
}

TEST(Config, WrongTypesAreErrorsWithLocation) {
  const ConfigNode root = ParseConfigString(
      "%YAML:1.0\nn: \"many\"\nf: 1.5\nb: maybe\ns: 3\nv: 4\nm: 3\nq: \"12x\"\n", "c.yaml");
  int n = 0;
  bool b = false;
  std::string s;
  std::vector<double> v;
  EXPECT_THAT(ErrorOf([&] { root.Read("n", &n); }), HasSubstr("c.yaml: 'n': expected an integer"));
  EXPECT_THAT(ErrorOf([&] { root.Read("f", &n); }), HasSubstr("expected an integer, got 1.5"));
  EXPECT_THAT(ErrorOf([&] { root.Read("b", &b); }), HasSubstr("expected a boolean"));
  EXPECT_THAT(ErrorOf([&] { root.Read("s", &s); }), HasSubstr("expected a string"));
  EXPECT_THAT(ErrorOf([&] { root.Read("v", &v); }), HasSubstr("expected a sequence"));
  EXPECT_THAT(ErrorOf([&] { root.Child("m"); }), HasSubstr("expected a map"));
  int64_t q = 0;
  EXPECT_THAT(ErrorOf([&] { root.Read("q", &q); }), HasSubstr("expected an integer, got '12x'"));
  EXPECT_EQ(n, 0);  // Untouched on error.
}

// Found by bench_suite_fuzzer: an empty key in a flow map makes OpenCV's parser throw
// std::length_error, which no dala::Error handler caught (every YAML reader aborted).
TEST(Config, OpenCvParserFailureIsAnError) {
  for (const char* text : {"{a: 1, : y}", "- {name: x, : y}\n"}) {
    EXPECT_THAT(ErrorOf([&] { ParseConfigString(text, "suite.yaml"); }),
                HasSubstr("suite.yaml: not valid YAML")) << text;
  }
}

TEST(Config, MissingAndInvalidFiles) {
  TempDir dir;
  EXPECT_THAT(ErrorOf([&] { LoadConfigFile(dir / "nope.yaml"); }),
              HasSubstr("missing config file"));
  {
    std::ofstream os(dir / "bad.yaml");
    os << "%YAML:1.0\na: [1, 2\nb: {c: \n";
  }
  EXPECT_THAT(ErrorOf([&] { LoadConfigFile(dir / "bad.yaml"); }), HasSubstr("bad.yaml"));
  {
    std::ofstream os(dir / "seq.yaml");
    os << "%YAML:1.0\n- 1\n- 2\n";
  }
  EXPECT_THAT(ErrorOf([&] { LoadConfigFile(dir / "seq.yaml"); }), HasSubstr("must be a map"));
}


// Found by bench_suite_fuzzer: once the first document's root ends before the end of the text,
// OpenCV 4.6's parser looks for a second document and loops forever on a '-' that does not start
// "---" (core/yaml_single_document.h). Each text runs in a child process with an alarm, so a hang
// fails the test instead of stalling the suite.
TEST(ConfigDeathTest, TextAfterTheFirstDocumentIsAnErrorNotAHang) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" L:0\n-:\n-", "line 2: indented by 0 where the document (line 1) is indented by 1"},
      {"a: 1\n...\n-\n", "line 3: text after the end of the document on line 2"},
      {"a: 1\n---\n-\n", "line 3: text after the end of the document on line 2"},
      {"a: 1\n... -\n", "line 2: text after a document marker"},
      {"  a: 1\n  b: 2\nc: 3\n-\n", "line 3: indented by 0"},
  };
  for (const auto& [text, expected] : cases) {
    EXPECT_EXIT(
        {
          alarm(20);
          try {
            ParseConfigString(text, "suite.yaml");
          } catch (const Error& e) {
            const std::string what = e.what();
            const bool ok = what.find("suite.yaml: " + expected) != std::string::npos &&
                            what.find("one YAML document per file") != std::string::npos;
            if (!ok) std::cerr << what;
            std::_Exit(ok ? 0 : 2);
          }
          std::_Exit(3);
        },
        ::testing::ExitedWithCode(0), "")
        << text;
  }
}

TEST(Config, SingleDocumentsInEveryLayoutStillParse) {
  const std::vector<std::string> texts = {
      "%YAML:1.0\n---\na: 1\nb: [1,\n  2]\n",                      // Header, marker, flow value.
      "# comment\n  a: 1\n# comment at column 0\n  b: 2\n",         // Indented root.
      "a: 1\nb:\n  c: 2\n...\n\n# trailing comment\n",               // Explicit end, nothing after.
      "b: \"#}\"\na: 1\r\n",                                          // Quotes and CRLF.
  };
  for (const std::string& text : texts) {
    int a = 0;
    EXPECT_NO_THROW(ParseConfigString(text, "ok.yaml").Read("a", &a)) << text;
    EXPECT_EQ(a, 1) << text;
  }
}

}  // namespace
}  // namespace dala
