#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <tuple>
#include <optional>
#include <sstream>
#include <string>
#include <toml++/toml.h>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/model_size.hpp"
#include "io/case_compare.hpp"

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
linear_solver = "eigen"

[output]
every = 2
tube_sides = 16
plots = false
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

using test::expect_same_case;

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
  EXPECT_EQ(c.solver.linear_solver, "eigen");
  EXPECT_EQ(c.output.every, 2);
  EXPECT_EQ(c.output.tube_sides, 16);
  EXPECT_FALSE(c.output.plots);
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
  EXPECT_EQ(c.solver.linear_solver, "cholmod");
  EXPECT_EQ(c.solver.krylov_precision, "auto");
  EXPECT_TRUE(c.bodies.empty());
  EXPECT_TRUE(c.bindings.empty());
  EXPECT_TRUE(c.steps[0].bodies.empty());
  EXPECT_EQ(c.solver.binding_tolerance, solver_defaults.binding_tolerance);
  EXPECT_EQ(c.solver.max_binding_updates, solver_defaults.max_binding_updates);
  EXPECT_EQ(c.output.every, 1);
  EXPECT_EQ(c.output.tube_sides, 12);
  EXPECT_TRUE(c.output.plots);
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
    "solver": {"max_cuts": 0},
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
    {"HelixStartAngleMisspelt", "pitch = 0.02", "pitch = 0.02, start_angel = 3",
     "fiber[2].helix.start_angel", "did you mean \"start_angle\"?"},
    {"UnknownLoadKey", "moment = [1, 2, 3]", "momnet = [1, 2, 3]", "step[0].load[0].momnet",
     "did you mean \"moment\"?"},
    {"UnknownStepTable", "[[step.displacement]]", "[[step.displacements]]",
     "step[0].displacements", "did you mean \"displacement\"?"},
    {"UnknownSolverKey", "max_iterations = 30", "max_iteration = 30", "solver.max_iteration",
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
    {"ElementsModelTooLarge", "elements = 20", "elements = 2000000000", "fiber[0].elements",
     "2000000000 elements make a model too large to run: estimated 2e+09 elements, 4e+09 nodes, 3.6e+10 dofs, "
     "6.66e+11 stiffness matrix entries and at least "},
    {"ElementsBeyondTheMatrixIndices", "elements = 20", "elements = 2000000000", "fiber[0].elements",
     "; the sparse solver holds at most 2147483647 matrix entries (32-bit indices)"},
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
    {"KrylovIterationsIsTheMethods", "max_cuts = 5", "max_cuts = 5\nkrylov_iterations = 40",
     "solver.krylov_iterations", "is not a setting: the solver sets it itself"},
    {"RelaxDragIsTheMethods", "max_cuts = 5", "max_cuts = 5\nrelax_drag = 0.25", "solver.relax_drag",
     "is not a setting: the solver sets it itself"},
    {"KrylovPrecisionUnknown", "max_cuts = 5", "max_cuts = 5\nkrylov_precision = \"singel\"",
     "solver.krylov_precision", "expected \"auto\", \"single\", \"half\" or \"double\", got \"singel\" (did you mean \"single\"?)"},
    {"TestToleranceMoved", "max_cuts = 5", "max_cuts = 5\ntest_tolerance = 1e-3", "solver.test_tolerance",
     "is now the `tolerance` of each relax, biaxial or shear [[step]]"},
    {"StepToleranceOfALoadStep", "max_increments = 200", "max_increments = 200\ntolerance = 1e-3", "step[0].tolerance",
     "belongs to relax, biaxial and shear steps"},
    {"LineSearchIsTheMethods", "max_cuts = 5", "max_cuts = 5\nline_search = false", "solver.line_search",
     "is not a setting"},
    {"LinearSolverUnknown", "linear_solver = \"eigen\"", "linear_solver = \"cholmd\"",
     "solver.linear_solver", "expected \"cholmod\" or \"eigen\", got \"cholmd\" (did you mean \"cholmod\"?)"},
    {"SolverArrayOfTables", "[solver]", "[[solver]]", "solver", "expected a"},
    {"EveryZero", "every = 2", "every = 0", "output.every", "must be >= 1"},
    {"TestLevelsNotBool", "every = 2", "every = 2\ntest_levels = 1", "output.test_levels", "expected a boolean"},
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

// ------------------------------------------------------------------------------------------
// Rigid bodies ([[body]]), averaged bindings ([[binding]]) and [[step.body]].

namespace fibra {
namespace {

/// Three fibers; two tows (bodies) bound to fiber ends, both bound to a grip: a two-level
/// hierarchy. The grip is driven with some components free.
const std::string kBodies = R"(
[[material]]
name = "steel"
young = 2e11
poisson = 0.3

[[fiber]]
name = "f1"
material = "steel"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[fiber]]
name = "f2"
material = "steel"
radius = 0.01
points = [[0, 0.1, 0], [1, 0.1, 0]]
elements = 4

[[fiber]]
name = "f3"
material = "steel"
radius = 0.01
points = [[0, 0.2, 0], [1, 0.2, 0]]
elements = 4

[[body]]
name = "grip"
center = [1.0, 0.1, 0]
axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]

[[body]]
name = "towA"
center = [1, 0.05, 0]

[[body]]
name = "towB"
center = [1, 0.2, 0]

[[binding]]
body = "towA"
ends = [{ fiber = "f1", node = "last" }, { fiber = "f2", at = 1 }]

[[binding]]
body = "towB"
ends = [{ fiber = "f3", node = 8 }]

[[binding]]
body = "grip"
bodies = ["towA", "towB"]

[[step]]
name = "pull"
increments = 4

  [[step.body]]
  name = "grip"
  displacement = [0.01, 0, "free"]
  rotation = ["free", "free", 0.5]
  force = [0, 0, 10]
  moment = [1, 2, 0]

  [[step.body]]
  name = "towA"
  force = [0, -3, 0]

[[step]]
name = "release"

  [[step.body]]
  name = "grip"
  displacement = ["free", "free", "free"]

[solver]
binding_tolerance = 1e-6
max_binding_updates = 12
)";

void expect_bodies_case(const Case& c) {
  ASSERT_EQ(c.bodies.size(), 3u);
  EXPECT_EQ(c.bodies[0].name, "grip");
  expect_vec(c.bodies[0].center, Vec3(1, 0.1, 0));
  // Rows D1, D2, D3 in the file, columns in BodySpec::axes.
  expect_vec(c.bodies[0].axes.col(0), Vec3(0, 1, 0));
  expect_vec(c.bodies[0].axes.col(1), Vec3(-1, 0, 0));
  expect_vec(c.bodies[0].axes.col(2), Vec3(0, 0, 1));
  EXPECT_EQ(c.bodies[1].name, "towA");
  expect_vec(c.bodies[1].center, Vec3(1, 0.05, 0));
  EXPECT_EQ(c.bodies[1].axes, Mat3::Identity());  // default frame
  EXPECT_EQ(c.bodies[2].name, "towB");

  ASSERT_EQ(c.bindings.size(), 3u);
  const BindingSpec& a = c.bindings[0];
  EXPECT_EQ(a.body, "towA");
  EXPECT_EQ(a.line, 0);
  EXPECT_TRUE(a.bodies.empty());
  ASSERT_EQ(a.ends.size(), 2u);
  EXPECT_EQ(a.ends[0].fiber, "f1");
  EXPECT_EQ(a.ends[0].kind, NodeRef::Kind::Last);
  EXPECT_EQ(a.ends[1].fiber, "f2");
  EXPECT_EQ(a.ends[1].kind, NodeRef::Kind::Fraction);
  EXPECT_DOUBLE_EQ(a.ends[1].fraction, 1.0);
  const BindingSpec& b = c.bindings[1];
  EXPECT_EQ(b.body, "towB");
  EXPECT_EQ(b.line, 1);
  ASSERT_EQ(b.ends.size(), 1u);
  EXPECT_EQ(b.ends[0].kind, NodeRef::Kind::NodeIndex);
  EXPECT_EQ(b.ends[0].index, 8);
  const BindingSpec& g = c.bindings[2];
  EXPECT_EQ(g.body, "grip");
  EXPECT_EQ(g.line, 2);
  EXPECT_TRUE(g.ends.empty());
  EXPECT_EQ(g.bodies, (std::vector<std::string>{"towA", "towB"}));

  ASSERT_EQ(c.steps.size(), 2u);
  ASSERT_EQ(c.steps[0].bodies.size(), 2u);
  const BodyStepSpec& grip = c.steps[0].bodies[0];
  EXPECT_EQ(grip.name, "grip");
  EXPECT_TRUE(grip.has_displacement);
  EXPECT_EQ(grip.displacement, (std::array<std::optional<double>, 3>{0.01, 0.0, std::nullopt}));
  EXPECT_TRUE(grip.has_rotation);
  EXPECT_EQ(grip.rotation, (std::array<std::optional<double>, 3>{std::nullopt, std::nullopt, 0.5}));
  ASSERT_TRUE(grip.force.has_value());
  expect_vec(*grip.force, Vec3(0, 0, 10));  // z is free: a force there is allowed
  ASSERT_TRUE(grip.moment.has_value());
  expect_vec(*grip.moment, Vec3(1, 2, 0));
  const BodyStepSpec& tow = c.steps[0].bodies[1];
  EXPECT_EQ(tow.name, "towA");
  EXPECT_FALSE(tow.has_displacement);
  EXPECT_FALSE(tow.has_rotation);
  EXPECT_FALSE(tow.moment.has_value());
  ASSERT_TRUE(tow.force.has_value());
  expect_vec(*tow.force, Vec3(0, -3, 0));
  ASSERT_EQ(c.steps[1].bodies.size(), 1u);
  const BodyStepSpec& release = c.steps[1].bodies[0];
  EXPECT_TRUE(release.has_displacement);  // every component released
  EXPECT_EQ(release.displacement, (std::array<std::optional<double>, 3>{}));
  EXPECT_FALSE(release.has_rotation);
  EXPECT_FALSE(release.force.has_value());

  EXPECT_DOUBLE_EQ(c.solver.binding_tolerance, 1e-6);
  EXPECT_EQ(c.solver.max_binding_updates, 12);
}

