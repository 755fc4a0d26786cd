// The schema of a case file (io/case/schema.hpp): its tables are those of docs/case-file.md, and
// its declarations are consistent.
#include "fibra/io/case/schema.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/case.hpp"
#include "support/scratch_dir.hpp"

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

TEST(CaseSchema, DocsAreWhatTheSchemaMakes) {
  // The whole file, as case_schema_docs would rewrite it (build/src/fibra/io/case_schema_docs
  // docs/case-file.md).
  std::ifstream in(kDocs, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  EXPECT_TRUE(with_case_schema_tables(text.str()) == text.str())
      << "docs/case-file.md differs from the schema: run case_schema_docs docs/case-file.md";
  // The rewriting replaces a table whole and keeps the rest.
  EXPECT_EQ(with_case_schema_tables("a\n<!-- schema: weave -->\n| old |\n|---|\n\nb"),
            "a\n<!-- schema: weave -->\n" + case_schema_markdown("weave") + "\nb");
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

TEST(CaseSchema, RequiredKeysSayWhatTheyExpect) {
  // A key that is always required declares what the reader's message expects of it, and a unit
  // that message gives is the key's.
  const std::regex unit(R"(\[(m|Pa|N|N m|N/m|rad|degrees)\])");
  int required = 0;
  for (const SectionSpec& s : case_schema()) {
    for (const KeySpec& k : s.keys) {
      if (k.default_value == "required" || k.default_value == "required, at least 1") {
        ++required;
        EXPECT_FALSE(k.expected.empty()) << s.name << "." << k.name;
      }
      const std::string expected(k.expected);
      std::smatch m;
      if (std::regex_search(expected, m, unit)) {
        EXPECT_EQ(m[1].str(), k.unit) << s.name << "." << k.name;
      }
    }
  }
  EXPECT_GE(required, 25);
}

TEST(CaseSchema, AMissingKeyIsReportedWithTheSchemasText) {
  const std::string text =
      "[[material]]\nname = \"glass\"\npoisson = 0.2\n\n[[fiber]]\nname = \"f\"\nmaterial = \"glass\"\n"
      "radius = 1e-4\npoints = [[0, 0, 0], [1e-3, 0, 0]]\nelements = 2\n\n[[step]]\nname = \"s\"\n";
  try {
    parse_case_toml(text, "case.toml");
    FAIL() << "a material without young was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material[0].young");
    EXPECT_NE(std::string(e.what()).find(fmt::format("(expected {})", schema_key("material", "young").expected)),
              std::string::npos)
        << e.what();
  }
}

TEST(CaseSchema, FuzzDictionaryHoldsEveryKeyAndWord) {
  // The case readers' fuzz harnesses start from every key and word of the schema.
  std::ifstream in(std::string(FIBRA_SOURCE_DIR) + "/fuzz/case.dict");
  ASSERT_TRUE(in) << "fuzz/case.dict";
  std::set<std::string> tokens;
  for (std::string line; std::getline(in, line);)
    if (line.size() >= 2 && line.front() == '"' && line.back() == '"') tokens.insert(line.substr(1, line.size() - 2));
  for (const SectionSpec& s : case_schema()) {
    for (const KeySpec& k : s.keys) {
      EXPECT_TRUE(tokens.count(std::string(k.name))) << s.name << "." << k.name;
      for (const std::string_view word : k.choices) EXPECT_TRUE(tokens.count(std::string(word))) << s.name << "." << k.name << ": " << word;
    }
  }
}

TEST(CaseSchema, ChoicesAreThoseAllowed) {
  // The words a string key may be are each in its Allowed text, quoted, in backticks.
  std::size_t keys = 0;
  for (const SectionSpec& s : case_schema()) {
    for (const KeySpec& k : s.keys) {
      if (k.choices.empty()) continue;
      ++keys;
      EXPECT_EQ(k.type, "string") << s.name << "." << k.name;
      for (std::string_view word : k.choices)
        EXPECT_NE(k.allowed.find(fmt::format("`\"{}\"`", word)), std::string_view::npos) << s.name << "." << k.name;
    }
  }
  EXPECT_GE(keys, 7u);
  EXPECT_EQ(schema_choices("solver", "krylov_precision"), (std::vector<std::string_view>{"auto", "single", "half", "double"}));
}

TEST(CaseSchema, VariantsSelectKeys) {
  EXPECT_EQ(schema_keys("material", "isotropic"), (std::vector<std::string_view>{"name", "model", "young", "poisson"}));
  EXPECT_EQ(schema_keys("material", "transverse").size(), 7u);
  EXPECT_EQ(schema_keys("step.load"), (std::vector<std::string_view>{"fiber", "node", "at", "force", "moment"}));
  EXPECT_THROW(schema_section("nonsense"), std::logic_error);
  EXPECT_THROW(schema_key("solver", "nonsense"), std::logic_error);
  EXPECT_EQ(schema_key("solver", "max_iterations").default_value, "`25`");
}

// -- the reader and the schema --------------------------------------------------------------

/// The value of a case's struct (model/case.hpp) that the key `section.name` leaves when it is
/// not given, for the schema's plain number keys.
std::map<std::string, double> case_defaults() {
  const SolverSpec solver;
  const ContactSpec contact;
  const OutputSpec output;
  const StepSpec step;
  return {
      {"solver.residual_tolerance", solver.residual_tolerance},
      {"solver.displacement_tolerance", solver.displacement_tolerance},
      {"solver.max_iterations", solver.max_iterations},
      {"solver.max_cuts", solver.max_cuts},
      {"solver.binding_tolerance", solver.binding_tolerance},
      {"solver.max_binding_updates", solver.max_binding_updates},
      {"contact.friction", contact.friction},
      {"contact.elastic_slip", contact.elastic_slip},
      {"contact.stiffness", contact.stiffness},
      {"contact.margin", contact.margin},
      {"contact.spacing", contact.spacing},
      {"contact.self_exclusion", contact.self_exclusion},
      {"contact.max_detections", contact.max_detections},
      {"contact.max_normal_updates", contact.max_normal_updates},
      {"contact.normal_tolerance", contact.normal_tolerance},
      {"output.every", output.every},
      {"output.tube_sides", output.tube_sides},
      {"step.increments", step.increments},
  };
}

TEST(CaseSchema, DefaultsAreThoseOfTheCase) {
  const std::map<std::string, double> defaults = case_defaults();
  std::size_t bounded = 0;
  for (const SectionSpec& s : case_schema()) {
    for (const KeySpec& k : s.keys) {
      if (!k.bounded()) continue;
      ++bounded;
      const std::string key = fmt::format("{}.{}", s.name, k.name);
      const auto it = defaults.find(key);
      ASSERT_NE(it, defaults.end()) << key << ": a plain number key the case's structs do not hold";
      EXPECT_EQ(k.number_default, it->second) << key;
      // The docs show the same default: the number first, in backticks.
      ASSERT_EQ(k.default_value.substr(0, 1), "`") << key;
      EXPECT_EQ(std::strtod(std::string(k.default_value.substr(1)).c_str(), nullptr), k.number_default) << key;
      EXPECT_TRUE(k.exclusive ? k.number_default > k.minimum : k.number_default >= k.minimum) << key;
    }
  }
  EXPECT_EQ(bounded, defaults.size());
}

/// The settings tables with every key, the plain number keys at their defaults (one of them,
/// `override_key` = "section.name", at `value` instead).
std::string settings(const std::string& override_key = "", const std::string& value = "") {
  // The other keys, at values of their own.
  const std::map<std::string, std::string> others = {
      {"solver", "linear_solver = \"eigen\"\nkrylov_precision = \"double\"\n"},
      {"contact", "max_penetration = 0.1\nregularization = 1\n"},
      {"output", "plots = false\ntest_levels = false\ncheckpoint = \"10 min\"\n"},
  };
  std::string out;
  for (const char* section : {"solver", "contact", "output"}) {
    out += fmt::format("\n[{}]\n", section) + others.at(section);
    for (const KeySpec& k : schema_section(section).keys) {
      const std::string key = fmt::format("{}.{}", section, k.name);
      if (key == override_key) {
        out += fmt::format("{} = {}\n", k.name, value);
      } else if (k.bounded()) {
        out += fmt::format("{} = {}\n", k.name, k.number_default);
      }
    }
  }
  return out;
}

/// Cases that together give every key of the schema a valid value: a model of fibers with every
/// section and path, tows and a weave (its pattern or, with `matrix`, its matrix).
std::string fiber_case(bool matrix) {
  return fmt::format(R"(title = "every key"

[[material]]
name = "steel"
model = "isotropic"
young = 210e9
poisson = 0.3

[[material]]
name = "carbon"
model = "transverse"
young = 230e9
poisson = 0.2
young_transverse = 15e9
shear_axial = 20e9
poisson_transverse = 0.4

[[fiber]]
name = "a"
material = "steel"
radius = 0.01
section_direction = [0, 1, 0]
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[fiber]]
name = "b"
material = "carbon"
semi_axes = [0.01, 0.005]
arc = {{ center = [0, 0, 1], axis = [0, 0, 1], radius = 1, start_angle = 10, angle = 90 }}
elements = 4

[[fiber]]
name = "c"
material = "steel"
radius = 0.01
helix = {{ center = [0, 0, 5], axis = [0, 0, 1], radius = 1, pitch = 0.5, turns = 1, start_angle = 10 }}
elements = 8

[[fix]]
fiber = "a"
node = "first"
dofs = "all"

[[fix]]
fiber = "b"
at = 0.0
dofs = ["x", "g1"]

[[body]]
name = "B"
center = [2, 0, 0]
axes = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]

[[body]]
name = "C"
center = [3, 0, 0]

[[binding]]
body = "B"
ends = [{{ fiber = "a", node = "last" }}, {{ fiber = "c", at = 1.0 }}]
bodies = ["C"]
grip = [2]
spin = true

[[tow]]
name = "t0"
direction = "warp"
index = 0
fibers = ["a"]

[[tow]]
name = "t1"
direction = "weft"
index = 0
fibers = ["b"]

[weave]
{}

[[step]]
name = "load"
kind = "load"
increments = 2
max_increments = 10

[[step.load]]
fiber = "a"
node = 4
force = [0, 0, -1]
moment = [0, 0, 0.5]

[[step.displacement]]
fiber = "c"
node = "last"
value = [0, "free", 0.001]

[[step.load]]
fiber = "b"
at = 0.5
force = [1, 0, 0]

[[step.displacement]]
fiber = "a"
at = 0.5
value = ["free", 0, "free"]

[[step.body]]
name = "B"
displacement = [0.001, "free", "free"]
rotation = [0, 0, "free"]
force = [0, 1, 0]
moment = [0, 0, 1]

[[step]]
name = "w"
kind = "weave"

[[step]]
name = "r"
kind = "relax"
tolerance = 1e-3
{})",
                     matrix ? "matrix = [[1, 0], [0, 1]]" : "pattern = \"plain\"", settings());
}

