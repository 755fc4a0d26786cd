#include "fibra/io/case_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <toml++/toml.h>
#include <vector>

#include "fibra/core/error.hpp"

namespace fibra {
namespace {

constexpr double kPi = std::numbers::pi;
const std::string kFile = "cases/demo.toml";

/// A valid case touching every part of the schema.
const std::string kBase = R"(title = "Cantilever under a tip load"

[[material]]
name = "steel"
model = "isotropic"
young = 210e9
poisson = 0.3

[[material]]
name = "fibre"
model = "transverse"
young = 230e9
poisson = 0.2
young_transverse = 15e9
shear_axial = 25e9
poisson_transverse = 0.4

[[fiber]]
name = "beam"
material = "steel"
radius = 0.01
section_direction = [0, 2, 0]
points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]
elements = 20

[[fiber]]
name = "ring"
material = "fibre"
semi_axes = [0.002, 0.001]
arc = { center = [0, 0, 1], axis = [0, 0, 2], radius = 0.5, start_angle = 90, angle = -180 }
elements = 8

[[fiber]]
name = "spring"
material = "steel"
radius = 0.001
helix = { center = [1, 1, 0], axis = [0, 3, 0], radius = 0.05, pitch = 0.02, turns = 3.5 }
elements = 30

[[fix]]
fiber = "beam"
node = "first"
dofs = "all"

[[fix]]
fiber = "ring"
node = 0
dofs = "position"

[[fix]]
fiber = "spring"
at = 0.5
dofs = "sections"

[[step]]
name = "load"
increments = 10
max_increments = 200

  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -1000]
  moment = [1, 2, 3]

  [[step.displacement]]
  fiber = "ring"
  node = 16
  value = [0.01, 0, "free"]

[[step]]
  [[step.load]]
  fiber = "spring"
  at = 1
  moment = [0, 0, 5]

[solver]
residual_tolerance = 1e-6
displacement_tolerance = 1e-9
max_iterations = 30
max_cuts = 5
line_search = false
linear_solver = "eigen"

[output]
every = 2
tube_sides = 16
)";

/// The smallest valid case: everything else takes its default.
const std::string kMinimal = R"(
[[material]]
name = "steel"
young = 2e11
poisson = 0.3

[[fiber]]
name = "beam"
material = "steel"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[step]]
)";

/// `text` with the single occurrence of `from` replaced by `to`.
std::string replace_once(const std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "not found in the base case: " << from;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "found twice in the base case: " << from;
  if (at == std::string::npos) return text;
  std::string out = text;
  out.replace(at, from.size(), to);
  return out;
}

/// The same document as JSON (tables become objects, arrays of tables arrays of objects).
std::string to_json(const std::string& toml_text) {
  std::ostringstream out;
  out << toml::json_formatter{toml::parse(toml_text)};
  return out.str();
}

void expect_vec(const Vec3& actual, const Vec3& expected) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(actual[i], expected[i], 1e-14) << "component " << i;
}

void expect_same_node(const NodeRef& a, const NodeRef& b) {
  EXPECT_EQ(a.fiber, b.fiber);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.index, b.index);
  EXPECT_DOUBLE_EQ(a.fraction, b.fraction);
}