TEST(CaseReaderBodies, ParsesBodiesBindingsAndStepBodies) {
  const Case c = parse_case_toml(kBodies, "bodies.toml");
  expect_bodies_case(c);
}

TEST(CaseReaderBodies, JsonGivesTheSameCaseAsToml) {
  const Case from_toml = parse_case_toml(kBodies, "bodies.toml");
  const Case from_json = parse_case_json(to_json(kBodies), "bodies.json");
  expect_bodies_case(from_json);
  expect_same_case(from_toml, from_json);
}

TEST(CaseReaderBodies, HandWrittenJson) {
  const std::string json = R"({
    "material": [{"name": "steel", "young": 2e11, "poisson": 0.25}],
    "fiber": [{"name": "beam", "material": "steel", "radius": 0.01,
               "points": [[0, 0, 0], [0, 0, 1]], "elements": 3}],
    "body": [{"name": "plate", "center": [0, 0, 1]}],
    "binding": [{"body": "plate", "ends": [{"fiber": "beam", "node": "last"}]}],
    "step": [{"body": [{"name": "plate", "rotation": [0, 0, 1.5]}]}],
    "solver": {"binding_tolerance": 1e-7}
  })";
  const Case c = parse_case_json(json, "plate.json");
  ASSERT_EQ(c.bodies.size(), 1u);
  EXPECT_EQ(c.bodies[0].axes, Mat3::Identity());
  ASSERT_EQ(c.bindings.size(), 1u);
  EXPECT_EQ(c.bindings[0].ends[0].kind, NodeRef::Kind::Last);
  ASSERT_EQ(c.steps[0].bodies.size(), 1u);
  EXPECT_FALSE(c.steps[0].bodies[0].has_displacement);
  EXPECT_TRUE(c.steps[0].bodies[0].has_rotation);
  EXPECT_EQ(c.steps[0].bodies[0].rotation, (std::array<std::optional<double>, 3>{0.0, 0.0, 1.5}));
  EXPECT_DOUBLE_EQ(c.solver.binding_tolerance, 1e-7);
}

class BadBodyInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadBodyInput, NamesFileKeyAndExpectation) {
  const BadCase& c = GetParam();
  const std::string text = replace_once(kBodies, c.from, c.to);
  expect_toml_error(text, c.key, c.fragment);
  if (c.json) expect_json_error(to_json(text), c.key, c.fragment);
}

const std::string kGripBinding = "[[binding]]\nbody = \"grip\"\nbodies = [\"towA\", \"towB\"]\n";

