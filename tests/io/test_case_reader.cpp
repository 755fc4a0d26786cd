#include "fibra/io/case_reader.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
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
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_EQ(a.bodies[i].name, b.bodies[i].name);
    expect_vec(a.bodies[i].center, b.bodies[i].center);
    EXPECT_EQ(a.bodies[i].axes, b.bodies[i].axes);
  }
  ASSERT_EQ(a.bindings.size(), b.bindings.size());
  for (std::size_t i = 0; i < a.bindings.size(); ++i) {
    EXPECT_EQ(a.bindings[i].body, b.bindings[i].body);
    EXPECT_EQ(a.bindings[i].line, b.bindings[i].line);
    EXPECT_EQ(a.bindings[i].bodies, b.bindings[i].bodies);
    ASSERT_EQ(a.bindings[i].ends.size(), b.bindings[i].ends.size());
    for (std::size_t k = 0; k < a.bindings[i].ends.size(); ++k) {
      expect_same_node(a.bindings[i].ends[k], b.bindings[i].ends[k]);
    }
  }
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    const StepSpec& x = a.steps[i];
    const StepSpec& y = b.steps[i];
    ASSERT_EQ(x.bodies.size(), y.bodies.size());
    for (std::size_t k = 0; k < x.bodies.size(); ++k) {
      EXPECT_EQ(x.bodies[k].name, y.bodies[k].name);
      EXPECT_EQ(x.bodies[k].has_displacement, y.bodies[k].has_displacement);
      EXPECT_EQ(x.bodies[k].displacement, y.bodies[k].displacement);
      EXPECT_EQ(x.bodies[k].has_rotation, y.bodies[k].has_rotation);
      EXPECT_EQ(x.bodies[k].rotation, y.bodies[k].rotation);
      EXPECT_EQ(x.bodies[k].force, y.bodies[k].force);
      EXPECT_EQ(x.bodies[k].moment, y.bodies[k].moment);
    }
  }
  EXPECT_DOUBLE_EQ(a.solver.binding_tolerance, b.solver.binding_tolerance);
  EXPECT_EQ(a.solver.max_binding_updates, b.solver.max_binding_updates);
  EXPECT_DOUBLE_EQ(a.solver.binding_stiffness, b.solver.binding_stiffness);
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
  EXPECT_TRUE(c.bodies.empty());
  EXPECT_TRUE(c.bindings.empty());
  EXPECT_TRUE(c.steps[0].bodies.empty());
  EXPECT_EQ(c.solver.binding_tolerance, solver_defaults.binding_tolerance);
  EXPECT_EQ(c.solver.max_binding_updates, solver_defaults.max_binding_updates);
  EXPECT_EQ(c.solver.binding_stiffness, solver_defaults.binding_stiffness);
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
binding_stiffness = 1e5
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
  EXPECT_DOUBLE_EQ(c.solver.binding_stiffness, 1e5);
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
    "solver": {"binding_stiffness": 0}
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
  EXPECT_DOUBLE_EQ(c.solver.binding_stiffness, 0.0);
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
    {"BindingStiffnessNegative", "binding_stiffness = 1e5", "binding_stiffness = -1", "solver.binding_stiffness",
     "expected a number >= 0 (0 = automatic), got -1"},
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