/// Checks two cases hold the same data (except file and name).
void expect_same_case(const Case& a, const Case& b) {
  EXPECT_EQ(a.title, b.title);
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (std::size_t i = 0; i < a.materials.size(); ++i) {
    const MaterialSpec& x = a.materials[i];
    const MaterialSpec& y = b.materials[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.model, y.model);
    EXPECT_DOUBLE_EQ(x.young, y.young);
    EXPECT_DOUBLE_EQ(x.poisson, y.poisson);
    EXPECT_DOUBLE_EQ(x.young_transverse, y.young_transverse);
    EXPECT_DOUBLE_EQ(x.shear_axial, y.shear_axial);
    EXPECT_DOUBLE_EQ(x.poisson_transverse, y.poisson_transverse);
  }
  ASSERT_EQ(a.fibers.size(), b.fibers.size());
  for (std::size_t i = 0; i < a.fibers.size(); ++i) {
    const FiberSpec& x = a.fibers[i];
    const FiberSpec& y = b.fibers[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.material, y.material);
    EXPECT_DOUBLE_EQ(x.radius, y.radius);
    EXPECT_DOUBLE_EQ(x.semi_axis_1, y.semi_axis_1);
    EXPECT_DOUBLE_EQ(x.semi_axis_2, y.semi_axis_2);
    ASSERT_EQ(x.section_direction.has_value(), y.section_direction.has_value());
    if (x.section_direction) expect_vec(*x.section_direction, *y.section_direction);
    EXPECT_EQ(x.elements, y.elements);
    EXPECT_EQ(x.path.kind, y.path.kind);
    ASSERT_EQ(x.path.points.size(), y.path.points.size());
    for (std::size_t k = 0; k < x.path.points.size(); ++k) expect_vec(x.path.points[k], y.path.points[k]);
    expect_vec(x.path.center, y.path.center);
    expect_vec(x.path.axis, y.path.axis);
    EXPECT_DOUBLE_EQ(x.path.radius, y.path.radius);
    EXPECT_DOUBLE_EQ(x.path.start_angle, y.path.start_angle);
    EXPECT_DOUBLE_EQ(x.path.angle, y.path.angle);
    EXPECT_DOUBLE_EQ(x.path.pitch, y.path.pitch);
    EXPECT_DOUBLE_EQ(x.path.turns, y.path.turns);
  }
  ASSERT_EQ(a.fixes.size(), b.fixes.size());
  for (std::size_t i = 0; i < a.fixes.size(); ++i) {
    expect_same_node(a.fixes[i].node, b.fixes[i].node);
    EXPECT_EQ(a.fixes[i].dofs, b.fixes[i].dofs);
    EXPECT_EQ(a.fixes[i].sections(), b.fixes[i].sections());
  }
  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    const StepSpec& x = a.steps[i];
    const StepSpec& y = b.steps[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.increments, y.increments);
    EXPECT_EQ(x.max_increments, y.max_increments);
    ASSERT_EQ(x.loads.size(), y.loads.size());
    for (std::size_t k = 0; k < x.loads.size(); ++k) {
      expect_same_node(x.loads[k].node, y.loads[k].node);
      expect_vec(x.loads[k].force, y.loads[k].force);
      expect_vec(x.loads[k].moment, y.loads[k].moment);
    }
    ASSERT_EQ(x.displacements.size(), y.displacements.size());
    for (std::size_t k = 0; k < x.displacements.size(); ++k) {
      expect_same_node(x.displacements[k].node, y.displacements[k].node);
      EXPECT_EQ(x.displacements[k].value, y.displacements[k].value);
    }
  }
  EXPECT_DOUBLE_EQ(a.solver.residual_tolerance, b.solver.residual_tolerance);
  EXPECT_DOUBLE_EQ(a.solver.displacement_tolerance, b.solver.displacement_tolerance);
  EXPECT_EQ(a.solver.max_iterations, b.solver.max_iterations);
  EXPECT_EQ(a.solver.max_cuts, b.solver.max_cuts);
  EXPECT_EQ(a.solver.line_search, b.solver.line_search);
  EXPECT_EQ(a.solver.linear_solver, b.solver.linear_solver);
  EXPECT_EQ(a.output.every, b.output.every);
  EXPECT_EQ(a.output.tube_sides, b.output.tube_sides);
}

/// Runs `parse` and checks it throws an InputError naming `file`, `key` and `fragment`.
template <class Parse>
void expect_input_error(Parse parse, const std::string& file, const std::string& key,
                        const std::string& fragment) {
  try {
    parse();
    ADD_FAILURE() << "no InputError; expected one for key " << key;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), file) << what;
    EXPECT_EQ(e.key(), key) << what;
    EXPECT_EQ(what.rfind(file + ": " + key + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << "missing \"" << fragment << "\" in: " << what;
  }
}

void expect_toml_error(const std::string& text, const std::string& key, const std::string& fragment) {
  expect_input_error([&] { parse_case_toml(text, kFile); }, kFile, key, fragment);
}

void expect_json_error(const std::string& text, const std::string& key, const std::string& fragment) {
  expect_input_error([&] { parse_case_json(text, "demo.json"); }, "demo.json", key, fragment);
}

// ------------------------------------------------------------------------------------------
// Good input.

