// docs/options.md against the option table (backend/system_options.cc): every option users tune
// has its row, with the default the code has, in the table of its section; every experimental
// option is listed in the experimental table on its section's row; nothing else is listed.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "backend/system_options.h"
#include "tests/test_util.h"

namespace dala {
namespace {

struct OptionsPage {
  // "section.key" (or "key" at the top level) -> the default column, from the section tables.
  std::map<std::string, std::string> user_defaults;
  // "section.key" listed in the experimental table.
  std::set<std::string> experimental;
};

std::string Section(const std::string& heading) {
  if (heading.rfind("Top level", 0) == 0 || heading == "top level") return "";
  const size_t a = heading.find('`'), b = heading.find('`', a + 1);
  return a == std::string::npos || b == std::string::npos ? "?" : heading.substr(a + 1, b - a - 1);
}

std::string Qualified(const std::string& section, const std::string& key) {
  return section.empty() ? key : section + "." + key;
}

// Cells of a table row "| a | b | c |", trimmed.
std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line.substr(1));
  std::string cell;
  while (std::getline(ss, cell, '|')) {
    const size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  return cells;
}

std::string Unquoted(const std::string& cell) {
  return cell.size() >= 2 && cell.front() == '`' && cell.back() == '`'
             ? cell.substr(1, cell.size() - 2)
             : cell;
}

OptionsPage ReadOptionsPage() {
  OptionsPage page;
  std::istringstream in(testing::ReadAll(std::string(DALA_SOURCE_DIR) + "/docs/options.md"));
  std::string line, heading;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) {
      heading = line.substr(3);
      continue;
    }
    if (line.rfind("| ", 0) != 0 || line.rfind("| key", 0) == 0 ||
        line.rfind("| section", 0) == 0) {
      continue;
    }
    const std::vector<std::string> cells = Cells(line);
    if (heading == "Experimental options") {
      std::stringstream keys(cells.at(1));
      std::string key;
      while (std::getline(keys, key, ',')) {
        key = Unquoted(key.substr(key.find_first_not_of(' ')));
        page.experimental.insert(Qualified(Section(cells[0]), key));
      }
    } else if (cells.size() >= 3 && !cells[0].empty() && cells[0][0] == '`') {
      page.user_defaults[Qualified(Section(heading), Unquoted(cells[0]))] = cells[1];
    }
  }
  return page;
}

// The default of each option, as the JSON of the run report writes it.
const nlohmann::json& DefaultOf(const nlohmann::json& defaults, const std::string& key) {
  const size_t dot = key.find('.');
  return dot == std::string::npos ? defaults.at(key)
                                  : defaults.at(key.substr(0, dot)).at(key.substr(dot + 1));
}

bool SameDefault(const nlohmann::json& value, const std::string& documented) {
  if (value.is_boolean()) return documented == (value.get<bool>() ? "1" : "0");
  if (value.is_string()) return documented == value.get<std::string>();
  char* end = nullptr;
  const double x = std::strtod(documented.c_str(), &end);
  if (documented.empty() || *end != '\0') return false;
  const double v = value.get<double>();
  return std::abs(x - v) <= 1e-9 * std::max(1.0, std::abs(v));
}

TEST(OptionsDocs, EveryOptionUsersTuneHasItsLineAndItsDefault) {
  const OptionsPage page = ReadOptionsPage();
  const std::vector<std::string> user = SystemOptionKeys(OptionSet::kUser);
  // The aim: half of the 150 keys there were.
  EXPECT_LE(user.size(), 75u);
  const nlohmann::json defaults = SystemOptionsToJson(SystemOptions());
  for (const std::string& key : user) {
    const auto row = page.user_defaults.find(key);
    ASSERT_NE(row, page.user_defaults.end()) << key << " has no row in docs/options.md";
    EXPECT_TRUE(SameDefault(DefaultOf(defaults, key), row->second))
        << key << ": docs/options.md says " << row->second << ", the code "
        << DefaultOf(defaults, key);
  }
  const std::set<std::string> user_set(user.begin(), user.end());
  for (const auto& [key, value] : page.user_defaults) {
    EXPECT_TRUE(user_set.count(key)) << "docs/options.md lists " << key
                                     << " as an option users tune; the code does not";
  }
}

TEST(OptionsDocs, EveryExperimentalOptionIsListedAsSuch) {
  const OptionsPage page = ReadOptionsPage();
  const std::vector<std::string> all = SystemOptionKeys(OptionSet::kAll);
  const std::vector<std::string> user = SystemOptionKeys(OptionSet::kUser);
  const std::set<std::string> user_set(user.begin(), user.end());
  std::set<std::string> experimental;
  for (const std::string& key : all) {
    if (!user_set.count(key)) experimental.insert(key);
  }
  for (const std::string& key : experimental) {
    EXPECT_TRUE(page.experimental.count(key))
        << key << " is missing from docs/options.md's experimental table";
  }
  for (const std::string& key : page.experimental) {
    EXPECT_TRUE(experimental.count(key))
        << "docs/options.md lists " << key << " as experimental; the code does not";
  }
}

// --dump_config shows the options users tune, and an experimental one only when it is set away
// from its default, so that the dump loads back to the same options.
TEST(OptionsDocs, TheDumpShowsExperimentalOptionsOnlyWhenSet) {
  SystemOptions options;
  const std::string plain = SystemOptionsToYaml(options);
  EXPECT_EQ(plain.find("landmark_exit"), std::string::npos) << plain;
  EXPECT_NE(plain.find("window_size"), std::string::npos) << plain;
  EXPECT_NE(SystemOptionsToYaml(options, OptionSet::kAll).find("landmark_exit"),
            std::string::npos);
  SetSystemOption("ba.landmark_exit=marginalize_all", &options);
  const std::string set = SystemOptionsToYaml(options);
  EXPECT_NE(set.find("landmark_exit: \"marginalize_all\""), std::string::npos) << set;

  const std::string path = ::testing::TempDir() + "/dumped_options.yaml";
  {
    std::ofstream out(path);
    out << set;
  }
  SystemOptions loaded;
  LoadSystemOptions(path, &loaded);
  EXPECT_EQ(SystemOptionsToJson(loaded), SystemOptionsToJson(options));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace dala
