#include "fibra/io/case_writer.hpp"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "io/case_compare.hpp"
#include "support/example_files.hpp"

namespace fibra {
namespace {

using test::expect_same_case;

/// parse -> write -> parse: the second case must equal the first (the written file is
/// also checked to read back to itself: writing is idempotent).
void expect_round_trip(const Case& c, const std::string& label, bool compare_fabric = true) {
  const std::string text = write_case_toml(c);
  Case again;
  try {
    again = parse_case_toml(text, label);
  } catch (const InputError& e) {
    FAIL() << "the written case does not read back: " << e.what() << "\n" << text;
  }
  SCOPED_TRACE(label);
  expect_same_case(c, again, compare_fabric);
  EXPECT_EQ(write_case_toml(again), text);
}

/// Every kind of entry of the schema except bodies (below), with values that print long.
const std::string kEverything = R"(title = "Everything: \"quotes\", a back\\slash, a tab\t and ünïcödé"

[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[material]]
name = "carbon fibre"
model = "transverse"
young = 230.1e9
poisson = 0.2
young_transverse = 15e9
shear_axial = 25e9
poisson_transverse = 0.4

[[fiber]]
name = "beam"
material = "steel"
radius = 0.01
section_direction = [0.1, 2, 0.3]
points = [[0, 0, 0], [0.1, 0.2, 0.3], [0.5, 1e-17, -0], [1, 0, 0], [1.1, 0.1, 0]]
elements = 20

[[fiber]]
name = "ring"
material = "carbon fibre"
semi_axes = [0.002, 0.001]
arc = { center = [0, 0, 1], axis = [0.3, 0.1, 2], radius = 0.5, start_angle = 33.3, angle = -181.7 }
elements = 8

[[fiber]]
name = "spring"
material = "steel"
radius = 0.001
helix = { center = [1, 1, 0], axis = [0, 3, 0], radius = 0.05, pitch = 0.02, turns = 3.5, start_angle = 123.456 }
elements = 30

[[fiber]]
name = "disc"
material = "steel"
semi_axes = [0.003, 0.003]
arc = { radius = 0.1, angle = 0.1 }
elements = 2

[[fix]]
fiber = "beam"
node = "first"

[[fix]]
fiber = "ring"
node = 0
dofs = "position"

[[fix]]
fiber = "spring"
at = 0.3333333333333333
dofs = "sections"

[[fix]]
fiber = "beam"
node = "last"
dofs = ["y", "g1", "g2z"]

[[fix]]
fiber = "disc"
node = 3
dofs = ["x", "z", "g1x", "g1y", "g2"]

[[step]]
name = "load"
increments = 10
max_increments = 200

  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -1000.000001]
  moment = [1, 2, 3]

  [[step.load]]
  fiber = "ring"
  at = 0.7
  moment = [0, 0, 1e-300]

  [[step.displacement]]
  fiber = "ring"
  node = 16
  value = [0.01, 0, "free"]

[[step]]
kind = "relax"
  [[step.displacement]]
  fiber = "spring"
  at = 1
  value = ["free", 2e-7, "free"]

[solver]
residual_tolerance = 1e-6
displacement_tolerance = 1e-9
max_iterations = 30
max_cuts = 5
linear_solver = "eigen"
krylov_precision = "single"
binding_tolerance = 3e-7
max_binding_updates = 7

[contact]
friction = 0.3
max_penetration = 0.07
elastic_slip = 1e-7
stiffness = 1e6
regularization = 0.25
margin = 1e-4
spacing = 2e-4
self_exclusion = 5e-3
max_detections = 3
max_normal_updates = 11
normal_tolerance = 1e-4

[output]
every = 3
tube_sides = 7
plots = false
)";

/// Bodies in a two-level hierarchy (fiber ends -> tows -> grip), a turned frame, body steps
/// with free components, forces and moments.
const std::string kHierarchy = R"(
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
axes = [[0.6, 0.8, 0], [-0.8, 0.6, 0], [0, 0, 1]]

[[body]]
name = "towA"
center = [1, 0.05, 0]

[[body]]
name = "towB"
center = [1, 0.2, 0]

[[binding]]
body = "towA"
ends = [{ fiber = "f1", node = "last" }, { fiber = "f2", at = 1 }, { fiber = "f1", node = 7 }]

[[binding]]
body = "towB"
ends = [{ fiber = "f3", node = 8 }]
grip = [1, 3]
spin = true

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

  [[step.body]]
  name = "towB"
  moment = [0, 0, 0.25]
)";

/// A general assembly with tows and a weave pattern: weave, relax and standard steps.
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
name = "warp0"
direction = "warp"
index = 0
fibers = ["w0"]

[[tow]]
name = "warp1"
direction = "warp"
index = 1
fibers = ["w1"]

[[tow]]
name = "weft0"
direction = "weft"
index = 0
fibers = ["f0"]

[[tow]]
name = "weft1"
direction = "weft"
index = 1
fibers = ["f1"]

[weave]
matrix = [[1, 0], [0, 1]]

[[fix]]
fiber = "w0"
node = "first"

[[step]]
name = "weave"
kind = "weave"
increments = 5

[[step]]
name = "relax"
kind = "relax"

[[step]]
name = "pull"

[contact]
)";

/// A small fabric (2 x 2 tows of 3 fibers): the reader expands it; the writer writes the
/// expanded assembly.
const std::string kFabric = R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22

[fabric]
pattern = "plain"
warp = { tows = 2, spacing = 1.0e-3 }
weft = { tows = 2, spacing = 1.1e-3, tow = { fibers = 4 } }
tension = 0.01

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