TEST(CaseReader, ParsesEveryPartOfTheSchema) {
  const Case c = parse_case_toml(kBase, kFile);
  EXPECT_EQ(c.file, kFile);
  EXPECT_EQ(c.name, "demo");
  EXPECT_EQ(c.title, "Cantilever under a tip load");

  ASSERT_EQ(c.materials.size(), 2u);
  EXPECT_EQ(c.materials[0].name, "steel");
  EXPECT_EQ(c.materials[0].model, MaterialSpec::Model::Isotropic);
  EXPECT_DOUBLE_EQ(c.materials[0].young, 210e9);
  EXPECT_DOUBLE_EQ(c.materials[0].poisson, 0.3);
  EXPECT_EQ(c.materials[1].name, "fibre");
  EXPECT_EQ(c.materials[1].model, MaterialSpec::Model::Transverse);
  EXPECT_DOUBLE_EQ(c.materials[1].young, 230e9);
  EXPECT_DOUBLE_EQ(c.materials[1].poisson, 0.2);
  EXPECT_DOUBLE_EQ(c.materials[1].young_transverse, 15e9);
  EXPECT_DOUBLE_EQ(c.materials[1].shear_axial, 25e9);
  EXPECT_DOUBLE_EQ(c.materials[1].poisson_transverse, 0.4);

  ASSERT_EQ(c.fibers.size(), 3u);
  const FiberSpec& beam = c.fibers[0];
  EXPECT_EQ(beam.name, "beam");
  EXPECT_EQ(beam.material, "steel");
  EXPECT_DOUBLE_EQ(beam.radius, 0.01);
  EXPECT_DOUBLE_EQ(beam.semi_axis_1, 0.01);
  EXPECT_DOUBLE_EQ(beam.semi_axis_2, 0.01);
  ASSERT_TRUE(beam.section_direction.has_value());
  expect_vec(*beam.section_direction, Vec3(0, 1, 0));  // normalized
  EXPECT_EQ(beam.path.kind, PathSpec::Kind::Polyline);
  ASSERT_EQ(beam.path.points.size(), 3u);
  expect_vec(beam.path.points[1], Vec3(0.5, 0, 0));
  expect_vec(beam.path.points[2], Vec3(1, 0, 0));
  EXPECT_EQ(beam.elements, 20);

  const FiberSpec& ring = c.fibers[1];
  EXPECT_EQ(ring.material, "fibre");
  EXPECT_DOUBLE_EQ(ring.semi_axis_1, 0.002);
  EXPECT_DOUBLE_EQ(ring.semi_axis_2, 0.001);
  EXPECT_DOUBLE_EQ(ring.radius, std::sqrt(0.002 * 0.001));
  EXPECT_FALSE(ring.section_direction.has_value());
  EXPECT_EQ(ring.path.kind, PathSpec::Kind::Arc);
  expect_vec(ring.path.center, Vec3(0, 0, 1));
  expect_vec(ring.path.axis, Vec3(0, 0, 1));  // normalized
  EXPECT_DOUBLE_EQ(ring.path.radius, 0.5);
  EXPECT_DOUBLE_EQ(ring.path.start_angle, kPi / 2);  // degrees in the file, radians stored
  EXPECT_DOUBLE_EQ(ring.path.angle, -kPi);
  EXPECT_EQ(ring.elements, 8);

  const FiberSpec& spring = c.fibers[2];
  EXPECT_EQ(spring.path.kind, PathSpec::Kind::Helix);
  expect_vec(spring.path.center, Vec3(1, 1, 0));
  expect_vec(spring.path.axis, Vec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(spring.path.radius, 0.05);
  EXPECT_DOUBLE_EQ(spring.path.pitch, 0.02);
  EXPECT_DOUBLE_EQ(spring.path.turns, 3.5);

  ASSERT_EQ(c.fixes.size(), 3u);
  EXPECT_EQ(c.fixes[0].node.fiber, "beam");
  EXPECT_EQ(c.fixes[0].node.kind, NodeRef::Kind::First);
  EXPECT_TRUE(c.fixes[0].position());
  EXPECT_TRUE(c.fixes[0].sections());
  EXPECT_EQ(c.fixes[1].node.kind, NodeRef::Kind::NodeIndex);
  EXPECT_EQ(c.fixes[1].node.index, 0);
  EXPECT_TRUE(c.fixes[1].position());
  EXPECT_FALSE(c.fixes[1].sections());
  EXPECT_EQ(c.fixes[2].node.kind, NodeRef::Kind::Fraction);
  EXPECT_DOUBLE_EQ(c.fixes[2].node.fraction, 0.5);
  EXPECT_FALSE(c.fixes[2].position());
  EXPECT_TRUE(c.fixes[2].sections());

  ASSERT_EQ(c.steps.size(), 2u);
  const StepSpec& s0 = c.steps[0];
  EXPECT_EQ(s0.name, "load");
  EXPECT_EQ(s0.increments, 10);
  EXPECT_EQ(s0.max_increments, 200);
  ASSERT_EQ(s0.loads.size(), 1u);
  EXPECT_EQ(s0.loads[0].node.fiber, "beam");
  EXPECT_EQ(s0.loads[0].node.kind, NodeRef::Kind::Last);
  expect_vec(s0.loads[0].force, Vec3(0, 0, -1000));
  expect_vec(s0.loads[0].moment, Vec3(1, 2, 3));
  ASSERT_EQ(s0.displacements.size(), 1u);
  EXPECT_EQ(s0.displacements[0].node.fiber, "ring");
  EXPECT_EQ(s0.displacements[0].node.kind, NodeRef::Kind::NodeIndex);
  EXPECT_EQ(s0.displacements[0].node.index, 16);  // the last node of 8 elements
  ASSERT_TRUE(s0.displacements[0].value[0].has_value());
  EXPECT_DOUBLE_EQ(*s0.displacements[0].value[0], 0.01);
  ASSERT_TRUE(s0.displacements[0].value[1].has_value());
  EXPECT_DOUBLE_EQ(*s0.displacements[0].value[1], 0.0);
  EXPECT_FALSE(s0.displacements[0].value[2].has_value());

  const StepSpec& s1 = c.steps[1];
  EXPECT_EQ(s1.name, "step1");  // default name: "step" + index
  EXPECT_EQ(s1.increments, 1);
  EXPECT_EQ(s1.max_increments, 0);
  ASSERT_EQ(s1.loads.size(), 1u);
  EXPECT_EQ(s1.loads[0].node.kind, NodeRef::Kind::Fraction);
  EXPECT_DOUBLE_EQ(s1.loads[0].node.fraction, 1.0);
  expect_vec(s1.loads[0].force, Vec3::Zero());
  expect_vec(s1.loads[0].moment, Vec3(0, 0, 5));
  EXPECT_TRUE(s1.displacements.empty());

  EXPECT_DOUBLE_EQ(c.solver.residual_tolerance, 1e-6);
  EXPECT_DOUBLE_EQ(c.solver.displacement_tolerance, 1e-9);
  EXPECT_EQ(c.solver.max_iterations, 30);
  EXPECT_EQ(c.solver.max_cuts, 5);
  EXPECT_FALSE(c.solver.line_search);
  EXPECT_EQ(c.solver.linear_solver, "eigen");
  EXPECT_EQ(c.output.every, 2);
  EXPECT_EQ(c.output.tube_sides, 16);
}

TEST(CaseReader, MinimalCaseTakesDefaults) {
  const Case c = parse_case_toml(kMinimal, "minimal.toml");
  EXPECT_EQ(c.name, "minimal");
  EXPECT_EQ(c.title, "");
  ASSERT_EQ(c.materials.size(), 1u);
  EXPECT_EQ(c.materials[0].model, MaterialSpec::Model::Isotropic);
  ASSERT_EQ(c.fibers.size(), 1u);
  EXPECT_FALSE(c.fibers[0].section_direction.has_value());
  EXPECT_TRUE(c.fixes.empty());
  ASSERT_EQ(c.steps.size(), 1u);
  EXPECT_EQ(c.steps[0].name, "step0");
  EXPECT_EQ(c.steps[0].increments, 1);
  EXPECT_EQ(c.steps[0].max_increments, 0);
  EXPECT_TRUE(c.steps[0].loads.empty());
  const SolverSpec solver_defaults;
  EXPECT_EQ(c.solver.residual_tolerance, solver_defaults.residual_tolerance);
  EXPECT_EQ(c.solver.displacement_tolerance, solver_defaults.displacement_tolerance);
  EXPECT_EQ(c.solver.max_iterations, solver_defaults.max_iterations);
  EXPECT_EQ(c.solver.max_cuts, solver_defaults.max_cuts);
  EXPECT_EQ(c.solver.line_search, solver_defaults.line_search);
  EXPECT_EQ(c.solver.linear_solver, "cholmod");
  EXPECT_EQ(c.output.every, 1);
  EXPECT_EQ(c.output.tube_sides, 12);
}

TEST(CaseReader, ArcAndHelixDefaults) {
  std::string text = replace_once(kMinimal, "points = [[0, 0, 0], [1, 0, 0]]",
                                  "arc = { radius = 2, angle = 45 }");
  Case c = parse_case_toml(text, kFile);
  EXPECT_EQ(c.fibers[0].path.kind, PathSpec::Kind::Arc);
  expect_vec(c.fibers[0].path.center, Vec3::Zero());
  expect_vec(c.fibers[0].path.axis, Vec3::UnitZ());
  EXPECT_DOUBLE_EQ(c.fibers[0].path.start_angle, 0.0);
  EXPECT_DOUBLE_EQ(c.fibers[0].path.angle, kPi / 4);

  text = replace_once(kMinimal, "points = [[0, 0, 0], [1, 0, 0]]",
                      "helix = { radius = 2, pitch = 0, turns = 1 }");
  c = parse_case_toml(text, kFile);
  EXPECT_EQ(c.fibers[0].path.kind, PathSpec::Kind::Helix);
  EXPECT_DOUBLE_EQ(c.fibers[0].path.pitch, 0.0);
  EXPECT_DOUBLE_EQ(c.fibers[0].path.turns, 1.0);
}

TEST(CaseReader, JsonGivesTheSameCaseAsToml) {
  const Case from_toml = parse_case_toml(kBase, kFile);
  const Case from_json = parse_case_json(to_json(kBase), "cases/demo.json");
  EXPECT_EQ(from_json.file, "cases/demo.json");
  EXPECT_EQ(from_json.name, "demo");
  expect_same_case(from_toml, from_json);
}

TEST(CaseReader, HandWrittenJson) {
  const std::string json = R"({
    "title": "pull",
    "material": [{"name": "steel", "young": 2e11, "poisson": 0.25}],
    "fiber": [{"name": "beam", "material": "steel", "semi_axes": [0.02, 0.01],
               "points": [[0, 0, 0], [0, 0, 1]], "elements": 3}],
    "fix": [{"fiber": "beam", "node": "first"}],
    "step": [{"increments": 4,
              "displacement": [{"fiber": "beam", "node": 6, "value": ["free", "free", 0.1]}]}],
    "solver": {"line_search": true, "max_cuts": 0},
    "output": {"tube_sides": 3}
  })";
  const Case c = parse_case_json(json, "pull.json");
  EXPECT_EQ(c.title, "pull");
  EXPECT_DOUBLE_EQ(c.materials[0].poisson, 0.25);
  EXPECT_DOUBLE_EQ(c.fibers[0].radius, std::sqrt(0.02 * 0.01));
  EXPECT_TRUE(c.fixes[0].position() && c.fixes[0].sections());  // dofs defaults to "all"
  EXPECT_EQ(c.steps[0].name, "step0");
  EXPECT_EQ(c.steps[0].increments, 4);
  EXPECT_EQ(c.steps[0].displacements[0].node.index, 6);
  EXPECT_FALSE(c.steps[0].displacements[0].value[0].has_value());
  EXPECT_FALSE(c.steps[0].displacements[0].value[1].has_value());
  EXPECT_DOUBLE_EQ(*c.steps[0].displacements[0].value[2], 0.1);
  EXPECT_EQ(c.solver.max_cuts, 0);
  EXPECT_EQ(c.output.tube_sides, 3);
}