const std::vector<BadCase> kBadBodyCases = {
    // [[body]].
    {"DuplicateBodyName", "name = \"towB\"\ncenter", "name = \"towA\"\ncenter", "body[2].name",
     "duplicate body name \"towA\" (already used by body[1])"},
    {"BodyNameEmpty", "name = \"towB\"\ncenter", "name = \"\"\ncenter", "body[2].name", "non-empty"},
    {"BodyNameMissing", "name = \"towB\"\ncenter", "center", "body[2].name", "missing required key"},
    {"BodyCenterMissing", "center = [1, 0.05, 0]\n", "", "body[1].center",
     "missing required key (expected an array of 3 numbers [m])"},
    {"BodyCenterLength", "center = [1, 0.05, 0]", "center = [1, 0.05]", "body[1].center",
     "expected an array of 3 numbers, got an array of 2 elements"},
    {"BodyCenterNotFinite", "center = [1, 0.05, 0]", "center = [1, inf, 0]", "body[1].center",
     "(finite), element 1 is inf", false},
    {"UnknownBodyKey", "center = [1, 0.05, 0]", "centre = [1, 0.05, 0]", "body[1].centre",
     "unknown key \"centre\" (did you mean \"center\"?)"},
    {"AxesNotOrthonormal", "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]",
     "axes = [[0, 1, 0], [-1, 0.1, 0], [0, 0, 1]]", "body[0].axes",
     "expected orthonormal axes (rows D1, D2, D3), but D1.D2 = 0.1 instead of 0"},
    {"AxesNotUnit", "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]", "axes = [[0, 2, 0], [-1, 0, 0], [0, 0, 1]]",
     "body[0].axes", "D1.D1 = 4 instead of 1"},
    {"AxesLeftHanded", "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]", "axes = [[0, 1, 0], [1, 0, 0], [0, 0, 1]]",
     "body[0].axes", "expected right-handed axes (D3 = D1 x D2)"},
    {"AxesTwoRows", "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]", "axes = [[0, 1, 0], [-1, 0, 0]]", "body[0].axes",
     "expected an array of 3 rows D1, D2, D3 (each an array of 3 numbers), got an array of 2 elements"},
    {"AxesRowLength", "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]", "axes = [[0, 1, 0], [-1, 0], [0, 0, 1]]",
     "body[0].axes[1]", "expected an array of 3 numbers"},

    // [[binding]].
    {"BindingUnknownBody", "body = \"grip\"\nbodies", "body = \"gripp\"\nbodies", "binding[2].body",
     "no body named \"gripp\" (did you mean \"grip\"?); defined bodies: grip, towA, towB"},
    {"BindingBodyMissing", "body = \"grip\"\nbodies", "bodies", "binding[2].body",
     "missing required key (expected a string naming a [[body]])"},
    {"BindingUnknownKey", "bodies = [\"towA\", \"towB\"]", "bodis = [\"towA\", \"towB\"]", "binding[2].bodis",
     "unknown key \"bodis\" (did you mean \"bodies\"?)"},
    {"BindingUnknownMemberBody", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", \"towC\"]",
     "binding[2].bodies[1]", "no body named \"towC\" (did you mean \"towA\"?)"},
    {"BindingBodiesNotArray", "bodies = [\"towA\", \"towB\"]", "bodies = \"towA\"", "binding[2].bodies",
     "expected an array of body names (strings), got a string"},
    {"BindingMemberNotString", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", 2]", "binding[2].bodies[1]",
     "expected a string, got an integer"},
    {"BindingUnknownFiber", "{ fiber = \"f3\", node = 8 }", "{ fiber = \"f4\", node = 8 }",
     "binding[1].ends[0].fiber", "no fiber named \"f4\""},
    {"BindingEndUnknownKey", "{ fiber = \"f3\", node = 8 }", "{ fiber = \"f3\", nod = 8 }", "binding[1].ends[0].nod",
     "unknown key \"nod\" (did you mean \"node\"?)"},
    {"BindingEndNodeOutOfRange", "{ fiber = \"f3\", node = 8 }", "{ fiber = \"f3\", node = 9 }",
     "binding[1].ends[0].node", "node index out of range"},
    {"BindingEndsNotTables", "ends = [{ fiber = \"f3\", node = 8 }]", "ends = [\"f3\"]", "binding[1].ends[0]",
     "expected a"},
    {"BindingEmpty", "ends = [{ fiber = \"f3\", node = 8 }]", "ends = []", "binding[1]",
     "a binding needs members: give `ends` and/or `bodies`"},
    {"BindingNoMembers", "ends = [{ fiber = \"f3\", node = 8 }]\n", "", "binding[1]",
     "a binding needs members: give `ends` and/or `bodies`"},
    {"GripNotArray", "ends = [{ fiber = \"f3\", node = 8 }]\n", "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = 2\n",
     "binding[1].grip", "expected an array of the body's axes (1, 2, 3) along which each bound fiber end is held, got an integer"},
    {"GripAxisOutOfRange", "ends = [{ fiber = \"f3\", node = 8 }]\n",
     "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = [2, 4]\n", "binding[1].grip[1]", "got axis 4"},
    {"GripAxisZero", "ends = [{ fiber = \"f3\", node = 8 }]\n", "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = [0]\n",
     "binding[1].grip[0]", "must be >= 1, got 0"},
    {"GripAxisTwice", "ends = [{ fiber = \"f3\", node = 8 }]\n",
     "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = [3, 3]\n", "binding[1].grip[1]", "axis 3 is listed twice"},
    {"GripAllAxes", "ends = [{ fiber = \"f3\", node = 8 }]\n",
     "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = [1, 2, 3]\n", "binding[1].grip", "grip at most two axes"},
    {"GripWithoutEnds", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", \"towB\"]\ngrip = [2]",
     "binding[2].grip", "a grip holds bound fiber ends, and this binding has none"},
    {"SpinNotBoolean", "ends = [{ fiber = \"f3\", node = 8 }]\n", "ends = [{ fiber = \"f3\", node = 8 }]\nspin = 1\n",
     "binding[1].spin", "expected a boolean"},
    {"SpinWithoutEnds", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", \"towB\"]\nspin = true",
     "binding[2].spin", "holds bound fiber ends against turning about their axis, and this binding has none"},
    {"DuplicateEnd", "{ fiber = \"f2\", at = 1 }", "{ fiber = \"f1\", node = \"last\" }", "binding[0].ends[1]",
     "duplicate end: node last of fiber \"f1\" is already binding[0].ends[0]"},
    {"DuplicateEndByIndex", "{ fiber = \"f3\", node = 8 }",
     "{ fiber = \"f3\", node = 8 }, { fiber = \"f3\", node = \"last\" }",
     "binding[1].ends[1]", "duplicate end: node last of fiber \"f3\" is already binding[1].ends[0]"},
    {"SelfBinding", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", \"grip\"]", "binding[2].bodies[1]",
     "body \"grip\" cannot be bound to itself"},
    {"BodyListedTwice", "bodies = [\"towA\", \"towB\"]", "bodies = [\"towA\", \"towA\"]", "binding[2].bodies[1]",
     "body \"towA\" is listed twice in this binding (already binding[2].bodies[0])"},
    {"BodyInTwoBindings", kGripBinding, kGripBinding + "\n[[binding]]\nbody = \"towB\"\nbodies = [\"towA\"]\n",
     "binding[3].bodies[0]",
     "body \"towA\" is a member of two bindings, binding[2] (to body \"grip\") and binding[3] (to body \"towB\")"},
    {"TwoCycle", kGripBinding, kGripBinding + "\n[[binding]]\nbody = \"towA\"\nbodies = [\"grip\"]\n",
     "binding[3].bodies", "bodies bound in a cycle: towA -> grip -> towA"},
    {"ThreeCycle", kGripBinding,
     "[[binding]]\nbody = \"grip\"\nbodies = [\"towA\"]\n\n[[binding]]\nbody = \"towA\"\nbodies = [\"towB\"]\n\n"
     "[[binding]]\nbody = \"towB\"\nbodies = [\"grip\"]\n",
     "binding[4].bodies", "bodies bound in a cycle: towB -> towA -> grip -> towB"},

    // [[step.body]].
    {"StepBodyUnknown", "name = \"towA\"\n  force", "name = \"towX\"\n  force", "step[0].body[1].name",
     "no body named \"towX\" (did you mean \"towA\"?); defined bodies: grip, towA, towB"},
    {"StepBodyNameMissing", "name = \"towA\"\n  force", "force", "step[0].body[1].name",
     "missing required key (expected a string naming a [[body]])"},
    {"StepBodyTwice", "name = \"towA\"\n  force", "name = \"grip\"\n  force", "step[0].body[1].name",
     "body \"grip\" is listed twice in this step (already step[0].body[0])"},
    {"StepBodyEmpty", "  force = [0, -3, 0]\n", "", "step[0].body[1]",
     "nothing given for body \"towA\": expected at least one of displacement, rotation"},
    {"StepBodyUnknownKey", "force = [0, -3, 0]", "forces = [0, -3, 0]", "step[0].body[1].forces",
     "unknown key \"forces\" (did you mean \"force\"?)"},
    {"ForceOnPrescribedComponent", "force = [0, 0, 10]", "force = [5, 0, 10]", "step[0].body[0].force",
     "force x is 5 but displacement x is prescribed in the same entry"},
    {"MomentOnPrescribedComponent", "moment = [1, 2, 0]", "moment = [1, 2, 3]", "step[0].body[0].moment",
     "moment z is 3 but rotation z is prescribed in the same entry"},
    {"BadFreeSpelling", "rotation = [\"free\", \"free\", 0.5]", "rotation = [\"fre\", \"free\", 0.5]",
     "step[0].body[0].rotation",
     "expected an array of 3 components, each a number or \"free\", element 0 is a string (\"fre\") (did you mean "
     "\"free\"?)"},
    {"DisplacementTwoComponents", "displacement = [0.01, 0, \"free\"]", "displacement = [0.01, 0]",
     "step[0].body[0].displacement", "got an array of 2 elements"},
    {"RotationNotFinite", "rotation = [\"free\", \"free\", 0.5]", "rotation = [\"free\", \"free\", nan]",
     "step[0].body[0].rotation", "element 2 is nan", false},
    {"BodyForceLength", "force = [0, -3, 0]", "force = [0, -3]", "step[0].body[1].force",
     "expected an array of 3 numbers"},
    {"StepBodyNotTables",
     "name = \"release\"\n\n  [[step.body]]\n  name = \"grip\"\n  displacement = [\"free\", \"free\", \"free\"]",
     "name = \"release\"\nbody = 3", "step[1].body", "expected an array of"},

    // [solver].
    {"BindingToleranceZero", "binding_tolerance = 1e-6", "binding_tolerance = 0", "solver.binding_tolerance",
     "must be > 0"},
    {"BindingToleranceString", "binding_tolerance = 1e-6", "binding_tolerance = \"small\"",
     "solver.binding_tolerance", "expected a number, got a string"},
    {"MaxBindingUpdatesZero", "max_binding_updates = 12", "max_binding_updates = 0", "solver.max_binding_updates",
     "must be >= 1"},
    {"MaxBindingUpdatesFloat", "max_binding_updates = 12", "max_binding_updates = 12.5",
     "solver.max_binding_updates", "expected an integer"},
    {"BindingToleranceMisspelled", "binding_tolerance = 1e-6", "binding_tolerence = 1e-6",
     "solver.binding_tolerence", "unknown key \"binding_tolerence\" (did you mean \"binding_tolerance\"?)"},
};

INSTANTIATE_TEST_SUITE_P(CaseReaderBodies, BadBodyInput, ::testing::ValuesIn(kBadBodyCases),
                         [](const ::testing::TestParamInfo<BadCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(CaseReaderBodies, CycleOfThreeIsListedInOrder) {
  // A bound to B, B bound to C, C bound to A: reported where the cycle closes.
  const std::string text = kMinimal + R"(
[[body]]
name = "A"
center = [0, 0, 0]
[[body]]
name = "B"
center = [0, 0, 0]
[[body]]
name = "C"
center = [0, 0, 0]
[[binding]]
body = "B"
bodies = ["A"]
[[binding]]
body = "C"
bodies = ["B"]
[[binding]]
body = "A"
bodies = ["C"]
)";
  expect_toml_error(text, "binding[2].bodies", "bodies bound in a cycle: A -> B -> C -> A");
  expect_json_error(to_json(text), "binding[2].bodies", "bodies bound in a cycle: A -> B -> C -> A");
}

TEST(CaseReaderBodies, BindingWithoutAnyBody) {
  const std::string text = kMinimal + "[[binding]]\nbody = \"grip\"\nends = [{ fiber = \"beam\", node = \"last\" }]\n";
  expect_toml_error(text, "binding[0].body", "no body named \"grip\": no [[body]] is defined");
}

TEST(CaseReaderBodies, BodyKeyAfterATableHeaderIsHinted) {
  // `body` is a top-level key: written inside [[fix]] it gets the hint about table headers.
  const std::string text = replace_once(kBase, "dofs = \"all\"", "dofs = \"all\"\nbody = \"grip\"");
  expect_toml_error(text, "fix[0].body", "a top-level key must be written before the first [table] header");
}

}  // namespace
}  // namespace fibra

// ------------------------------------------------------------------------------------------
// Woven fabrics ([fabric]), tows ([[tow]]), the weave pattern ([weave]) and step kinds.

namespace fibra {
namespace {

/// A small fabric: 2 x 2 tows of 3 fibers, the weft with its own fiber count and material.
const std::string kFabric = R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22

[[material]]
name = "carbon"
young = 230e9
poisson = 0.2

[fabric]
pattern = "plain"
warp = { tows = 2, spacing = 1.0e-3 }
weft = { tows = 2, spacing = 1.2e-3, tow = { fibers = 4 }, fiber = { material = "carbon" } }
margin = 0.4e-3
tension = 0.02