/// A woven fabric with its shared and per-direction tables, and the test steps.
std::string fabric_case(bool matrix) {
  return fmt::format(R"([[material]]
name = "glass"
young = 72e9
poisson = 0.22

[fabric]
{}
warp = {{ tows = 2, spacing = 1.0e-3, tow = {{ fibers = 3 }}, fiber = {{ radius = 5.0e-5 }} }}
weft = {{ tows = 2, spacing = 1.0e-3 }}
margin = 0.5e-3
tension = 0.05
grip = "width"

[fabric.tow]
fibers = 3
width = 0.7e-3
thickness = 0.25e-3

[fabric.fiber]
radius = 5.0e-5
material = "glass"
element_length = 2.5e-4

[[step]]
name = "pull"
kind = "biaxial"
strain = 0.01
ratio = 0.5
tolerance = 1e-3

[[step]]
name = "shear"
kind = "shear"
angle = 10
height = "free"
)",
                     matrix ? "matrix = [[1, 0], [0, 1]]" : "pattern = \"plain\"");
}

/// The (table, key) pairs of the schema a case file's text gives, its array indices left out:
/// `fiber[1].arc.radius` gives (fiber, arc) and (fiber.arc, radius).
std::set<std::pair<std::string, std::string>> keys_given(const std::string& text) {
  std::set<std::pair<std::string, std::string>> out;
  for (const auto& [path, value] : case_file_keys(text, false, "keys.toml")) {
    std::vector<std::string> parts;
    std::istringstream in(path);
    for (std::string part; std::getline(in, part, '.');) {
      const std::size_t bracket = part.find('[');
      if (bracket != 0) parts.push_back(part.substr(0, bracket));
    }
    std::string section = "top";
    for (const std::string& part : parts) {
      out.insert({section, part});
      if (section == "fabric" && (part == "warp" || part == "weft")) {
        section = "fabric.direction";
      } else if (section == "fabric.direction") {
        section = "fabric." + part;
      } else if (section == "binding" && part == "ends") {
        section = "node";
      } else {
        section = section == "top" ? part : section + "." + part;
      }
    }
  }
  return out;
}