[contact]
friction = 0.2
)";

// ------------------------------------------------------------------------------------------

TEST(CaseWriter, RoundTripsEveryPartOfTheSchema) {
  const Case c = parse_case_toml(kEverything, "everything.toml");
  ASSERT_EQ(c.fixes.size(), 5u);
  expect_round_trip(c, "everything.toml");
}

TEST(CaseWriter, RoundTripsTheExamples) {
  int count = 0;
  for (const std::filesystem::path& file : test::standalone_examples()) {
    const Case c = read_case(file.string());
    // A fabric is written expanded (no [fabric] table): everything else must match.
    expect_round_trip(c, file.string(), !c.fabric.has_value());
    ++count;
  }
  EXPECT_GE(count, 7);
}

TEST(CaseWriter, RoundTripsBodiesAndAHierarchy) {
  const Case c = parse_case_toml(kHierarchy, "hierarchy.toml");
  ASSERT_EQ(c.bindings.size(), 3u);
  ASSERT_EQ(c.bindings[1].grip, (std::vector<int>{1, 3}));
  ASSERT_TRUE(c.bindings[1].spin);
  ASSERT_FALSE(c.bindings[0].spin);
  expect_round_trip(c, "hierarchy.toml");
}

TEST(CaseWriter, RoundTripsTowsWeaveAndStepKinds) {
  const Case c = parse_case_toml(kTows, "tows.toml");
  ASSERT_EQ(c.tows.size(), 4u);
  ASSERT_EQ(c.steps[0].kind, StepSpec::Kind::Weave);
  expect_round_trip(c, "tows.toml");
  // The weave given by name is written as its matrix.
  std::string named = kTows;
  named.replace(named.find("matrix = [[1, 0], [0, 1]]"), 25, "pattern = \"twill 2/1\"");
  const Case twill = parse_case_toml(named, "tows.toml");
  ASSERT_EQ(twill.weave.size(), 3u);
  const std::string text = write_case_toml(twill);
  EXPECT_NE(text.find("[weave]\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("pattern"), std::string::npos) << text;
  expect_round_trip(twill, "tows.toml");
}

TEST(CaseWriter, WritesTheExpandedFabric) {
  const Case c = parse_case_toml(kFabric, "fabric.toml");
  ASSERT_TRUE(c.fabric.has_value());
  ASSERT_FALSE(c.fibers.empty());
  const std::string text = write_case_toml(c);
  EXPECT_EQ(text.find("fabric"), std::string::npos) << "a written case holds no [fabric]:\n" << text;
  const Case again = parse_case_toml(text, "fabric.toml");
  EXPECT_FALSE(again.fabric.has_value());
  expect_same_case(c, again, /*compare_fabric=*/false);
  EXPECT_EQ(write_case_toml(again), text);
}

TEST(CaseWriter, DefaultsStayDefaults) {
  // Automatic settings are written so that they read back automatic: the method's rules are
  // not written, zeros of the contact table stay zeros, no [contact] without contact.
  const Case c = parse_case_toml(kHierarchy, "hierarchy.toml");
  const std::string text = write_case_toml(c);
  EXPECT_EQ(text.find("max_step"), std::string::npos) << text;
  EXPECT_EQ(text.find("relax_drag"), std::string::npos) << text;
  EXPECT_EQ(text.find("[contact]"), std::string::npos) << text;
  const Case contact = parse_case_toml(kTows, "tows.toml");
  EXPECT_NE(write_case_toml(contact).find("[contact]"), std::string::npos);
}

TEST(CaseWriter, AnglesReadBackExactly) {
  // Arcs and helices hold radians, the file degrees: angles read from degrees are written as
  // degrees that read back to the same radians.
  constexpr double kDegree = std::numbers::pi / 180.0;  // as the reader converts
  Case c = parse_case_toml(kEverything, "everything.toml");
  FiberSpec& ring = c.fibers[1];
  for (int k = 1; k < 500; ++k) {
    ring.path.angle = (0.0137 * k * k - 3.3) * kDegree;
    ring.path.start_angle = (-0.91 * k + 1.0 / k) * kDegree;
    const Case again = parse_case_toml(write_case_toml(c), "angles.toml");
    ASSERT_EQ(again.fibers[1].path.angle, ring.path.angle) << k;
    ASSERT_EQ(again.fibers[1].path.start_angle, ring.path.start_angle) << k;
  }
}

TEST(CaseWriter, NumbersAreWrittenInFull) {
  Case c = parse_case_toml(kHierarchy, "hierarchy.toml");
  c.bodies[1].center = Vec3(0.1 + 0.2, 1.0 / 3.0, -2.0e-310);  // subnormal too
  c.materials[0].young = 2.0e11 + 1.0 / 7.0;
  const Case again = parse_case_toml(write_case_toml(c), "numbers.toml");
  EXPECT_EQ(again.bodies[1].center, c.bodies[1].center);
  EXPECT_EQ(again.materials[0].young, c.materials[0].young);
}

TEST(CaseWriter, ListsAreWrittenOnePerLineWhenLong) {
  const Case c = parse_case_toml(kFabric, "fabric.toml");
  const std::string text = write_case_toml(c);
  // A tow-end binding of 3 fiber ends and a weft tow of 4 fibers.
  EXPECT_NE(text.find("ends = [\n  { fiber = \"warp0.f0\", node = \"first\" },\n"), std::string::npos) << text;
  EXPECT_NE(text.find("fibers = [\"weft1.f0\", \"weft1.f1\", \"weft1.f2\", \"weft1.f3\"]\n"), std::string::npos)
      << text;
}

}  // namespace
}  // namespace fibra