  [fabric.tow]
  fibers = 3
  width = 0.8e-3
  thickness = 0.2e-3

  [fabric.fiber]
  radius = 2.0e-5
  material = "glass"
  element_length = 2.5e-4

[[step]]
name = "weave"
kind = "weave"
increments = 5

[[step]]
name = "relax"
kind = "relax"
)";

TEST(CaseReaderFabric, ReadsTheFabricTable) {
  const Case c = parse_case_toml(kFabric, "fabric.toml");
  ASSERT_TRUE(c.fabric.has_value());
  const FabricSpec& f = *c.fabric;
  EXPECT_EQ(f.pattern, "plain");
  EXPECT_EQ(f.matrix, (std::vector<std::vector<int>>{{1, 0}, {0, 1}}));
  EXPECT_EQ(f.warp.tows, 2);
  EXPECT_DOUBLE_EQ(f.warp.spacing, 1.0e-3);
  EXPECT_EQ(f.warp.tow.fibers, 3);
  EXPECT_DOUBLE_EQ(f.warp.tow.width, 0.8e-3);
  EXPECT_DOUBLE_EQ(f.warp.tow.thickness, 0.2e-3);
  EXPECT_DOUBLE_EQ(f.warp.fiber.radius, 2.0e-5);
  EXPECT_EQ(f.warp.fiber.material, "glass");
  EXPECT_DOUBLE_EQ(f.warp.fiber.element_length, 2.5e-4);
  // The weft overrides some keys of the shared tables and takes the others from them.
  EXPECT_EQ(f.weft.tows, 2);
  EXPECT_DOUBLE_EQ(f.weft.spacing, 1.2e-3);
  EXPECT_EQ(f.weft.tow.fibers, 4);
  EXPECT_DOUBLE_EQ(f.weft.tow.width, 0.8e-3);
  EXPECT_DOUBLE_EQ(f.weft.tow.thickness, 0.2e-3);
  EXPECT_EQ(f.weft.fiber.material, "carbon");
  EXPECT_DOUBLE_EQ(f.weft.fiber.radius, 2.0e-5);
  EXPECT_DOUBLE_EQ(f.margin, 0.4e-3);
  EXPECT_DOUBLE_EQ(f.tension, 0.02);
  ASSERT_EQ(c.steps.size(), 2u);
  EXPECT_EQ(c.steps[0].kind, StepSpec::Kind::Weave);
  EXPECT_EQ(c.steps[1].kind, StepSpec::Kind::Relax);
}

TEST(CaseReaderFabric, GripOfTheTowEnds) {
  // Default: the paper's averaged binding, no grip on any tow end.
  const Case plain = parse_case_toml(kFabric, "fabric.toml");
  EXPECT_EQ(plain.fabric->grip, FabricSpec::Grip::Averaged);
  for (const BindingSpec& b : plain.bindings) EXPECT_TRUE(b.grip.empty() && !b.spin) << b.body;
  // width: each end held across its tow in the plane (warp: D2 = y; weft: D1 = x);
  // clamped: and across the thickness (D3 = z). Edge bindings (bodies only) never grip.
  for (const auto& [word, warp, weft] :
       {std::tuple{"width", std::vector<int>{2}, std::vector<int>{1}},
        std::tuple{"clamped", std::vector<int>{2, 3}, std::vector<int>{1, 3}}}) {
    const Case c = parse_case_toml(
        replace_once(kFabric, "pattern = \"plain\"", std::string("pattern = \"plain\"\ngrip = \"") + word + "\""),
        "fabric.toml");
    int ends = 0;
    for (const BindingSpec& b : c.bindings) {
      if (!b.ends.empty()) {
        ++ends;
        EXPECT_EQ(b.grip, b.body.rfind("warp", 0) == 0 ? warp : weft) << word << " " << b.body;
        EXPECT_TRUE(b.spin) << word << " " << b.body;  // a grip also holds each end's spin
      } else {
        EXPECT_TRUE(b.grip.empty() && !b.spin) << b.body;
      }
    }
    EXPECT_EQ(ends, 8) << word;  // 4 tows x 2 ends
  }
}

TEST(CaseReaderBodies, GripAxesAreReadSorted) {
  const Case c = parse_case_toml(
      replace_once(kBodies, "ends = [{ fiber = \"f3\", node = 8 }]\n", "ends = [{ fiber = \"f3\", node = 8 }]\ngrip = [3, 1]\n"),
      "bodies.toml");
  EXPECT_TRUE(c.bindings[0].grip.empty());
  EXPECT_EQ(c.bindings[1].grip, (std::vector<int>{1, 3}));
}

TEST(CaseReaderFabric, DefaultsOfMarginAndTension) {
  std::string text = replace_once(kFabric, "margin = 0.4e-3\n", "");
  text = replace_once(text, "tension = 0.02\n", "");
  const Case c = parse_case_toml(text, "fabric.toml");
  EXPECT_DOUBLE_EQ(c.fabric->margin, 0.5 * 1.2e-3);  // half the larger spacing
  EXPECT_EQ(c.fabric->tension, 0.0);                  // automatic
}

TEST(CaseReaderFabric, NamedPatternsAndMatrix) {
  const auto weave_of = [&](const std::string& line) {
    return parse_case_toml(replace_once(kFabric, "pattern = \"plain\"", line), "fabric.toml").fabric;
  };
  const auto twill = weave_of("pattern = \"twill 2/1\"");
  EXPECT_EQ(twill->pattern, "twill 2/1");
  EXPECT_EQ(twill->matrix.size(), 3u);
  const auto satin = weave_of("pattern = \"satin 5/2\"");
  EXPECT_EQ(satin->matrix.size(), 5u);
  const auto matrix = weave_of("matrix = [[1, 1, 0], [0, 1, 1], [1, 0, 1]]");
  EXPECT_EQ(matrix->pattern, "matrix");
  EXPECT_EQ(matrix->matrix, (std::vector<std::vector<int>>{{1, 1, 0}, {0, 1, 1}, {1, 0, 1}}));
}

TEST(CaseReaderFabric, ExpandsTheFabric) {
  // The generated assembly: 2 x 3 warp fibers and 2 x 4 weft fibers, a body on each tow end
  // and on each edge, the tows and the weave, the edges' conditions in the first step.
  const Case c = parse_case_toml(kFabric, "fabric.toml");
  ASSERT_EQ(c.fibers.size(), 2u * 3 + 2u * 4);
  EXPECT_EQ(c.fibers[0].name, "warp0.f0");
  EXPECT_EQ(c.fibers[0].material, "glass");
  EXPECT_EQ(c.fibers[6].name, "weft0.f0");
  EXPECT_EQ(c.fibers[6].material, "carbon");
  ASSERT_EQ(c.tows.size(), 4u);
  EXPECT_EQ(c.tows[0].name, "warp0");
  EXPECT_EQ(c.tows[0].direction, TowSpec::Direction::Warp);
  EXPECT_EQ(c.tows[3].name, "weft1");
  EXPECT_EQ(c.tows[3].direction, TowSpec::Direction::Weft);
  EXPECT_EQ(c.tows[3].index, 1);
  EXPECT_EQ(c.tows[3].fibers.size(), 4u);
  EXPECT_EQ(c.weave, c.fabric->matrix);
  std::vector<std::string> bodies;
  for (const BodySpec& b : c.bodies) bodies.push_back(b.name);
  for (const char* name : {"warp0.start", "warp0.end", "weft1.start", "weft1.end", "edge.x-", "edge.x+", "edge.y-",
                           "edge.y+"}) {
    EXPECT_NE(std::find(bodies.begin(), bodies.end(), name), bodies.end()) << name;
  }
  EXPECT_EQ(c.bodies.size(), 4u * 2 + 4);
  EXPECT_EQ(c.bindings.size(), 4u * 2 + 4);
  EXPECT_EQ(c.steps[0].bodies.size(), 4u + 4u * 2);  // the four edges and the tow ends (held in rotation)
  EXPECT_TRUE(c.steps[1].bodies.empty());
}

TEST(CaseReaderFabric, UserEntriesMayNameGeneratedFibersAndBodies) {
  const std::string text = kFabric + R"(
[[fiber]]
name = "probe"
material = "glass"
radius = 1e-5
points = [[0, 0, 1e-3], [1e-3, 0, 1e-3]]
elements = 2

[[body]]
name = "grip"
center = [1e-3, 0, 0]

[[binding]]
body = "grip"
bodies = ["edge.x+"]

[[fix]]
fiber = "warp0.f1"
node = "first"
dofs = "position"

[[step]]
name = "pull"

  [[step.load]]
  fiber = "weft1.f3"
  node = "last"
  force = [0, 1e-3, 0]

  [[step.body]]
  name = "grip"
  displacement = [1e-5, 0, 0]

  [[step.body]]
  name = "edge.y+"
  displacement = [0, 1e-5, 0]
)";
  const Case c = parse_case_toml(text, "fabric.toml");
  // User entries first, then the generated ones.
  EXPECT_EQ(c.fibers.front().name, "probe");
  EXPECT_EQ(c.fibers.size(), 1u + 14);
  EXPECT_EQ(c.bodies.front().name, "grip");
  EXPECT_EQ(c.bindings.front().body, "grip");
  EXPECT_EQ(c.bindings.front().bodies, std::vector<std::string>{"edge.x+"});
  ASSERT_EQ(c.fixes.size(), 1u);
  EXPECT_EQ(c.fixes[0].node.fiber, "warp0.f1");
  EXPECT_EQ(c.steps[2].loads[0].node.fiber, "weft1.f3");
  // An edge a step lists gets no default conditions in the first step.
  std::vector<std::string> first;
  for (const BodyStepSpec& b : c.steps[0].bodies) first.push_back(b.name);
  EXPECT_EQ(first, (std::vector<std::string>{"edge.x-", "edge.x+", "edge.y-", "warp0.start", "warp0.end", "warp1.start",
                                             "warp1.end", "weft0.start", "weft0.end", "weft1.start", "weft1.end"}));
}