class CaseSchemaFiles : public test::ScratchDirTest {
 protected:
  CaseSchemaFiles() : ScratchDirTest("case_schema_") {}
};

TEST_F(CaseSchemaFiles, EveryKeyIsRead) {
  // An earlier run to go on from: its case file and the state at the end of its step "load".
  const std::filesystem::path run = m_dir / "run";
  std::filesystem::create_directories(run / "state");
  std::ofstream(run / "case.toml") << fiber_case(false);
  std::ofstream(run / "state" / (step_file_stem("load") + ".bin")) << "state";
  const std::string continued = fmt::format(R"([start]
from = "{}"
step = "load"

[[step]]
name = "more"
)",
                                            run.string());
  const std::vector<std::string> cases = {fiber_case(false), fiber_case(true), fabric_case(false), fabric_case(true),
                                          continued};
  std::set<std::pair<std::string, std::string>> given;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i]);
    EXPECT_NO_THROW(parse_case_toml(cases[i], (m_dir / fmt::format("case{}.toml", i)).string()));
    const auto keys = keys_given(cases[i]);
    given.insert(keys.begin(), keys.end());
  }
  for (const SectionSpec& s : case_schema()) {
    for (std::string_view name : schema_keys(s.name)) {
      EXPECT_EQ(given.count({std::string(s.name), std::string(name)}), 1u)
          << s.name << "." << name << ": in the schema, in none of the cases read";
    }
  }
  for (const auto& [section, name] : given) {
    const std::vector<std::string_view> known = schema_keys(section);
    EXPECT_NE(std::find(known.begin(), known.end(), name), known.end())
        << section << "." << name << ": read, not in the schema";
  }
}