TEST(CaseReader, ReadsFilesByExtension) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("fibra_case_reader_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::create_directories(dir);
  const std::string toml_path = (dir / "cantilever.toml").string();
  const std::string json_path = (dir / "cantilever.JSON").string();
  std::ofstream(toml_path) << kBase;
  std::ofstream(json_path) << to_json(kBase);

  const Case a = read_case(toml_path);
  EXPECT_EQ(a.file, toml_path);
  EXPECT_EQ(a.name, "cantilever");
  const Case b = read_case(json_path);
  EXPECT_EQ(b.file, json_path);
  EXPECT_EQ(b.name, "cantilever");
  expect_same_case(a, b);

  const std::string missing = (dir / "missing.toml").string();
  expect_input_error([&] { read_case(missing); }, missing, "(file)", "cannot open");
  const std::string yaml = (dir / "case.yaml").string();
  expect_input_error([&] { read_case(yaml); }, yaml, "(file)", "expected a .toml or .json file");
  std::filesystem::remove_all(dir);
}

TEST(NodeRefLabel, Formats) {
  NodeRef ref;
  ref.kind = NodeRef::Kind::First;
  EXPECT_EQ(ref.label(), "first");
  ref.kind = NodeRef::Kind::Last;
  EXPECT_EQ(ref.label(), "last");
  ref.kind = NodeRef::Kind::NodeIndex;
  ref.index = 12;
  EXPECT_EQ(ref.label(), "12");
  ref.kind = NodeRef::Kind::Fraction;
  ref.fraction = 0.5;
  EXPECT_EQ(ref.label(), "at0.5");
  ref.fraction = 0;
  EXPECT_EQ(ref.label(), "at0");
  ref.fraction = 1;
  EXPECT_EQ(ref.label(), "at1");
  ref.fraction = 1.0 / 3.0;
  EXPECT_EQ(ref.label(), "at0.333333");
}