// The mechanical tests of a woven sample: biaxial (strain, ratio) and shear (angle) steps, and
// "load" as the name of a standard step; written back (as a plain assembly) they read the same.
TEST(CaseReaderFabric, BiaxialAndShearSteps) {
  const std::string text = kFabric + R"(
[[step]]
name = "pull"
kind = "biaxial"
strain = 0.02
ratio = 0.5

[[step]]
name = "uniaxial"
kind = "biaxial"
strain = 0.01
ratio = 0

[[step]]
name = "shear"
kind = "shear"
angle = -25
height = "free"

[[step]]
name = "more"
kind = "load"
)";
  const Case c = parse_case_toml(text, "fabric.toml");
  ASSERT_EQ(c.steps.size(), 6u);
  EXPECT_EQ(c.steps[2].kind, StepSpec::Kind::Biaxial);
  EXPECT_EQ(c.steps[2].strain, 0.02);
  EXPECT_EQ(c.steps[2].ratio, 0.5);
  EXPECT_EQ(c.steps[3].ratio, 0.0);
  EXPECT_EQ(c.steps[4].kind, StepSpec::Kind::Shear);
  EXPECT_EQ(c.steps[4].angle, -25.0);
  EXPECT_TRUE(c.steps[4].free_height);
  EXPECT_FALSE(c.steps[2].free_height);
  EXPECT_EQ(c.steps[5].kind, StepSpec::Kind::Standard);
  EXPECT_EQ(c.steps[0].ratio, 1.0);  // defaults elsewhere
  const Case back = parse_case_toml(write_case_toml(c), "written.toml");
  ASSERT_EQ(back.steps.size(), c.steps.size());
  for (size_t i = 0; i < c.steps.size(); ++i) {
    EXPECT_EQ(back.steps[i].kind, c.steps[i].kind) << i;
    EXPECT_EQ(back.steps[i].strain, c.steps[i].strain) << i;
    EXPECT_EQ(back.steps[i].ratio, c.steps[i].ratio) << i;
    EXPECT_EQ(back.steps[i].angle, c.steps[i].angle) << i;
    EXPECT_EQ(back.steps[i].free_height, c.steps[i].free_height) << i;
  }
}

TEST(CaseReaderFabric, JsonGivesTheSameCaseAsToml) {
  const Case from_toml = parse_case_toml(kFabric, "fabric.toml");
  const Case from_json = parse_case_json(to_json(kFabric), "fabric.json");
  expect_same_case(from_toml, from_json);
}

class BadFabricInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadFabricInput, NamesFileKeyAndExpectation) {
  const BadCase& c = GetParam();
  const std::string text = replace_once(kFabric, c.from, c.to);
  expect_toml_error(text, c.key, c.fragment);
  if (c.json) expect_json_error(to_json(text), c.key, c.fragment);
}

const std::string kSharedTow = "  [fabric.tow]\n  fibers = 3\n  width = 0.8e-3\n  thickness = 0.2e-3\n";