TEST(CaseSchema, StartTakesNoModelKey) {
  // The top level's model keys are refused in a case with [start], each named; the others pass
  // that check (and fail later, at [start].from, which names no run here).
  std::size_t model = 0;
  for (const KeySpec& k : schema_section("top").keys) {
    if (k.name == "start" || k.name == "step") continue;
    const std::string text = fmt::format("{} = 1\n\n[start]\nfrom = \"nowhere\"\n", k.name);
    try {
      parse_case_toml(text, "start.toml");
      ADD_FAILURE() << text << " is accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      const bool named = message.find(fmt::format("start.toml: {}: a case with [start] takes its model", k.name)) !=
                         std::string::npos;
      EXPECT_EQ(named, k.variant == "model") << message;
      model += named ? 1 : 0;
    }
  }
  EXPECT_EQ(model, 8u);
}

TEST(CaseSchema, ReaderChecksTheMinimums) {
  // Each plain number key of the settings just below its minimum: refused, naming the key.
  for (const char* section : {"solver", "contact", "output"}) {
    for (const KeySpec& k : schema_section(section).keys) {
      if (!k.bounded()) continue;
      const std::string key = fmt::format("{}.{}", section, k.name);
      const bool integer = k.type == "integer";
      const std::string below = k.exclusive ? fmt::format("{}", k.minimum)
                                : integer   ? fmt::format("{}", k.minimum - 1)
                                            : fmt::format("{}", k.minimum - 1e-3);
      const std::string text = fiber_case(false);
      const std::string bad = text.substr(0, text.find("\n[solver]")) + settings(key, below);
      try {
        parse_case_toml(bad, "minimum.toml");
        ADD_FAILURE() << key << " = " << below << " is accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("minimum.toml: " + key + ": "), std::string::npos) << e.what();
      }
      // At its minimum, or just above when it is excluded: accepted.
      const std::string at = k.exclusive ? fmt::format("{}", k.minimum + 1e-6) : fmt::format("{}", k.minimum);
      EXPECT_NO_THROW(parse_case_toml(text.substr(0, text.find("\n[solver]")) + settings(key, at), "minimum.toml"))
          << key << " = " << at;
    }
  }
}

}  // namespace
}  // namespace fibra::case_file