// ------------------------------------------------------------------------------------------
// Bad input: each case edits the valid base case in one place. Every one is checked as TOML and
// (converted) as JSON, since both formats share one schema.

struct BadCase {
  const char* name;
  std::string from;
  std::string to;
  std::string key;
  std::string fragment;
  bool json = true;  ///< also check the JSON form (false when it cannot be expressed in JSON)
};

std::ostream& operator<<(std::ostream& out, const BadCase& c) { return out << c.name; }

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, NamesFileKeyAndExpectation) {
  const BadCase& c = GetParam();
  const std::string text = replace_once(kBase, c.from, c.to);
  expect_toml_error(text, c.key, c.fragment);
  if (c.json) expect_json_error(to_json(text), c.key, c.fragment);
}

const std::vector<BadCase> kBadCases = {
    // Unknown keys, with suggestions.
    {"UnknownTopLevelKey", "title = \"Cantilever under a tip load\"", "titel = \"x\"", "titel",
     "unknown key \"titel\" (did you mean \"title\"?)"},
    {"UnknownKeyWithoutSuggestion", "title = \"Cantilever under a tip load\"", "colour = \"red\"",
     "colour", "allowed keys here: title, material, fiber"},
    {"UnknownFiberKey", "radius = 0.01", "radiuss = 0.01", "fiber[0].radiuss",
     "did you mean \"radius\"?"},
    {"UnknownArcKey", "start_angle = 90", "startangle = 90", "fiber[1].arc.startangle",
     "did you mean \"start_angle\"?"},
    {"HelixHasNoStartAngle", "pitch = 0.02", "pitch = 0.02, start_angle = 3",
     "fiber[2].helix.start_angle", "unknown key"},
    {"UnknownLoadKey", "moment = [1, 2, 3]", "momnet = [1, 2, 3]", "step[0].load[0].momnet",
     "did you mean \"moment\"?"},
    {"UnknownStepTable", "[[step.displacement]]", "[[step.displacements]]",
     "step[0].displacements", "did you mean \"displacement\"?"},
    {"UnknownSolverKey", "max_iterations = 30", "max_iter = 30", "solver.max_iter",
     "did you mean \"max_iterations\"?"},
    {"UnknownOutputKey", "every = 2", "evry = 2", "output.evry", "did you mean \"every\"?"},
    {"TransverseKeyOnIsotropic", "poisson = 0.3", "poisson = 0.3\nshear_axial = 1e9",
     "material[0].shear_axial", "only allowed with model = \"transverse\""},

    // Materials.
    {"PoissonTooLarge", "poisson = 0.3", "poisson = 0.5", "material[0].poisson",
     "must be in [0, 0.5)"},
    {"PoissonNegativeIsotropic", "poisson = 0.3", "poisson = -0.1", "material[0].poisson",
     "must be in [0, 0.5)"},
    {"YoungNegative", "young = 210e9", "young = -1", "material[0].young", "must be > 0"},
    {"YoungNotFinite", "young = 210e9", "young = inf", "material[0].young",
     "expected a finite number", false},
    {"YoungMissing", "young = 210e9", "", "material[0].young", "missing required key"},
    {"YoungString", "young = 210e9", "young = \"210 GPa\"", "material[0].young",
     "expected a number, got a string"},
    {"UnknownModel", "model = \"isotropic\"", "model = \"isotropc\"", "material[0].model",
     "expected \"isotropic\" or \"transverse\", got \"isotropc\" (did you mean \"isotropic\"?)"},
    {"MaterialNameMissing", "name = \"steel\"", "", "material[0].name", "missing required key"},
    {"MaterialNameEmpty", "name = \"steel\"", "name = \"\"", "material[0].name", "non-empty"},
    {"DuplicateMaterial", "name = \"fibre\"", "name = \"steel\"", "material[1].name",
     "duplicate material name \"steel\""},
    {"TransverseMissingKey", "young_transverse = 15e9", "", "material[1].young_transverse",
     "missing required key"},
    {"TransverseShearZero", "shear_axial = 25e9", "shear_axial = 0", "material[1].shear_axial",
     "must be > 0"},
    {"TransverseNotPositiveDefinite", "poisson = 0.2", "poisson = 3", "material[1]",
     "compliance matrix is not positive definite"},
    {"TransversePoissonBelowMinusOne", "poisson_transverse = 0.4", "poisson_transverse = -1",
     "material[1].poisson_transverse", "must be > -1"},

    // Fibers.
    {"RadiusNegative", "radius = 0.01", "radius = -0.01", "fiber[0].radius", "must be > 0"},
    {"RadiusString", "radius = 0.01", "radius = \"thin\"", "fiber[0].radius",
     "expected a number, got a string"},
    {"RadiusAndSemiAxes", "radius = 0.01", "radius = 0.01\nsemi_axes = [1, 1]", "fiber[0]",
     "either radius or semi_axes, not both"},
    {"NoSection", "radius = 0.01", "", "fiber[0].radius", "missing the section"},
    {"SemiAxesLength", "semi_axes = [0.002, 0.001]", "semi_axes = [0.002]", "fiber[1].semi_axes",
     "expected an array of 2 numbers"},
    {"SemiAxesNegative", "semi_axes = [0.002, 0.001]", "semi_axes = [0.002, -0.001]",
     "fiber[1].semi_axes", "must be > 0"},
    {"MaterialNotFound", "material = \"fibre\"", "material = \"fibres\"", "fiber[1].material",
     "no material named \"fibres\" (did you mean \"fibre\"?)"},
    {"MaterialNotString", "material = \"fibre\"", "material = 1", "fiber[1].material",
     "expected a string, got an integer"},
    {"DuplicateFiber", "name = \"ring\"", "name = \"beam\"", "fiber[1].name",
     "duplicate fiber name \"beam\""},
    {"ElementsZero", "elements = 20", "elements = 0", "fiber[0].elements", "must be >= 1"},
    {"ElementsFloat", "elements = 20", "elements = 20.5", "fiber[0].elements", "expected an integer"},
    {"ElementsIntegralFloat", "elements = 20", "elements = 20.0", "fiber[0].elements",
     "expected an integer, got the floating-point number 20"},
    {"ElementsMissing", "elements = 20", "", "fiber[0].elements", "missing required key"},
    {"ElementsTooLarge", "elements = 20", "elements = 99999999999", "fiber[0].elements",
     "must be <= 2147483647"},
    {"PointsTooFew", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]", "points = [[0, 0, 0]]",
     "fiber[0].points", "expected at least 2 points"},
    {"PointsCoincide", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]",
     "points = [[0, 0, 0], [1, 0, 0], [1, 0, 0]]", "fiber[0].points[2]", "coincide"},
    {"PointTwoComponents", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]",
     "points = [[0, 0, 0], [0.5, 0], [1, 0, 0]]", "fiber[0].points[1]",
     "expected an array of 3 numbers, got an array of 2 elements"},
    {"PointStringComponent", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]",
     "points = [[0, 0, 0], [0.5, 0, \"z\"], [1, 0, 0]]", "fiber[0].points[1]",
     "expected an array of 3 numbers, element 2 is a string"},
    {"PointsNotArray", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]", "points = 3",
     "fiber[0].points", "expected an array of points"},
    {"TwoPaths", "elements = 20", "arc = { radius = 1, angle = 90 }\nelements = 20", "fiber[0]",
     "exactly one of points, arc or helix"},
    {"NoPath", "points = [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]", "", "fiber[0].points",
     "missing the fiber path"},
    {"ArcAngleZero", "angle = -180", "angle = 0", "fiber[1].arc.angle", "must be nonzero"},
    {"ArcAxisZero", "axis = [0, 0, 2]", "axis = [0, 0, 0]", "fiber[1].arc.axis",
     "expected a nonzero vector"},
    {"ArcRadiusMissing", "radius = 0.5, ", "", "fiber[1].arc.radius", "missing required key"},
    {"ArcNotTable", "arc = { center = [0, 0, 1], axis = [0, 0, 2], radius = 0.5, start_angle = 90, "
                    "angle = -180 }",
     "arc = 3", "fiber[1].arc", "expected a"},
    {"HelixPitchNegative", "pitch = 0.02", "pitch = -0.02", "fiber[2].helix.pitch", "must be >= 0"},
    {"HelixTurnsZero", "turns = 3.5", "turns = 0", "fiber[2].helix.turns", "must be > 0"},
    {"HelixRadiusZero", "radius = 0.05", "radius = 0", "fiber[2].helix.radius", "must be > 0"},
    {"SectionDirectionParallel", "section_direction = [0, 2, 0]", "section_direction = [-3, 0, 0]",
     "fiber[0].section_direction", "must not be parallel to the start tangent"},
    {"SectionDirectionZero", "section_direction = [0, 2, 0]", "section_direction = [0, 0, 0]",
     "fiber[0].section_direction", "nonzero vector"},

    // Fixes and node references.
    {"FixFiberNotFound", "fiber = \"beam\"\nnode = \"first\"", "fiber = \"bean\"\nnode = \"first\"",
     "fix[0].fiber", "no fiber named \"bean\" (did you mean \"beam\"?)"},
    {"FixFiberMissing", "fiber = \"beam\"\nnode = \"first\"", "node = \"first\"", "fix[0].fiber",
     "missing required key"},
    {"NodeWord", "node = \"first\"", "node = \"start\"", "fix[0].node",
     "expected \"first\", \"last\" or a node index"},
    {"NodeIndexNegative", "node = 0", "node = -1", "fix[1].node", "node index out of range"},
    {"NodeIndexTooLarge", "node = 16", "node = 17", "step[0].displacement[0].node",
     "fiber \"ring\" has 17 nodes (indices 0 to 16), got 17"},
    {"NodeFloat", "node = 0", "node = 0.5", "fix[1].node", "expected \"first\", \"last\" or a node index"},
    {"NodeAndAt", "at = 0.5", "at = 0.5\nnode = 1", "fix[2]", "either node or at, not both"},
    {"NoNode", "node = \"first\"\ndofs", "dofs", "fix[0].node", "missing required key"},
    {"AtOutOfRange", "at = 0.5", "at = 1.5", "fix[2].at", "must be in [0, 1]"},
    {"AtNegative", "at = 1\n", "at = -0.25\n", "step[1].load[0].at", "must be in [0, 1]"},
    {"BadDofs", "dofs = \"all\"", "dofs = \"positions\"", "fix[0].dofs",
     "expected \"all\", \"position\", \"sections\" or a list of components, got \"positions\" (did you mean \"position\"?)"},

    // Steps, loads, displacements.
    {"IncrementsZero", "increments = 10", "increments = 0", "step[0].increments", "must be >= 1"},
    {"IncrementsString", "increments = 10", "increments = \"ten\"", "step[0].increments",
     "expected an integer, got a string"},
    {"MaxIncrementsBelowIncrements", "max_increments = 200", "max_increments = 5",
     "step[0].max_increments", "must be 0 (automatic) or >= increments (10)"},
    {"MaxIncrementsNegative", "max_increments = 200", "max_increments = -1",
     "step[0].max_increments", "must be >= 0"},
    {"DuplicateStepName", "[[step]]\n  [[step.load]]", "[[step]]\nname = \"load\"\n  [[step.load]]",
     "step[1].name", "duplicate step name \"load\""},
    {"ForceLength", "force = [0, 0, -1000]", "force = [0, -1000]", "step[0].load[0].force",
     "expected an array of 3 numbers"},
    {"ForceNumber", "force = [0, 0, -1000]", "force = -1000", "step[0].load[0].force",
     "expected an array of 3 numbers, got an integer"},
    {"NoForceNorMoment", "moment = [0, 0, 5]", "", "step[1].load[0].force", "force and/or moment"},
    {"LoadFiberNotFound", "fiber = \"spring\"\n  at = 1", "fiber = \"springs\"\n  at = 1",
     "step[1].load[0].fiber", "did you mean \"spring\"?"},
    {"DisplacementAllFree", "value = [0.01, 0, \"free\"]", "value = [\"free\", \"free\", \"free\"]",
     "step[0].displacement[0].value", "at least one must be a number"},
    {"DisplacementBadWord", "value = [0.01, 0, \"free\"]", "value = [0.01, 0, \"fixed\"]",
     "step[0].displacement[0].value", "each a number or \"free\", element 2 is a string"},
    {"DisplacementTwoComponents", "value = [0.01, 0, \"free\"]", "value = [0.01, 0]",
     "step[0].displacement[0].value", "got an array of 2 elements"},
    {"DisplacementMissingValue", "value = [0.01, 0, \"free\"]", "", "step[0].displacement[0].value",
     "missing required key"},

    // Solver and output.
    {"ResidualToleranceZero", "residual_tolerance = 1e-6", "residual_tolerance = 0",
     "solver.residual_tolerance", "must be > 0"},
    {"DisplacementToleranceNegative", "displacement_tolerance = 1e-9",
     "displacement_tolerance = -1e-9", "solver.displacement_tolerance", "must be > 0"},
    {"MaxIterationsZero", "max_iterations = 30", "max_iterations = 0", "solver.max_iterations",
     "must be >= 1"},
    {"MaxCutsNegative", "max_cuts = 5", "max_cuts = -1", "solver.max_cuts", "must be >= 0"},
    {"LineSearchNotBool", "line_search = false", "line_search = 0", "solver.line_search",
     "expected a boolean"},
    {"LinearSolverUnknown", "linear_solver = \"eigen\"", "linear_solver = \"cholmd\"",
     "solver.linear_solver", "expected \"cholmod\" or \"eigen\", got \"cholmd\" (did you mean \"cholmod\"?)"},
    {"SolverArrayOfTables", "[solver]", "[[solver]]", "solver", "expected a"},
    {"EveryZero", "every = 2", "every = 0", "output.every", "must be >= 1"},
    {"TubeSidesTwo", "tube_sides = 16", "tube_sides = 2", "output.tube_sides", "must be >= 3"},

    // Top level.
    {"TitleNotString", "title = \"Cantilever under a tip load\"", "title = 5", "title",
     "expected a string, got an integer"},
    {"TitleDate", "title = \"Cantilever under a tip load\"", "title = 2024-01-01", "title",
     "expected a string, got a date", false},
};