const std::vector<BadCase> kBadFabricCases = {
    // Sizes: the key that makes the model large, and the estimates. The weft's fibers (8 of
    // 1.8 mm) then the warp's (6 of 2 mm) take the shared element length.
    {"ElementLengthPicometre", "element_length = 2.5e-4", "element_length = 1e-12", "fabric.fiber.element_length",
     "1e-12 m cuts each of the 8 weft fibers (0.0018 m long) into 1.8e+09 elements: a model too large to run: "
     "estimated 2.64e+10 elements, 5.28e+10 nodes, 4.75e+11 dofs"},
    {"OwnElementLengthPicometre", "warp = { tows = 2, spacing = 1.0e-3 }",
     "warp = { tows = 2, spacing = 1.0e-3, fiber = { element_length = 1e-12 } }", "fabric.warp.fiber.element_length",
     "1e-12 m cuts each of the 6 warp fibers (0.002 m long) into 2e+09 elements: a model too large to run"},
    {"ElementLengthSubnormal", "element_length = 2.5e-4", "element_length = 5e-324", "fabric.fiber.element_length",
     "cuts each of the 6 warp fibers (0.002 m long) into inf elements: a model too large to run: estimated inf "
     "elements"},
    {"ElementLengthInfinite", "element_length = 2.5e-4", "element_length = inf", "fabric.fiber.element_length",
     "expected a finite number, got inf", false},
    {"ElementLengthNaN", "element_length = 2.5e-4", "element_length = nan", "fabric.fiber.element_length",
     "expected a finite number, got nan", false},
    {"ElementLengthNegative", "element_length = 2.5e-4", "element_length = -2.5e-4", "fabric.fiber.element_length",
     "must be > 0, got -0.00025"},
    {"TwoBillionTows", "warp = { tows = 2, spacing = 1.0e-3 }", "warp = { tows = 2000000000, spacing = 1.0e-3 }",
     "fabric.warp.tows",
     "2000000000 tows of 3 fibers make 6e+09 warp fibers: a model too large to run: estimated "},
    {"TwoBillionFibersPerTow", "  fibers = 3\n", "  fibers = 2000000000\n", "fabric.tow.fibers",
     "2 tows of 2000000000 fibers make 4e+09 warp fibers: a model too large to run: estimated "},
    // The weave.
    {"UnknownPattern", "pattern = \"plain\"", "pattern = \"plian\"", "fabric.pattern",
     "unknown pattern \"plian\" (did you mean \"plain\"?)"},
    {"UnknownGrip", "pattern = \"plain\"", "pattern = \"plain\"\ngrip = \"tight\"", "fabric.grip",
     "expected \"averaged\" (the ends' mean held), \"width\" (each end held across the tow in the fabric's plane) or "
     "\"clamped\" (each end held across the tow), got \"tight\""},
    {"GripNotString", "pattern = \"plain\"", "pattern = \"plain\"\ngrip = 2", "fabric.grip",
     "expected a string, got an integer"},
    {"MisspeltTwill", "pattern = \"plain\"", "pattern = \"twil 2/1\"", "fabric.pattern",
     "(did you mean \"twill 2/1\"?)"},
    {"BadTwill", "pattern = \"plain\"", "pattern = \"twill 2\"", "fabric.pattern",
     "a twill is \"twill A/B\" with A, B >= 1"},
    {"BadSatinMove", "pattern = \"plain\"", "pattern = \"satin 6/3\"", "fabric.pattern",
     "must be coprime with N"},
    {"PatternNotString", "pattern = \"plain\"", "pattern = 1", "fabric.pattern", "expected a string, got an integer"},
    {"PatternAndMatrix", "pattern = \"plain\"", "pattern = \"plain\"\nmatrix = [[1, 0], [0, 1]]", "fabric",
     "give either pattern or matrix, not both"},
    {"NoPatternNorMatrix", "pattern = \"plain\"\n", "", "fabric.pattern",
     "missing the weave: give pattern (\"plain\", \"twill 2/1\", \"satin 5\", ...) or matrix"},
    {"MatrixConstantColumn", "pattern = \"plain\"", "matrix = [[1, 0], [1, 0]]", "fabric.matrix",
     "column 0 (a warp) is above every weft: it never interlaces"},
    {"MatrixConstantRow", "pattern = \"plain\"", "matrix = [[1, 0], [0, 0]]", "fabric.matrix",
     "row 1 (a weft) is above every warp"},
    {"MatrixEntryTwo", "pattern = \"plain\"", "matrix = [[1, 0], [0, 2]]", "fabric.matrix",
     "weave matrix entries must be 0 or 1 (row 1 has 2)"},
    {"MatrixRagged", "pattern = \"plain\"", "matrix = [[1, 0], [0, 1, 1]]", "fabric.matrix",
     "the weave matrix is not rectangular: row 1 has 3 entries, row 0 has 2"},
    {"MatrixEmpty", "pattern = \"plain\"", "matrix = []", "fabric.matrix", "the weave matrix is empty"},
    {"MatrixFloatEntry", "pattern = \"plain\"", "matrix = [[1, 0.0], [0, 1]]", "fabric.matrix[0][1]",
     "expected 0 or 1 (an integer), got a floating-point number"},
    {"MatrixRowNotArray", "pattern = \"plain\"", "matrix = [[1, 0], 1]", "fabric.matrix[1]",
     "expected the weave repeat: an array of rows (wefts)"},
    // The directions.
    {"WarpTowsZero", "warp = { tows = 2,", "warp = { tows = 0,", "fabric.warp.tows", "must be >= 1, got 0"},
    {"WarpTowsFloat", "warp = { tows = 2,", "warp = { tows = 2.5,", "fabric.warp.tows", "expected an integer"},
    {"WeftSpacingZero", "spacing = 1.2e-3", "spacing = 0", "fabric.weft.spacing", "must be > 0, got 0"},
    {"WarpMissing", "warp = { tows = 2, spacing = 1.0e-3 }\n", "", "fabric.warp",
     "missing required key (expected a table such as { tows = 5, spacing = 1.0e-3 })", false},
    {"WarpNotTable", "warp = { tows = 2, spacing = 1.0e-3 }", "warp = 2", "fabric.warp",
     "expected a table, got an integer", false},
    {"WarpTowNotTable", "warp = { tows = 2,", "warp = { tows = 2, tow = 2,", "fabric.warp.tow",
     "expected a table, got an integer", false},
    {"WarpMisspeltKey", "warp = { tows = 2,", "warp = { tows = 2, spacnig = 1, ", "fabric.warp.spacnig",
     "unknown key \"spacnig\" (did you mean \"spacing\"?)"},
    // The tow and fiber tables.
    {"SharedWidthMissing", "  width = 0.8e-3\n", "", "fabric.tow.width",
     "missing required key (expected a number > 0 [m]): the warp tows take it from fabric.warp.tow or, when not "
     "given there, from the shared fabric.tow"},
    {"ThicknessAboveWidth", "  thickness = 0.2e-3", "  thickness = 1e-3", "fabric.tow.thickness",
     "must be <= the width of the warp tows (0.0008, from fabric.tow.width), got 0.001"},
    {"WidthNegative", "  width = 0.8e-3", "  width = -0.8e-3", "fabric.tow.width", "must be > 0, got -0.0008"},
    // A fuzzer's input: without the check, the packing of a tow 450 m wide lists millions of sites.
    {"TowFlatterThanAThousand", "  width = 0.8e-3", "  width = 450", "fabric.warp.tow.width",
     "a tow section of 450 m by 0.0002 m (width by thickness) is more than 1000 times wider than thick"},
    {"FibersZero", "  fibers = 3", "  fibers = 0", "fabric.tow.fibers", "must be >= 1, got 0"},
    {"FibersTooFewForTheGenerator", "  fibers = 3", "  fibers = 2", "fabric.warp.tow.fibers",
     "a tow needs at least 3 fibers"},
    {"WeftFibersZero", "tow = { fibers = 4 }", "tow = { fibers = 0 }", "fabric.weft.tow.fibers", "must be >= 1, got 0"},
    {"UnknownMaterial", "  material = \"glass\"", "  material = \"glas\"", "fabric.fiber.material",
     "no material named \"glas\" (did you mean \"glass\"?); defined materials: glass, carbon"},
    {"WeftUnknownMaterial", "fiber = { material = \"carbon\" }", "fiber = { material = \"carbn\" }",
     "fabric.weft.fiber.material", "no material named \"carbn\" (did you mean \"carbon\"?)"},
    {"RadiusMissing", "  radius = 2.0e-5\n", "", "fabric.fiber.radius", "missing required key"},
    {"ElementLengthZero", "  element_length = 2.5e-4", "  element_length = 0", "fabric.fiber.element_length",
     "must be > 0"},
    {"UnknownTowKey", "  fibers = 3", "  fibres = 3", "fabric.tow.fibres",
     "unknown key \"fibres\" (did you mean \"fibers\"?)"},
    {"UnknownFabricKey", "pattern = \"plain\"", "patern = \"plain\"", "fabric.patern",
     "unknown key \"patern\" (did you mean \"pattern\"?)"},
    {"MarginNegative", "margin = 0.4e-3", "margin = -1e-3", "fabric.margin", "expected a length >= 0 [m], got -0.001"},
    {"TensionNegative", "tension = 0.02", "tension = -0.02", "fabric.tension",
     "expected a force per fiber >= 0 [N] (0 = automatic), got -0.02"},
    // Names and other tables.
    {"FiberNameClash", "[[step]]\nname = \"weave\"",
     "[[fiber]]\nname = \"warp1.f2\"\nmaterial = \"glass\"\nradius = 1e-5\npoints = [[0, 0, 0], [1, 0, 0]]\n"
     "elements = 1\n\n[[step]]\nname = \"weave\"",
     "fiber[0].name", "fiber name \"warp1.f2\" is also the name of a fiber the [fabric] generates"},
    {"BodyNameClash", "[[step]]\nname = \"weave\"",
     "[[body]]\nname = \"edge.y-\"\ncenter = [0, 0, 0]\n\n[[step]]\nname = \"weave\"",
     "body[0].name", "body name \"edge.y-\" is also the name of a body the [fabric] generates"},
    {"WeaveWithFabric", "[[step]]\nname = \"weave\"", "[weave]\npattern = \"plain\"\n\n[[step]]\nname = \"weave\"",
     "weave", "the weave of a [fabric] is its pattern or matrix: remove the [weave] table", false},
    {"BindingOfAGeneratedMember", "[[step]]\nname = \"weave\"",
     "[[body]]\nname = \"grip\"\ncenter = [0, 0, 0]\n\n[[binding]]\nbody = \"grip\"\nbodies = [\"warp0.end\"]\n\n"
     "[[step]]\nname = \"weave\"",
     "binding[0].bodies[0]",
     "body \"warp0.end\" is a member of two bindings, a binding the [fabric] generates (to body \"edge.x+\") and "
     "binding[0] (to body \"grip\")"},
    {"UnknownGeneratedFiber", "[[step]]\nname = \"weave\"",
     "[[fix]]\nfiber = \"warp2.f0\"\nnode = \"first\"\n\n[[step]]\nname = \"weave\"", "fix[0].fiber",
     "no fiber named \"warp2.f0\" (did you mean \"warp0.f0\"?); defined fibers: warp0.f0, warp0.f1, warp0.f2, "
     "warp1.f0"},
    {"TowClashesWithGenerated", "[[step]]\nname = \"weave\"",
     "[[tow]]\nname = \"warp0\"\ndirection = \"warp\"\nindex = 5\nfibers = [\"weft0.f0\"]\n\n"
     "[[step]]\nname = \"weave\"",
     "tow[0].name", "duplicate tow name \"warp0\" (already used by tow \"warp0\" (generated by the [fabric]))"},
};

