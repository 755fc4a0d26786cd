// The command-line program (FIBRA_BINARY_DIR/fibra) end to end: exit codes, error messages on
// stderr naming the file and the key, the outputs of a run that fails to converge, and the
// rigid-body outputs and binding errors.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"
#include "fibra/io/nodes_csv.hpp"
#include "fibra/io/slice.hpp"
#include "io/case_compare.hpp"
#include "support/curve_checks.hpp"
#include "support/fabric_cases.hpp"
#include "support/scratch_dir.hpp"
#include "support/slice_files.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

using Result = test::CliResult;
using test::slurp;

class Cli : public test::ScratchDirTest {
 protected:
  Cli() : ScratchDirTest("fibra_cli_") {}

  // Runs `fibra ARGS` in the temporary directory, capturing stdout and stderr.
  Result fibra(const std::string& args) const { return test::run_fibra(m_dir, args); }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = m_dir / name;
    std::ofstream(p) << text;
    return p;
  }

};

const std::string kGood = R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[fiber]]
name = "beam"
material = "steel"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[fix]]
fiber = "beam"
node = "first"

[[step]]
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -1]
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Without a terminal a run prints no progress; with --progress one line per increment.
TEST_F(Cli, ProgressLinesOnRequest) {
  write("good.toml", replace(kGood, "[[step]]", "[[step]]\nincrements = 3"));
  const Result quiet = fibra("run good.toml --out quiet");
  EXPECT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  const Result r = fibra("run good.toml --out loud --progress");
  EXPECT_EQ(r.code, 0) << r.err;
  int lines = 0;
  for (size_t at = r.err.find("step 1"); at != std::string::npos; at = r.err.find("step 1", at + 1)) ++lines;
  EXPECT_EQ(lines, 3) << r.err;
  EXPECT_NE(r.err.find("load 1.0000"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 3) << r.err;
}

TEST_F(Cli, CheckAcceptsTheExample) {
  const Result r = fibra("check '" + std::string(FIBRA_SOURCE_DIR) + "/examples/cantilever/cantilever.toml'");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("valid"), std::string::npos) << r.out;
}

TEST_F(Cli, CheckRejectsAnOutOfRangePoissonRatio) {
  write("poisson.toml", replace(kGood, "poisson = 0.3", "poisson = 0.6"));
  const Result r = fibra("check poisson.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("poisson.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("material[0].poisson"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0.6"), std::string::npos) << r.err;
}

TEST_F(Cli, CheckRejectsAnUnknownKey) {
  write("unknown.toml", replace(kGood, "radius = 0.01", "radiuss = 0.01"));
  const Result r = fibra("check unknown.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fiber[0].radiuss"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\"radius\""), std::string::npos) << r.err;  // the suggestion
}

TEST_F(Cli, CheckRejectsAMissingMaterial) {
  // A fiber naming a material that is not defined ...
  write("undefined.toml", replace(kGood, "material = \"steel\"", "material = \"titanium\""));
  Result r = fibra("check undefined.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("undefined.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fiber[0].material"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("titanium"), std::string::npos) << r.err;
  // ... and a file without any [[material]].
  write("none.toml", replace(kGood, "[[material]]\nname = \"steel\"\nyoung = 210e9\npoisson = 0.3\n", ""));
  r = fibra("check none.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("none.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": material:"), std::string::npos) << r.err;
}

TEST_F(Cli, RunThatCannotConvergeFailsAndKeepsItsOutputs) {
  // A huge load (tip deflection >> L by linear theory) in one increment, two Newton iterations,
  // no cuts allowed: the first increment must fail.
  write("diverge.toml", replace(replace(kGood, "force = [0, 0, -1]", "force = [0, 0, -1e7]"), "[[step]]",
                                "[solver]\nmax_cuts = 0\nmax_iterations = 2\n\n[[step]]\nname = \"crush\""));
  const Result r = fibra("run diverge.toml --out out");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.code, 2);  // not an input error
  EXPECT_NE(r.err.find("failed"), std::string::npos) << r.err;
  ASSERT_TRUE(fs::is_regular_file(m_dir / "out" / "history.csv")) << r.err;
  EXPECT_NE(slurp(m_dir / "out" / "history.csv").find("step,step_index,increment"), std::string::npos);
  ASSERT_TRUE(fs::is_regular_file(m_dir / "out" / "summary.json"));
  const nlohmann::json s = nlohmann::json::parse(slurp(m_dir / "out" / "summary.json"));
  EXPECT_EQ(s.value("status", ""), "failed");
  EXPECT_EQ(s.value("converged", true), false);
  ASSERT_TRUE(s.contains("stopped_at")) << s.dump(2);
  EXPECT_EQ(s["stopped_at"].value("step", ""), "crush");
  EXPECT_EQ(s["stopped_at"].value("load_factor", -1.0), 0.0);
  EXPECT_EQ(s["stopped_at"].value("attempted_load_factor", -1.0), 1.0);
  EXPECT_NE(s.value("message", "").find("did not converge after 0 cuts"), std::string::npos) << s.dump(2);

  // With cuts allowed but one increment at most, the message says the increment limit stopped it.
  write("limited.toml", replace(replace(kGood, "force = [0, 0, -1]", "force = [0, 0, -1e7]"), "[[step]]",
                                "[solver]\nmax_iterations = 2\n\n[[step]]\nname = \"crush\"\nmax_increments = 1"));
  const Result l = fibra("run limited.toml --out out2");
  EXPECT_NE(l.code, 0);
  EXPECT_NE(l.err.find("stopped at load factor 0 after 1 increments tried (max_increments 1)"), std::string::npos)
      << l.err;
}