INSTANTIATE_TEST_SUITE_P(CaseReader, BadInput, ::testing::ValuesIn(kBadCases),
                         [](const ::testing::TestParamInfo<BadCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(CaseReaderErrors, TomlLinesAreReported) {
  const std::string text = replace_once(kBase, "radius = 0.01", "radius = -0.01");
  try {
    parse_case_toml(text, kFile);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(line 21)"), std::string::npos) << e.what();
  }
}

TEST(CaseReaderErrors, RequiredSections) {
  // No fiber.
  std::string text = kMinimal;
  text = replace_once(text, "[[fiber]]\nname = \"beam\"\nmaterial = \"steel\"\nradius = 0.01\n"
                            "points = [[0, 0, 0], [1, 0, 0]]\nelements = 4\n", "");
  expect_toml_error(text, "fiber", "missing required key");
  // No step.
  expect_toml_error(replace_once(kMinimal, "[[step]]\n", ""), "step", "missing required key");
  // No material.
  expect_toml_error(replace_once(kMinimal, "[[material]]\nname = \"steel\"\nyoung = 2e11\npoisson = 0.3\n", ""),
                    "material", "missing required key");
  // [material] instead of [[material]].
  expect_toml_error(replace_once(kMinimal, "[[material]]", "[material]"), "material",
                    "expected an array of tables ([[material]]), got a table");
  // Empty arrays.
  expect_toml_error("step = []\n" + replace_once(kMinimal, "[[step]]\n", ""), "step",
                    "at least one step is required");
  expect_json_error(R"({"material": [], "fiber": [], "step": [{}]})", "material",
                    "at least one material is required");
  // An array holding something other than tables.
  expect_toml_error("step = [1]\n" + replace_once(kMinimal, "[[step]]\n", ""), "step[0]",
                    "expected a table, got an integer");
  // A top-level key written after a table header belongs to that table.
  expect_toml_error(replace_once(kMinimal, "[[step]]\n", "title = \"late\"\n[[step]]\n"),
                    "fiber[0].title", "before the first [table] header");
  expect_json_error(R"({"material": {"name": "steel"}})", "material",
                    "expected an array of objects, got an object");
}

TEST(CaseReaderErrors, SyntaxErrors) {
  expect_toml_error("title = \"x\"\nradius = \n", "(file)", "TOML syntax error at line 2");
  expect_toml_error("title = \"x\"\ntitle = \"y\"\n", "(file)", "TOML syntax error at line 2");
  expect_json_error("{\"title\": \"x\",\n \"material\": [}\n", "(file)",
                    "JSON syntax error: parse error at line 2, column");
  expect_json_error("", "(file)", "JSON syntax error");
  expect_json_error("[1, 2]", "(file)", "expected a JSON object at the top level");
}

TEST(CaseReaderErrors, JsonSpecifics) {
  // Duplicate keys are rejected (the TOML parser does this itself).
  expect_json_error(R"({"material": [{"name": "a", "name": "b"}]})", "material[0].name",
                    "duplicate key");
  // null is not a value of any key.
  const std::string json = to_json(kMinimal);
  std::string with_null = json;
  with_null.replace(with_null.find('{') + 1, 0, "\"title\": null,");
  expect_json_error(with_null, "title", "expected a string, got null");
  // Large unsigned integers are not integers any more.
  std::string huge = json;
  const std::size_t at = huge.find("\"elements\" : 4");
  ASSERT_NE(at, std::string::npos) << huge;
  huge.replace(at, std::string("\"elements\" : 4").size(), "\"elements\" : 18446744073709551615");
  expect_json_error(huge, "fiber[0].elements", "expected an integer");
}

}  // namespace
}  // namespace fibra

namespace fibra {
namespace {

TEST(CaseReaderFixComponents, ListOfComponentsSelectsDofs) {
  const std::string text = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "f"
material = "m"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 2
[[fix]]
fiber = "f"
node = "first"
dofs = ["y", "g1", "g2z"]
[[step]]
increments = 1
)";
  const Case c = parse_case_toml(text, "fix.toml");
  const std::array<bool, 9> expected{false, true, false, true, true, true, false, false, true};
  EXPECT_EQ(c.fixes[0].dofs, expected);
  EXPECT_FALSE(c.fixes[0].position());
  const std::string bad = std::string(text).replace(text.find("\"g2z\""), 5, "\"g3\"");
  try {
    parse_case_toml(bad, "fix.toml");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fix[0].dofs[2]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fibra