INSTANTIATE_TEST_SUITE_P(CaseReaderFabric, BadFabricInput, ::testing::ValuesIn(kBadFabricCases),
                         [](const ::testing::TestParamInfo<BadCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(CaseReaderFabric, UnknownPatternListsTheAcceptedForms) {
  const std::string text = replace_once(kFabric, "pattern = \"plain\"", "pattern = \"hopsack\"");
  for (const char* fragment : {"unknown pattern \"hopsack\"", "\"plain\"", "\"twill A/B\"", "\"twill 2/1\"",
                               "\"basket N\"", "\"satin N/M\"", "matrix"}) {
    expect_toml_error(text, "fabric.pattern", fragment);
  }
}

TEST(CaseReaderFabric, FabricMustBeATable) {
  expect_toml_error("fabric = 1\n" + kMinimal, "fabric", "expected a table, got an integer");
  expect_json_error(to_json("fabric = [1]\n" + kMinimal), "fabric", "expected an object, got an array of 1 element");
}

TEST(CaseReaderFabric, OwnTableMissingAKeyIsNamed) {
  // No shared tow table: the weft's own table lacks the width.
  std::string text = replace_once(kFabric, kSharedTow, "");
  text = replace_once(text, "warp = { tows = 2, spacing = 1.0e-3 }",
                      "warp = { tows = 2, spacing = 1.0e-3, "
                      "tow = { fibers = 3, width = 0.8e-3, thickness = 0.2e-3 } }");
  expect_toml_error(text, "fabric.weft.tow.width",
                    "missing required key (expected a number > 0 [m]): the weft tows take it from fabric.weft.tow or, "
                    "when not given there, from the shared fabric.tow");
  // Nor an own table: named in the shared table.
  text = replace_once(text, ", tow = { fibers = 4 }", "");
  expect_toml_error(text, "fabric.tow.fibers", "the weft tows take it from fabric.weft.tow");
}

TEST(CaseReaderFabric, FibersAreOptionalWithAFabric) {
  const Case c = parse_case_toml("fiber = []\n" + kFabric, "fabric.toml");
  EXPECT_EQ(c.fibers.size(), 14u);
  // Without a fabric, fibers are still required.
  expect_toml_error(replace_once(kMinimal, "[[fiber]]\nname = \"beam\"\nmaterial = \"steel\"\nradius = 0.01\n"
                                           "points = [[0, 0, 0], [1, 0, 0]]\nelements = 4\n", ""),
                    "fiber", "missing required key (expected an array of tables ([[fiber]]), or a [fabric])");
  expect_toml_error("fiber = []\n" + kMinimal.substr(0, kMinimal.find("[[fiber]]")) + "[[step]]\n", "fiber",
                    "at least one fiber (or a [fabric]) is required");
}

// -- [[tow]], [weave] and step kinds -------------------------------------------------------

/// Four fibers in two warp and two weft tows, woven plain; weave, relax and standard steps.
const std::string kTows = R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22

[[fiber]]
name = "w0"
material = "glass"
radius = 1e-4
points = [[-2e-3, -0.5e-3, 0], [2e-3, -0.5e-3, 0]]
elements = 8

[[fiber]]
name = "w1"
material = "glass"
radius = 1e-4
points = [[-2e-3, 0.5e-3, 0], [2e-3, 0.5e-3, 0]]
elements = 8

[[fiber]]
name = "f0"
material = "glass"
radius = 1e-4
points = [[-0.5e-3, -2e-3, 0], [-0.5e-3, 2e-3, 0]]
elements = 8

[[fiber]]
name = "f1"
material = "glass"
radius = 1e-4
points = [[0.5e-3, -2e-3, 0], [0.5e-3, 2e-3, 0]]
elements = 8

[[tow]]
name = "A"
direction = "warp"
index = 0
fibers = ["w0"]

[[tow]]
name = "B"
direction = "warp"
index = 1
fibers = ["w1"]

[[tow]]
name = "C"
direction = "weft"
index = 0
fibers = ["f0", "f1"]

[weave]
matrix = [[1, 0], [0, 1]]

[[step]]
name = "weave"
kind = "weave"

[[step]]
name = "relax"
kind = "relax"

[[step]]
name = "pull"
)";

TEST(CaseReaderTows, ReadsTowsWeaveAndStepKinds) {
  const Case c = parse_case_toml(kTows, "tows.toml");
  ASSERT_EQ(c.tows.size(), 3u);
  EXPECT_EQ(c.tows[0].name, "A");
  EXPECT_EQ(c.tows[0].direction, TowSpec::Direction::Warp);
  EXPECT_EQ(c.tows[0].index, 0);
  EXPECT_EQ(c.tows[0].fibers, std::vector<std::string>{"w0"});
  EXPECT_EQ(c.tows[1].index, 1);
  EXPECT_EQ(c.tows[2].direction, TowSpec::Direction::Weft);
  EXPECT_EQ(c.tows[2].fibers, (std::vector<std::string>{"f0", "f1"}));
  EXPECT_EQ(c.weave, (std::vector<std::vector<int>>{{1, 0}, {0, 1}}));
  EXPECT_FALSE(c.fabric.has_value());
  ASSERT_EQ(c.steps.size(), 3u);
  EXPECT_EQ(c.steps[0].kind, StepSpec::Kind::Weave);
  EXPECT_EQ(c.steps[1].kind, StepSpec::Kind::Relax);
  EXPECT_EQ(c.steps[2].kind, StepSpec::Kind::Standard);  // the default
  // A weave pattern by name.
  const Case twill = parse_case_toml(replace_once(kTows, "matrix = [[1, 0], [0, 1]]", "pattern = \"twill 2/2\""),
                                     "tows.toml");
  EXPECT_EQ(twill.weave.size(), 4u);
  // JSON reads the same.
  expect_same_case(c, parse_case_json(to_json(kTows), "tows.json"));
}

TEST(CaseReaderTows, TowsAndWeaveWithoutWeaveSteps) {
  // Tows without [weave] are fine while no step weaves; so is a [weave] without tows.
  std::string text = replace_once(kTows, "kind = \"weave\"", "kind = \"standard\"");
  const Case no_weave = parse_case_toml(replace_once(text, "[weave]\nmatrix = [[1, 0], [0, 1]]\n", ""), "tows.toml");
  EXPECT_TRUE(no_weave.weave.empty());
  EXPECT_EQ(no_weave.steps[0].kind, StepSpec::Kind::Standard);
}

class BadTowInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadTowInput, NamesFileKeyAndExpectation) {
  const BadCase& c = GetParam();
  const std::string text = replace_once(kTows, c.from, c.to);
  expect_toml_error(text, c.key, c.fragment);
  if (c.json) expect_json_error(to_json(text), c.key, c.fragment);
}

const std::string kTowA = "[[tow]]\nname = \"A\"\ndirection = \"warp\"\nindex = 0\nfibers = [\"w0\"]\n";
const std::string kTowB = "[[tow]]\nname = \"B\"\ndirection = \"warp\"\nindex = 1\nfibers = [\"w1\"]\n";
const std::string kTowC = "[[tow]]\nname = \"C\"\ndirection = \"weft\"\nindex = 0\nfibers = [\"f0\", \"f1\"]\n";

const std::vector<BadCase> kBadTowCases = {
    {"UnknownFiber", "fibers = [\"f0\", \"f1\"]", "fibers = [\"f0\", \"f2\"]", "tow[2].fibers[1]",
     "no fiber named \"f2\" (did you mean \"f0\"?); defined fibers: w0, w1, f0, f1"},
    {"FiberInTwoTows", "fibers = [\"w1\"]", "fibers = [\"w0\"]", "tow[1].fibers[0]",
     "fiber \"w0\" is already in tow \"A\" (tow[0]): a fiber belongs to at most one tow"},
    {"FiberTwiceInATow", "fibers = [\"f0\", \"f1\"]", "fibers = [\"f0\", \"f0\"]", "tow[2].fibers[1]",
     "fiber \"f0\" is listed twice in this tow (already tow[2].fibers[0])"},
    {"NoFibers", "fibers = [\"w1\"]", "fibers = []", "tow[1].fibers", "expected at least one fiber name"},
    {"FibersNotArray", "fibers = [\"w1\"]", "fibers = \"w1\"", "tow[1].fibers",
     "expected an array of fiber names (strings), got a string"},
    {"FibersMissing", "fibers = [\"w1\"]\n", "", "tow[1].fibers", "missing required key"},
    {"DuplicateName", "name = \"B\"", "name = \"A\"", "tow[1].name",
     "duplicate tow name \"A\" (already used by tow \"A\" (tow[0]))"},
    {"NameMissing", "name = \"B\"\n", "", "tow[1].name", "missing required key"},
    {"BadDirection", "direction = \"weft\"", "direction = \"wfet\"", "tow[2].direction",
     "expected \"warp\" or \"weft\", got \"wfet\" (did you mean \"weft\"?)"},
    {"IndexNegative", "index = 1", "index = -1", "tow[1].index", "must be >= 0, got -1"},
    {"IndexMissing", "index = 1\n", "", "tow[1].index", "missing required key"},
    {"IndexTaken", "index = 1", "index = 0", "tow[1].index", "warp tow index 0 is already used by tow \"A\" (tow[0])"},
    {"UnknownTowKey", "index = 1", "indx = 1", "tow[1].indx", "unknown key \"indx\" (did you mean \"index\"?)"},
    // [weave].
    {"WeaveBadMatrix", "matrix = [[1, 0], [0, 1]]", "matrix = [[1, 1], [0, 1]]", "weave.matrix",
     "row 0 (a weft) is below every warp"},
    {"WeaveBadPattern", "matrix = [[1, 0], [0, 1]]", "pattern = \"satin\"", "weave.pattern",
     "a satin is \"satin N\" or \"satin N/M\" with N >= 5"},
    {"WeaveBoth", "matrix = [[1, 0], [0, 1]]", "matrix = [[1, 0], [0, 1]]\npattern = \"plain\"", "weave",
     "give either pattern or matrix, not both"},
    {"WeaveNeither", "matrix = [[1, 0], [0, 1]]", "", "weave.matrix", "missing the weave: give matrix"},
    {"WeaveUnknownKey", "matrix = [[1, 0], [0, 1]]", "matrx = [[1, 0], [0, 1]]", "weave.matrx",
     "unknown key \"matrx\" (did you mean \"matrix\"?)"},
    // Step kinds.
    {"UnknownKind", "kind = \"relax\"", "kind = \"relx\"", "step[1].kind",
     "expected \"load\" (or \"standard\"), \"weave\", \"relax\", \"biaxial\" or \"shear\", got \"relx\" (did you mean "
     "\"relax\"?)"},
    {"BiaxialWithoutStrain", "kind = \"relax\"", "kind = \"biaxial\"", "step[1].strain",
     "a biaxial step needs `strain`"},
    {"BiaxialWithoutEdges", "kind = \"relax\"", "kind = \"biaxial\"\nstrain = 0.01", "step[1].kind",
     "a biaxial step drives the edge bodies of a fabric (edge.x-, edge.x+, edge.y-, edge.y+); there is no body "
     "\"edge.x-\""},
    {"AngleOnBiaxial", "kind = \"relax\"", "kind = \"biaxial\"\nstrain = 0.01\nangle = 5", "step[1].angle",
     "`angle` belongs to kind = \"shear\" steps"},
    {"StrainOnRelax", "kind = \"relax\"", "kind = \"relax\"\nstrain = 0.01", "step[1].strain",
     "`strain` belongs to kind = \"biaxial\" steps"},
    {"StrainZero", "kind = \"relax\"", "kind = \"biaxial\"\nstrain = 0", "step[1].strain",
     "expected a strain in (-0.5, 0.5), not 0, got 0"},
    {"RatioNegative", "kind = \"relax\"", "kind = \"biaxial\"\nstrain = 0.01\nratio = -1", "step[1].ratio",
     "expected a ratio in [0, 10]"},
    {"ShearWithoutAngle", "kind = \"relax\"", "kind = \"shear\"", "step[1].angle", "a shear step needs `angle`"},
    {"ShearAngleZero", "kind = \"relax\"", "kind = \"shear\"\nangle = 0", "step[1].angle",
     "expected an angle in degrees in (-80, 80), not 0, got 0"},
    {"ShearHeightWord", "kind = \"relax\"", "kind = \"shear\"\nangle = 5\nheight = \"loose\"", "step[1].height",
     "expected \"held\" or \"free\", got \"loose\""},
    {"HeightOnBiaxial", "kind = \"relax\"", "kind = \"biaxial\"\nstrain = 0.01\nheight = \"free\"", "step[1].height",
     "`height` belongs to kind = \"shear\" steps"},
    {"KindNotString", "kind = \"relax\"", "kind = 1", "step[1].kind", "expected a string, got an integer"},
    {"WeaveStepWithoutTows", kTowA + "\n" + kTowB + "\n" + kTowC, "", "step[0].kind",
     "a weave step needs tows: define [[tow]] entries (or a [fabric])", false},
    {"WeaveStepWithoutWeave", "[weave]\nmatrix = [[1, 0], [0, 1]]\n", "", "step[0].kind",
     "a weave step needs the weave pattern: give a [weave] table (matrix or pattern)", false},
};