TEST_F(Cli, RunOfAValidCaseSucceeds) {
  write("good.toml", kGood);
  const Result r = fibra("run good.toml --out out");
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* name : {"history.csv", "nodes.csv", "fibers.pvd", "summary.json"})
    EXPECT_TRUE(fs::is_regular_file(m_dir / "out" / name)) << name;
}

// ------------------------------------------------------------------------------------------
// Rigid bodies and averaged bindings through the program: the bundle_pull example's outputs,
// and the binding errors that are found when the model is built (still exit code 2).

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, ',')) out.push_back(field);
  return out;
}

TEST_F(Cli, RunOfTheBundleExampleWritesTheBodyOutputs) {
  const fs::path file = fs::path(FIBRA_SOURCE_DIR) / "examples" / "bundle_pull" / "bundle_pull.toml";
  const Result r = fibra("run '" + file.string() + "' --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path out = m_dir / "out";

  // history.csv: the body's and the binding's columns.
  std::ifstream in(out / "history.csv");
  std::string header, line, last;
  ASSERT_TRUE(std::getline(in, header));
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  const std::vector<std::string> columns = split_csv(header);
  for (const char* name : {"body:grip:fx", "body:grip:mz", "body:grip:ux", "body:grip:rz", "binding:updates",
                           "binding:max_violation"})
    EXPECT_NE(std::find(columns.begin(), columns.end(), name), columns.end()) << name << " not in " << header;

  // The last row: the grip is where the example's last step puts it.
  const Case c = read_case(file.string());
  ASSERT_FALSE(c.steps.empty());
  ASSERT_EQ(c.steps.back().bodies.size(), 1u);
  ASSERT_TRUE(c.steps.back().bodies[0].displacement[0].has_value());
  const double prescribed = *c.steps.back().bodies[0].displacement[0];
  EXPECT_GT(prescribed, 0.0);
  const std::vector<std::string> row = split_csv(last);
  ASSERT_EQ(row.size(), columns.size()) << last;
  const size_t ux = std::find(columns.begin(), columns.end(), "body:grip:ux") - columns.begin();
  ASSERT_LT(ux, row.size());
  EXPECT_NEAR(std::stod(row[ux]), prescribed, 1e-12 * prescribed) << last;
  EXPECT_EQ(row[0], c.steps.back().name);

  // bodies.pvd and its .vtu files.
  EXPECT_TRUE(fs::is_regular_file(out / "bodies.pvd"));
  int vtus = 0;
  for (const fs::directory_entry& f : fs::directory_iterator(out / "bodies")) {
    const std::string name = f.path().filename().string();
    if (name.rfind("bodies_", 0) == 0 && f.path().extension() == ".vtu") ++vtus;
  }
  EXPECT_GE(vtus, 1);
  EXPECT_NE(slurp(out / "bodies.pvd").find("file=\"bodies/bodies_"), std::string::npos);

  // summary.json counts the body and the binding.
  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s.value("status", ""), "converged");
  ASSERT_TRUE(s.contains("counts")) << s.dump(2);
  EXPECT_EQ(s["counts"].value("bodies", -1), 1) << s.dump(2);
  EXPECT_EQ(s["counts"].value("bindings", -1), 1) << s.dump(2);
}

// Three fibers whose ends, bound to "grip", are not on one line (b is out of the plane z = 0).
const std::string kBound = R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[fiber]]
name = "a"
material = "steel"
radius = 1e-4
points = [[0, -1e-3, 0], [0.01, -1e-3, 0]]
elements = 2

[[fiber]]
name = "b"
material = "steel"
radius = 1e-4
points = [[0, 0, 1e-3], [0.01, 0, 1e-3]]
elements = 2

[[fiber]]
name = "c"
material = "steel"
radius = 1e-4
points = [[0, 1e-3, 0], [0.01, 1e-3, 0]]
elements = 2

[[fix]]
fiber = "a"
node = "first"

[[fix]]
fiber = "b"
node = "first"

[[fix]]
fiber = "c"
node = "first"

