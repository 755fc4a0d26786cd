// The schema of a case file (io/case/schema.hpp): its tables are those of docs/case-file.md, and
// its declarations are consistent.
#include "fibra/io/case/schema.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fibra::case_file {
namespace {

const std::filesystem::path kDocs = std::filesystem::path(FIBRA_SOURCE_DIR) / "docs" / "case-file.md";

/// A key table of the docs: the tables of the schema it shows (its `<!-- schema: ... -->` line)
/// and its lines.
struct DocsTable {
  std::string sections;
  int line = 0;  ///< of the marker
  std::string text;
};

std::vector<DocsTable> docs_tables() {
  std::ifstream in(kDocs);
  EXPECT_TRUE(in) << kDocs;
  const std::string open = "<!-- schema: ", close = " -->";
  std::vector<DocsTable> tables;
  std::string line;
  int number = 0;
  bool in_table = false;
  while (std::getline(in, line)) {
    ++number;
    if (line.rfind(open, 0) == 0 && line.size() > open.size() + close.size() &&
        line.compare(line.size() - close.size(), close.size(), close) == 0) {
      tables.push_back({line.substr(open.size(), line.size() - open.size() - close.size()), number, ""});
      in_table = true;
      continue;
    }
    if (in_table && line.rfind("|", 0) == 0) {
      tables.back().text += line + "\n";
    } else {
      in_table = false;
    }
  }
  return tables;
}

TEST(CaseSchema, DocsTablesAreTheSchemas) {
  const std::vector<DocsTable> tables = docs_tables();
  ASSERT_FALSE(tables.empty());
  for (const DocsTable& t : tables) {
    SCOPED_TRACE("docs/case-file.md, line " + std::to_string(t.line) + ": schema " + t.sections);
    EXPECT_EQ(t.text, case_schema_markdown(t.sections));
  }
}

TEST(CaseSchema, DocsShowEveryTableOnce) {
  std::map<std::string, int> shown;
  for (const DocsTable& t : docs_tables()) {
    std::istringstream names(t.sections);
    for (std::string name; names >> name;) ++shown[name];
  }
  for (const SectionSpec& s : case_schema()) EXPECT_EQ(shown[std::string(s.name)], 1) << s.name;
  EXPECT_EQ(shown.size(), case_schema().size());
}

TEST(CaseSchema, KeysAreDeclaredOnce) {
  std::set<std::string_view> sections;
  for (const SectionSpec& s : case_schema()) {
    EXPECT_TRUE(sections.insert(s.name).second) << s.name;
    EXPECT_FALSE(s.keys.empty()) << s.name;
    std::set<std::string_view> names;
    for (std::string_view name : schema_keys(s.name)) EXPECT_TRUE(names.insert(name).second) << s.name << "." << name;
    for (const KeySpec& k : s.keys) {
      EXPECT_FALSE(k.type.empty()) << s.name << "." << k.name;
      EXPECT_EQ(k.default_value.empty(), !s.default_column) << s.name << "." << k.name;
    }
  }
}

TEST(CaseSchema, UnitsAreThoseOfTheMeanings) {
  // A unit is given in brackets in the meaning, and the unit of the key is that one.
  const std::regex unit(R"(\[(m|Pa|N|N m|N/m|rad|degrees)\])");
  for (const SectionSpec& s : case_schema()) {
    for (const KeySpec& k : s.keys) {
      const std::string meaning(k.meaning);
      std::smatch m;
      if (std::regex_search(meaning, m, unit)) {
        EXPECT_EQ(m[1].str(), k.unit) << s.name << "." << k.name;
      } else {
        EXPECT_EQ(k.unit, "") << s.name << "." << k.name;
      }
    }
  }
}

TEST(CaseSchema, VariantsSelectKeys) {
  EXPECT_EQ(schema_keys("material", "isotropic"), (std::vector<std::string_view>{"name", "model", "young", "poisson"}));
  EXPECT_EQ(schema_keys("material", "transverse").size(), 7u);
  EXPECT_EQ(schema_keys("step.load"), (std::vector<std::string_view>{"fiber", "node", "at", "force", "moment"}));
  EXPECT_THROW(schema_section("nonsense"), std::logic_error);
  EXPECT_THROW(schema_key("solver", "nonsense"), std::logic_error);
  EXPECT_EQ(schema_key("solver", "max_iterations").default_value, "`25`");
}

}  // namespace
}  // namespace fibra::case_file