INSTANTIATE_TEST_SUITE_P(CaseReaderTows, BadTowInput, ::testing::ValuesIn(kBadTowCases),
                         [](const ::testing::TestParamInfo<BadCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(CaseReaderTows, JsonWordsForWeaveSteps) {
  expect_json_error(to_json(replace_once(kTows, kTowA + "\n" + kTowB + "\n" + kTowC, "")), "step[0].kind",
                    "a weave step needs tows: define tow entries (or a fabric object)");
  expect_json_error(to_json(replace_once(kTows, "[weave]\nmatrix = [[1, 0], [0, 1]]\n", "")), "step[0].kind",
                    "a weave step needs the weave pattern: give a weave object (matrix or pattern)");
}

// -- Model size --------------------------------------------------------------------------
// Models too large are refused while the file is read, with the key and the estimates; models
// large but within the limits are read as written. Explicit limits make these independent of
// the machine.

/// Limits with `memory` bytes (and the solver's matrix index limit).
SizeLimits memory_limits(double memory) {
  SizeLimits limits;
  limits.memory = memory;
  return limits;
}

TEST(CaseReaderSize, LargeButFineModelsAreAccepted) {
  const SizeLimits roomy = memory_limits(1024.0 * 1024 * 1024 * 1024 * 1024);  // 1 PiB
  // The largest fiber whose matrix the 32-bit indices hold: 45 + 333 E <= 2^31 - 1.
  const std::string largest = replace_once(kMinimal, "elements = 4", "elements = 6448899");
  EXPECT_EQ(parse_case_toml(largest, kFile, roomy).fibers[0].elements, 6448899);
  expect_input_error([&] { parse_case_toml(replace_once(kMinimal, "elements = 4", "elements = 6448900"), kFile, roomy); },
                     kFile, "fiber[0].elements", "(32-bit indices)");
  // A fabric of fine elements: 6 warp fibers of 20000, 8 weft fibers of 18000.
  const Case fine = parse_case_toml(replace_once(kFabric, "element_length = 2.5e-4", "element_length = 1e-7"),
                                    "fabric.toml", roomy);
  ASSERT_EQ(fine.fibers.size(), 14u);
  EXPECT_EQ(fine.fibers[0].elements, 20000);
  EXPECT_EQ(fine.fibers[13].elements, 18000);
  // On this machine's limits: a fiber of 100 000 elements (1.8 million dofs, at least 0.9 GiB).
  const ModelSize size = fiber_size(100000);
  if (size.bytes() > machine_size_limits().memory) GTEST_SKIP() << "less memory than " << format_bytes(size.bytes());
  EXPECT_EQ(parse_case_toml(replace_once(kMinimal, "elements = 4", "elements = 100000"), kFile).fibers[0].elements,
            100000);
}

// Fibers of a nanometre in a 0.8 mm tow: read and packed at once (the packing listed 5e10
// lattice sites before).
TEST(CaseReaderSize, TinyFibersInALargeTow) {
  const Case c = parse_case_toml(replace_once(kFabric, "radius = 2.0e-5", "radius = 1e-9"), "fabric.toml");
  ASSERT_EQ(c.fibers.size(), 14u);
  EXPECT_EQ(c.fibers[0].radius, 1e-9);
}

TEST(CaseReaderSize, AModelAboveTheMemoryIsRefused) {
  const SizeLimits small = memory_limits(64.0 * 1024 * 1024);
  const std::string text = replace_once(kMinimal, "elements = 4", "elements = 100000");
  for (const bool json : {false, true}) {
    const std::string file = json ? "demo.json" : kFile;
    const auto parse = [&] {
      if (json)
        parse_case_json(to_json(text), file, small);
      else
        parse_case_toml(text, file, small);
    };
    expect_input_error(parse, file, "fiber[0].elements",
                       "100000 elements make a model too large to run: estimated 1e+05 elements, 2e+05 nodes, "
                       "1.8e+06 dofs, 3.33e+07 stiffness matrix entries and at least ");
    expect_input_error(parse, file, "fiber[0].elements", "; this machine has 64 MiB of memory");
  }
  EXPECT_EQ(parse_case_toml(replace_once(kMinimal, "elements = 4", "elements = 1000"), kFile, small).fibers[0].elements,
            1000);
}

TEST(CaseReaderSize, FibersFineAloneButTooManyTogether) {
  // The base case's fibers: 20, 8 and 30 elements; each alone takes less than 400 kB, all
  // three more (about 574 kB).
  const SizeLimits small = memory_limits(400e3);
  ASSERT_LT(fiber_size(30).bytes(), 400e3);
  expect_input_error([&] { parse_case_toml(kBase, kFile, small); }, kFile, "fiber",
                     "the 3 fibers of the file (58 elements in all) make a model too large to run: estimated 58 "
                     "elements, 119 nodes, 1.07e+03 dofs");
  // With a fabric: its elements are counted with the file's (8 x 6 and 8 x 8 of 2.5e-4 m).
  const std::string with_fiber =
      replace_once(kFabric, "[[step]]\nname = \"weave\"",
                   "[[fiber]]\nname = \"extra\"\nmaterial = \"glass\"\nradius = 1e-5\n"
                   "points = [[0, 0, 1], [1, 0, 1]]\nelements = 500\n\n[[step]]\nname = \"weave\"");
  const Case c = parse_case_toml(with_fiber, "fabric.toml");
  ASSERT_EQ(c.fibers.size(), 15u);
  const ModelSize fabric = fabric_size(*c.fabric);
  EXPECT_EQ(fabric.elements, 6 * 8 + 8 * 8);
  ModelSize all = fabric;
  all += fiber_size(500);
  const SizeLimits between = memory_limits(0.5 * (all.bytes() + std::max(fabric.bytes(), fiber_size(500).bytes())));
  expect_input_error([&] { parse_case_toml(with_fiber, "fabric.toml", between); }, "fabric.toml", "fiber",
                     "the 1 fibers of the file (500 elements in all, with the fabric's 112) make a model too large");
}

}  // namespace
}  // namespace fibra