[[body]]
name = "grip"
center = [0.01, 0, 0]

[[binding]]
body = "grip"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]

[[step]]
  [[step.body]]
  name = "grip"
  displacement = [1e-5, 0, 0]
)";

TEST_F(Cli, CheckAcceptsABindingOfThreeEndsNotOnALine) {
  write("bound.toml", kBound);
  const Result r = fibra("check bound.toml");
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST_F(Cli, CheckRejectsABindingWhoseEndsLieOnOneLine) {
  // b moved into the plane z = 0: the three ends lie on the line x = 0.01, z = 0.
  write("collinear.toml",
        replace(kBound, "points = [[0, 0, 1e-3], [0.01, 0, 1e-3]]", "points = [[0, 0, 0], [0.01, 0, 0]]"));
  const Result r = fibra("check collinear.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("collinear.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("binding[0]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("one line"), std::string::npos) << r.err;
}

TEST_F(Cli, CheckRejectsABodyWithoutMembers) {
  // A second body that no [[binding]] names.
  write("lonely.toml", replace(kBound, "[[binding]]", "[[body]]\nname = \"spare\"\ncenter = [0, 0, 0]\n\n[[binding]]"));
  const Result r = fibra("check lonely.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("lonely.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("body[1]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("spare"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("has no members"), std::string::npos) << r.err;
}

// ------------------------------------------------------------------------------------------
// fibra generate (the assembly a [fabric] generates, as a plain case file, its ParaView views
// and slices) and fibra slice (slices of a run's final state).

/// A small fabric: 2 x 2 tows of 3 fibers, 2 elements per fiber.
const std::string kSmallFabric = R"(
title = "Small fabric"

[[material]]
name = "glass"
young = 72e9
poisson = 0.22

[fabric]
pattern = "plain"
warp = { tows = 2, spacing = 1.0e-3 }
weft = { tows = 2, spacing = 1.0e-3 }

  [fabric.tow]
  fibers = 3
  width = 0.8e-3
  thickness = 0.2e-3

  [fabric.fiber]
  radius = 2.0e-5
  material = "glass"
  element_length = 1.0e-3

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

bool is_png(const fs::path& p) {
  const std::string s = slurp(p);
  return s.size() > 8 && s.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0 &&
         s.find("IEND") == s.size() - 8;
}

TEST_F(Cli, GenerateWritesThePlainCaseItsViewsAndSlices) {
  write("fabric.toml", kSmallFabric);
  const Result r = fibra("generate fabric.toml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("12 fibers"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("4 tows"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fabric_generated"), std::string::npos) << r.out;
  const fs::path dir = m_dir / "fabric_generated";
  for (const char* name : {"fabric.toml", "fibers.pvd", "lines.pvd", "bodies.pvd", "fibers/fibers_000000.vtu",
                           "lines/lines_000000.vtu", "bodies/bodies_000000.vtu", "slices/slice_x.svg", "slices/slice_y.svg"})
    EXPECT_TRUE(fs::is_regular_file(dir / name)) << name << "\n" << r.out;
  EXPECT_FALSE(fs::exists(dir / "history.csv"));  // nothing was run
  EXPECT_FALSE(fs::exists(dir / "fibers" / "fibers_000001.vtu"));
  for (const char* name : {"slices/slice_x.png", "slices/slice_y.png"}) EXPECT_TRUE(is_png(dir / name)) << name;
  // The middle slices: x = 0 (between the wefts) cuts the 6 warp fibers, y = 0 the 6 weft fibers.
  EXPECT_NE(r.out.find("slices/slice_x.png (x = 0 mm)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("slices/slice_y.png (y = 0 mm)"), std::string::npos) << r.out;
  // One path per cut in its tow's colour (warp0, warp1: 3 each), and the legend's swatch.
  const std::string svg_x = slurp(dir / "slices" / "slice_x.svg"), svg_y = slurp(dir / "slices" / "slice_y.svg");
  EXPECT_EQ(test::xml_error(svg_x), "");
  EXPECT_EQ(test::xml_error(svg_y), "");
  const std::vector<test::Colour> fills_x = test::svg_path_fills(svg_x), fills_y = test::svg_path_fills(svg_y);
  EXPECT_EQ(test::count_colour(fills_x, test::kSliceWarp[0]), 3 + 1);
  EXPECT_EQ(test::count_colour(fills_x, test::kSliceWarp[1]), 3);
  EXPECT_EQ(test::count_colour(fills_x, test::kSliceWeft[0]) + test::count_colour(fills_x, test::kSliceWeft[1]), 0);
  EXPECT_EQ(test::count_colour(fills_y, test::kSliceWeft[0]), 3 + 1);
  EXPECT_EQ(test::count_colour(fills_y, test::kSliceWeft[1]), 3);
  EXPECT_EQ(test::count_colour(fills_y, test::kSliceWarp[0]) + test::count_colour(fills_y, test::kSliceWarp[1]), 0);
  // The bodies' view holds each body and its members: 4 + 8 bodies, each with members.
  EXPECT_NE(slurp(dir / "bodies" / "bodies_000000.vtu").find("NumberOfPoints"), std::string::npos);

  // The written case is a plain case that check accepts and that reads back to the same
  // fibers, bodies, bindings, tows and weave.
  const std::string text = slurp(dir / "fabric.toml");
  EXPECT_EQ(text.find("[fabric]"), std::string::npos);
  const Result check = fibra("check fabric_generated/fabric.toml");
  EXPECT_EQ(check.code, 0) << check.err;
  EXPECT_NE(check.out.find("12 fibers"), std::string::npos) << check.out;
  const Case original = read_case((m_dir / "fabric.toml").string());
  const Case again = read_case((dir / "fabric.toml").string());
  EXPECT_FALSE(again.fabric.has_value());
  test::expect_same_case(original, again, /*compare_fabric=*/false);

  // --out names the directory.
  const Result other = fibra("generate fabric.toml --out gen/here");
  ASSERT_EQ(other.code, 0) << other.err;
  EXPECT_TRUE(fs::is_regular_file(m_dir / "gen" / "here" / "fabric.toml"));
  EXPECT_TRUE(fs::is_regular_file(m_dir / "gen" / "here" / "slices" / "slice_y.png"));
}

TEST_F(Cli, GenerateOfABadCaseIsAnInputError) {
  write("fabric.toml", replace(kSmallFabric, "fibers = 3", "fibers = 300"));  // do not fit in the tow
  Result r = fibra("generate fabric.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("fabric.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fabric"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(m_dir / "fabric_generated"));
  r = fibra("generate missing.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("missing.toml"), std::string::npos) << r.err;
}

// A model too large is refused while the case is read, by check, run and generate alike: exit
// code 2, the file, the key and the estimated size, no output directory.
TEST_F(Cli, ModelsTooLargeAreRefusedWithTheKeyAndTheSize) {
  write("huge.toml", replace(kGood, "elements = 4", "elements = 2000000000"));
  for (const std::string command : {"check huge.toml", "run huge.toml --out huge_out"}) {
    const Result r = fibra(command);
    EXPECT_EQ(r.code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("error: huge.toml: fiber[0].elements: 2000000000 elements make a model too large to run: "
                         "estimated 2e+09 elements, 4e+09 nodes, 3.6e+10 dofs, 6.66e+11 stiffness matrix entries "
                         "and at least "),
              std::string::npos)
        << command << ": " << r.err;
    EXPECT_NE(r.err.find("(32-bit indices)"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(m_dir / "huge_out"));

  // A fabric's element length of a picometre: 6 warp fibers of 2 mm in 2e9 elements each.
  write("pico.toml", replace(kSmallFabric, "element_length = 1.0e-3", "element_length = 1e-12"));
  for (const std::string command : {"check pico.toml", "run pico.toml --out pico_out", "generate pico.toml"}) {
    const Result r = fibra(command);
    EXPECT_EQ(r.code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("error: pico.toml: fabric.fiber.element_length: 1e-12 m cuts each of the 6 warp fibers "
                         "(0.002 m long) into 2e+09 elements: a model too large to run: estimated 2.4e+10 elements"),
              std::string::npos)
        << command << ": " << r.err;
    EXPECT_NE(r.err.find("TiB of memory"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(m_dir / "pico_out"));
  EXPECT_FALSE(fs::exists(m_dir / "pico_generated"));
}

/// Two cantilevers along x (tows "A" warp and "B" weft), bent down by a tip load.
const std::string kTwoBeams = R"(
title = "Two beams"

[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[fiber]]
name = "a"
material = "steel"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[fiber]]
name = "b"
material = "steel"
radius = 0.01
points = [[0, 0.1, 0], [1, 0.1, 0]]
elements = 4

[[tow]]
name = "A"
direction = "warp"
index = 0
fibers = ["a"]

[[tow]]
name = "B"
direction = "weft"
index = 0
fibers = ["b"]

[[fix]]
fiber = "a"
node = "first"

[[fix]]
fiber = "b"
node = "first"

[[step]]
  [[step.load]]
  fiber = "a"
  node = "last"
  force = [0, 0, -1]

  [[step.load]]
  fiber = "b"
  node = "last"
  force = [0, 0, -2]
)";

// A biaxial step after the weaving writes curves_<step>.csv: a row at the step's start and one
// per load level, whose numbers are the edge bodies' in history.csv at the same increments.
TEST_F(Cli, BiaxialStepWritesItsCurves) {
  // The friction sample of the weaving tests (kSmallFabric's elements of 1 mm are too coarse
  // for a test: its first level did not settle).
  write("fabric.toml", test::plain_friction_sample(R"([[step]]
name = "pull"
kind = "biaxial"
strain = 0.004
increments = 2
)"));
  const Result r = fibra("run fabric.toml --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path out = m_dir / "out";
  ASSERT_TRUE(fs::is_regular_file(out / "curves_pull.csv")) << r.out;
  std::ifstream in(out / "curves_pull.csv");
  std::string header, line;
  ASSERT_TRUE(std::getline(in, header));
  EXPECT_EQ(header,
            "step,increment,load_factor,warp_strain,weft_strain,warp_force,weft_force,shear_angle_deg,shear_force,"
            "contact_elements,max_penetration_ratio");
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line))
    if (!line.empty()) rows.push_back(split_csv(line));
  ASSERT_EQ(rows.size(), 3u);
  const double loads[3] = {0.0, 0.5, 1.0};
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(rows[k].size(), 11u);
    EXPECT_EQ(rows[k][0], "pull");
    EXPECT_NEAR(std::stod(rows[k][2]), loads[k], 1e-12);
    EXPECT_NEAR(std::stod(rows[k][3]), 0.004 * loads[k], 1e-12);  // warp strain
    EXPECT_NEAR(std::stod(rows[k][4]), 0.004 * loads[k], 1e-12);  // ratio 1: the weft alike
  }
  EXPECT_GT(std::stod(rows[2][5]), std::stod(rows[0][5]));  // the warp force grows

  // history.csv holds the same forces at the same increments.
  std::ifstream hin(out / "history.csv");
  ASSERT_TRUE(std::getline(hin, header));
  const std::vector<std::string> columns = split_csv(header);
  auto column = [&](const std::string& name) {
    return static_cast<size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin());
  };
  const size_t fx = column("body:edge.x+:fx"), fy = column("body:edge.y+:fy"), inc = column("increment");
  ASSERT_LT(fx, columns.size());
  ASSERT_LT(fy, columns.size());
  int matched = 0;
  while (std::getline(hin, line)) {
    const std::vector<std::string> h = split_csv(line);
    if (h.empty() || h[0] != "pull") continue;
    for (int k = 1; k < 3; ++k)
      if (h[inc] == rows[k][1]) {
        EXPECT_DOUBLE_EQ(std::stod(h[fx]), std::stod(rows[k][5]));
        EXPECT_DOUBLE_EQ(std::stod(h[fy]), std::stod(rows[k][6]));
        ++matched;
      }
  }
  EXPECT_EQ(matched, 2);

  // The drag columns: the weave's drag is one constant; the relax starts from it (the stiffest
  // drag: the initial penalty) and adapts; the test's levels are dragged
  // too and their last increments settle below the test tolerance.
  hin.clear();
  hin.seekg(0);
  std::getline(hin, header);
  const size_t drag = column("relax:drag"), force = column("relax:drag_residual"), step = column("step"),
               its = column("iterations");
  ASSERT_LT(drag, columns.size());
  ASSERT_LT(force, columns.size());
  std::map<std::string, std::vector<double>> drags, forces;
  std::vector<int> relax_its;
  while (std::getline(hin, line)) {
    const std::vector<std::string> h = split_csv(line);
    if (h.size() != columns.size()) continue;
    drags[h[step]].push_back(std::stod(h[drag]));
    forces[h[step]].push_back(std::stod(h[force]));
    if (h[step] == "relax") relax_its.push_back(std::stoi(h[its]));
  }
  ASSERT_FALSE(drags["weave"].empty());
  ASSERT_FALSE(drags["relax"].empty());
  ASSERT_FALSE(drags["pull"].empty());
  for (double d : drags["weave"]) EXPECT_DOUBLE_EQ(d, drags["weave"].front());
  EXPECT_GT(drags["weave"].front(), 0.0);
  // The weave's drag: the stiffest, so a failed first attempt is cut, not stiffened.
  EXPECT_DOUBLE_EQ(drags["relax"].front(), drags["weave"].front());
  const double tries = std::log(drags["relax"].front() / drags["weave"].front()) / std::log(4.0);
  EXPECT_NEAR(tries, std::round(tries), 1e-9);
  EXPECT_GE(std::round(tries), 0.0);
  // After a failed attempt the drag stays above twice the drag that failed: an easy first
  // increment (at most 12 iterations) would quarter it, the floor holds it at half (times 4 per
  // failure of the second increment's own attempts); without failures, a quarter.
  ASSERT_GE(drags["relax"].size(), 2u);
  if (relax_its.front() <= 12) {
    const double expected = drags["relax"].front() * (std::round(tries) >= 1.0 ? 0.5 : 0.25);
    const double retries = std::log(drags["relax"][1] / expected) / std::log(4.0);
    EXPECT_NEAR(retries, std::round(retries), 1e-9) << drags["relax"][1] << " vs " << expected;
    EXPECT_GE(std::round(retries), 0.0);
  }
  for (double d : drags["relax"]) EXPECT_GT(d, 0.0);
  for (double d : drags["pull"]) EXPECT_GT(d, 0.0);
  for (double f : forces["weave"]) EXPECT_EQ(f, 0.0);
  EXPECT_LE(forces["relax"].back(), 1e-4);
  EXPECT_LE(forces["pull"].back(), 1e-4);

  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  ASSERT_TRUE(s.contains("curves")) << s.dump();
  EXPECT_EQ(s["curves"][0]["file"], "curves_pull.csv");
  EXPECT_EQ(s["curves"][0]["kind"], "biaxial");

  // The step's plots (tests/verification/test_plots.cpp has the rest): the sidecar shows the
  // curves' numbers, warp and weft; the PNG is one; the SVG has its axis labels as text.
  EXPECT_EQ(s["plots"], (nlohmann::json{"plots/pull.png", "plots/pull.svg", "plots/pull.json"})) << r.err;
  const nlohmann::json sidecar = test::read_sidecar(out / "plots" / "pull.json");
  ASSERT_EQ(sidecar["series"].size(), 2u);
  for (const nlohmann::json& series : sidecar["series"])
    test::expect_series_matches_csv(series, out / "plots" / "pull.json");
  EXPECT_EQ(test::png_size(out / "plots" / "pull.png"), std::make_pair(960u, 720u));
  const std::string svg = slurp(out / "plots" / "pull.svg");
  EXPECT_NE(svg.find("axial strain [%]"), std::string::npos);
  EXPECT_NE(svg.find("axial force [N]"), std::string::npos);
  EXPECT_TRUE(fs::is_regular_file(out / "slices" / "pull_x.svg"));
}

TEST_F(Cli, SliceOfARunWritesSvgAndPng) {
  write("beams.toml", kTwoBeams);
  const Result run = fibra("run beams.toml --out out");
  ASSERT_EQ(run.code, 0) << run.err;
  const fs::path out = m_dir / "out";
  if (!fs::exists(out / "case.toml"))  // written by the run; if not, as the run would
    std::ofstream(out / "case.toml") << write_case_toml(read_case((m_dir / "beams.toml").string()));

  Result r = fibra("slice out --plane x=0.5 --plane y=0.1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("2 fibers cut"), std::string::npos) << r.out;
  for (const char* name : {"slice_x_0.5.svg", "slice_x_0.5.png", "slice_y_0.1.svg", "slice_y_0.1.png"})
    EXPECT_TRUE(fs::is_regular_file(out / "slices" / name)) << name << "\n" << r.out;
  EXPECT_TRUE(is_png(out / "slices" / "slice_x_0.5.png"));
  // x = 0.5 cuts both beams across, where the final state has them (bent down): the SVG is the
  // drawing of the cuts of the state in nodes.csv, not of the reference state.
  const Case c = read_case((out / "case.toml").string());
  const Model model = build_model(c);
  const VecX q = read_nodes_csv((out / "nodes.csv").string(), model);
  const std::vector<SliceCut> final_cuts = slice_cuts(model, q, c.tows, 0, 0.5);
  ASSERT_EQ(final_cuts.size(), 2u);
  EXPECT_LT(final_cuts[0].center.y(), -1e-6);  // a, bent down [m]
  EXPECT_LT(final_cuts[1].center.y(), 1.5 * final_cuts[0].center.y());
  write_slice((m_dir / "final").string(), final_cuts, c.tows, 0, 0.5, "Two beams");
  write_slice((m_dir / "reference").string(), model, model.reference, c.tows, 0, 0.5, "Two beams");
  const std::string svg = slurp(out / "slices" / "slice_x_0.5.svg");
  EXPECT_EQ(test::xml_error(svg), "");
  EXPECT_EQ(svg, slurp(m_dir / "final.svg"));
  EXPECT_NE(svg, slurp(m_dir / "reference.svg"));
  const test::PngImage png = test::read_png((out / "slices" / "slice_x_0.5.png").string());
  const SlicePage page = slice_page(final_cuts);
  ASSERT_EQ(png.height, page.height) << png.error;
  for (const SliceCut& cut : final_cuts) {
    const Eigen::Vector2d p = page.to_page(cut.center);
    const test::Colour expected = cut.name == "a" ? test::kSliceWarp[0] : test::kSliceWeft[0];
    EXPECT_EQ(png.at(static_cast<int>(p.x()), static_cast<int>(p.y())), expected) << cut.name;
  }
  // y = 0.1 runs along b: a strip, one path in the weft's colour with the legend's swatch.
  bool strip = false;
  for (const SliceCut& cut : slice_cuts(model, q, c.tows, 1, 0.1)) strip |= cut.kind == SliceCut::Kind::Strip;
  EXPECT_TRUE(strip);
  EXPECT_EQ(test::count_colour(test::svg_path_fills(slurp(out / "slices" / "slice_y_0.1.svg")), test::kSliceWeft[0]),
            1 + 1);

  // --out: the stem (one plane), or stem_AXIS_VALUE (several).
  r = fibra("slice out --plane x=0.25 --out mine");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(m_dir / "mine.svg"));
  EXPECT_TRUE(is_png(m_dir / "mine.png"));
  r = fibra("slice out --plane x=0.25 --plane 'x = 0.75' --out pics/cut");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(m_dir / "pics" / "cut_x_0.25.svg"));
  EXPECT_TRUE(fs::is_regular_file(m_dir / "pics" / "cut_x_0.75.png"));
}

TEST_F(Cli, SliceInputErrors) {
  write("beams.toml", kTwoBeams);
  ASSERT_EQ(fibra("run beams.toml --out out").code, 0);
  const fs::path out = m_dir / "out";
  if (!fs::exists(out / "case.toml"))
    std::ofstream(out / "case.toml") << write_case_toml(read_case((m_dir / "beams.toml").string()));

  // A malformed plane, whatever else is wrong: nothing is written.
  for (const char* plane : {"x=abc", "w=0.5", "x0.5", "x=", "x=0.5mm", "x=nan"}) {
    const Result r = fibra(std::string("slice out --plane '") + plane + "'");
    EXPECT_EQ(r.code, 2) << plane << ": " << r.err;
    EXPECT_NE(r.err.find("--plane"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string("\"") + plane + "\""), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("x=0.5e-3"), std::string::npos) << r.err;  // an example of the form
  }
  EXPECT_FALSE(fs::exists(out / "slices"));

  // --tow and --stations: an unknown tow (the case's are listed), a count that is not one, one
  // without the other, both with --plane, neither.
  Result r = fibra("slice out --tow C --stations 3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--tow"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no tow named \"C\"; the case's tows: A, B"), std::string::npos) << r.err;
  for (const char* count : {"0", "-2", "abc", "2.5", "1000", "''"}) {
    r = fibra(std::string("slice out --tow A --stations ") + count);
    EXPECT_EQ(r.code, 2) << count << ": " << r.err;
    EXPECT_NE(r.err.find("--stations"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("an integer from 1 to 999"), std::string::npos) << r.err;
  }
  r = fibra("slice out --tow A");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--stations"), std::string::npos) << r.err;
  r = fibra("slice out --stations 3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--stations"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--tow"), std::string::npos) << r.err;
  r = fibra("slice out --tow A --stations 3 --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("either --plane or --tow"), std::string::npos) << r.err;
  r = fibra("slice out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--plane"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "slices"));

  // A plane that misses every fiber: where the fibers are.
  r = fibra("slice out --plane x=0.5 --plane y=3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("y=3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cuts no fiber"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("x from 0 to 1, y from "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" to 0.1, z from "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "slices")) << "no slice written when a plane is wrong";

  // A missing directory, a file instead, a directory without the run's files.
  r = fibra("slice nowhere --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no such directory"), std::string::npos) << r.err;
  r = fibra("slice beams.toml --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("not a directory"), std::string::npos) << r.err;
  fs::remove(out / "nodes.csv");
  r = fibra("slice out --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("nodes.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not found"), std::string::npos) << r.err;
  fs::remove(out / "case.toml");
  r = fibra("slice out --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("case.toml"), std::string::npos) << r.err;
  // nodes.csv of another case.
  fs::create_directories(m_dir / "other");
  std::ofstream(m_dir / "other" / "case.toml") << write_case_toml(read_case((m_dir / "beams.toml").string()));
  std::ofstream(m_dir / "other" / "nodes.csv") << "fiber,node,x,y,z,g1x,g1y,g1z,g2x,g2y,g2z\nzz,0,0,0,0,0,1,0,0,0,1\n";
  r = fibra("slice other --plane x=0.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("nodes.csv: line 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("zz"), std::string::npos) << r.err;
}

// A woven and relaxed plain weave: the slices of a warp tow at four stations (the tow alone,
// each fiber of it cut once, the planes evenly spaced), and a slice along that tow showing it
// waving over and under the wefts it crosses.
TEST_F(Cli, SliceOfAWovenRunShowsATowsStationsAndTheWeaveAlongIt) {
  write("fabric.toml", test::plain_friction_sample());
  ASSERT_EQ(fibra("run fabric.toml --out out").code, 0);
  const fs::path out = m_dir / "out";
  Result r = fibra("slice out --tow warp0 --stations 4");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("tow warp0: 4 stations"), std::string::npos) << r.out;
  const Case c = read_case((out / "case.toml").string());
  const Model model = build_model(c);
  const VecX q = read_nodes_csv((out / "nodes.csv").string(), model);
  int warp0 = -1;
  for (size_t t = 0; t < c.tows.size(); ++t)
    if (c.tows[t].name == "warp0") warp0 = static_cast<int>(t);
  ASSERT_GE(warp0, 0);
  const TowSpec& tow = c.tows[warp0];
  ASSERT_EQ(tow.fibers.size(), 3u);
  const TowStations st = tow_stations(model, q, tow, 4);
  EXPECT_GT(st.direction.x(), 0.99);
  int height = 0;
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(st.planes[k].offset - st.start, (k + 1) * (st.end - st.start) / 5, 1e-12) << k;
    // Every fiber of the tow cut once, as a crossing.
    std::map<std::string, int> cut;
    for (const SliceCut& s : slice_cuts(model, q, c.tows, st.planes[k]))
      if (s.tow == warp0) {
        EXPECT_EQ(s.kind, SliceCut::Kind::Crossing) << s.name;
        ++cut[s.name];
      }
    for (const std::string& f : tow.fibers) EXPECT_EQ(cut[f], 1) << f << " at station " << k + 1;
    // The files: the tow's three fibers only (warp0's colour, with the swatch), one page size.
    const std::string stem = fmt::format("out/slices/tow_warp0_0{}", k + 1);
    EXPECT_NE(r.out.find(stem + ".svg"), std::string::npos) << r.out;
    const std::string svg = slurp(m_dir / (stem + ".svg"));
    EXPECT_EQ(test::xml_error(svg), "") << stem;
    const std::vector<test::Colour> fills = test::svg_path_fills(svg);
    EXPECT_EQ(test::count_colour(fills, test::kSliceWarp[0]), 3 + 1) << stem;
    for (const test::Colour& weft : test::kSliceWeft) EXPECT_EQ(test::count_colour(fills, weft), 0) << stem;
    const test::PngImage png = test::read_png((m_dir / (stem + ".png")).string());
    EXPECT_EQ(png.width, 1200) << png.error;
    if (k == 0) height = png.height;
    EXPECT_EQ(png.height, height) << "the stations share one frame";
  }
  EXPECT_FALSE(fs::exists(out / "slices" / "tow_warp0_05.svg"));
  r = fibra("slice out --tow weft1 --stations 2 --out pics/w");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name : {"w_01.svg", "w_01.png", "w_02.svg", "w_02.png"})
    EXPECT_TRUE(fs::is_regular_file(m_dir / "pics" / name)) << name;

  // Along the tow: the plane y through its middle fiber cuts that fiber along its length as
  // strips, the wefts across; the fiber runs above one weft and below the other.
  const Fiber& middle = model.fibers[model.fiber_index(tow.fibers[1])];
  double y = 0;
  for (Index k = 0; k < middle.num_nodes; ++k) y += q[kNodeDofs * (middle.first_node + k) + 1];
  y /= static_cast<double>(middle.num_nodes);
  int strips = 0;
  std::map<std::string, double> weft_z;  // the mean z of each weft's crossings
  std::map<std::string, int> weft_n;
  std::vector<const SliceCut*> along;
  const std::vector<SliceCut> cuts = slice_cuts(model, q, c.tows, 1, y);
  for (const SliceCut& s : cuts) {
    if (s.tow == warp0 && s.kind == SliceCut::Kind::Strip) {
      ++strips;
      along.push_back(&s);
    }
    if (s.tow >= 0 && c.tows[s.tow].direction == TowSpec::Direction::Weft && s.kind == SliceCut::Kind::Crossing) {
      weft_z[c.tows[s.tow].name] += s.center.y();
      ++weft_n[c.tows[s.tow].name];
    }
  }
  EXPECT_GT(strips, 0);
  ASSERT_EQ(weft_n.size(), 2u) << "crossings of both wefts";
  // The strips' height over each weft's crossings, read from the polygons: above one, below
  // the other (a plain weave).
  std::vector<double> sides;
  for (const auto& [name, n] : weft_n) {
    const double z = weft_z[name] / n;
    double x = 0;
    int m = 0;
    for (const SliceCut& s : cuts)
      if (s.tow >= 0 && c.tows[s.tow].name == name && s.kind == SliceCut::Kind::Crossing) x += s.center.x(), ++m;
    x /= m;
    double above = 0, below = 0;  // the strips' points within 0.05 mm of x, above and below z
    for (const SliceCut* s : along)
      for (const Eigen::Vector2d& p : s->points)
        if (std::abs(p.x() - x) < 0.05e-3) (p.y() > z ? above : below) += 1;
    ASSERT_GT(above + below, 0) << name;
    sides.push_back(above > below ? 1.0 : -1.0);
  }
  EXPECT_EQ(sides[0] * sides[1], -1.0) << "the warp passes over one weft and under the other";
  r = fibra(fmt::format("slice out --plane y={}", y));
  ASSERT_EQ(r.code, 0) << r.err;
}

}  // namespace
}  // namespace fibra
