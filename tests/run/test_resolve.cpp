// The resolution stage (run/resolve.hpp): every input error of a case is raised before anything
// is computed, with the file and the key, including those a step's conditions would only meet
// when the step starts (after a weaving of an hour on the paper's samples).
#include <gtest/gtest.h>

#include <string>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/run/resolve.hpp"
#include "support/fabric_cases.hpp"

namespace fibra::test {
namespace {

/// The key of the InputError resolve_case raises on `text`, with the message checked for
/// `words` and the file name; "no error" if it raises none.
std::string resolve_error(const std::string& text, const std::string& words) {
  const Case c = parse_case_toml(text, "resolve.toml");
  try {
    resolve_case(c);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("resolve.toml"), std::string::npos) << e.what();
    return e.key();
  }
  return "no error";
}

const std::string kWovenSteps =
    "[contact]\n[[step]]\nname = \"weave\"\nkind = \"weave\"\n[[step]]\nname = \"relax\"\nkind = \"relax\"\n";

TEST(Resolve, AWovenSampleResolves) {
  const Case c = parse_case_toml(glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "", kWovenSteps +
                                                  "[[step]]\nname = \"shear\"\nkind = \"shear\"\nangle = 5\n"
                                                  "height = \"free\"\n"),
                                 "resolve.toml");
  const ResolvedCase r = resolve_case(c);
  EXPECT_EQ(r.model.fibers.size(), 12u);
  EXPECT_FALSE(r.start.has_value());
}

// A shear whose height is free keeps the force across its top edge: with that force taken off
// by an earlier step there is none to keep. Raised before the weave step runs.
TEST(Resolve, ShearWithItsHeightFreeNeedsAForceAcross) {
  const std::string unload = "[[step]]\nname = \"unload\"\n  [[step.body]]\n  name = \"edge.y+\"\n  force = [0, 0, 0]\n";
  const std::string shear = "[[step]]\nname = \"shear\"\nkind = \"shear\"\nangle = 5\nheight = \"free\"\n";
  EXPECT_EQ(resolve_error(glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "", kWovenSteps + unload + shear),
                          "height = \"free\" leaves the top edge"),
            "step[3].height");
  // Held, or with the force given back, it resolves.
  EXPECT_EQ(resolve_error(glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "",
                                       kWovenSteps + unload +
                                           "[[step]]\nname = \"shear\"\nkind = \"shear\"\nangle = 5\nheight = \"held\"\n"),
                          ""),
            "no error");
  const std::string reload = "[[step]]\nname = \"reload\"\n  [[step.body]]\n  name = \"edge.y+\"\n  force = [0, 2, 0]\n";
  EXPECT_EQ(resolve_error(glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "", kWovenSteps + unload + reload + shear), ""),
            "no error");
}

// The weaving pushes crossing tows apart through their contacts: a weave step without
// [contact] is refused at its kind (the reader has checked its tows and pattern).
TEST(Resolve, AWeaveStepNeedsContact) {
  EXPECT_EQ(resolve_error(glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "", "[[step]]\nname = \"weave\"\nkind = \"weave\"\n"),
                          "it needs [contact]"),
            "step[0].kind");
}

const std::string kTwoFibers = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.01
elements = 2
points = [[0, 0, 0], [1, 0, 0]]
[[fiber]]
name = "b"
material = "m"
radius = 0.01
elements = 2
points = [[0, 0.1, 0], [1, 0.1, 0]]
[[fiber]]
name = "c"
material = "m"
radius = 0.01
elements = 2
points = [[0, 0.05, 0.1], [1, 0.05, 0.1]]
[[body]]
name = "grip"
center = [1, 0.05, 0.03]
[[binding]]
body = "grip"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]
[[fix]]
fiber = "a"
node = "first"
[[fix]]
fiber = "b"
node = "first"
[[fix]]
fiber = "c"
node = "first"
)";

// A body's component prescribed in one step takes no load in a later one until released.
TEST(Resolve, ALoadOnAPrescribedComponentIsRefused) {
  const std::string held = "[[step]]\nname = \"hold\"\n  [[step.body]]\n  name = \"grip\"\n  displacement = [0.01, 0, 0]\n";
  const std::string pushed = "[[step]]\nname = \"push\"\n  [[step.body]]\n  name = \"grip\"\n  force = [1, 0, 0]\n";
  EXPECT_EQ(resolve_error(kTwoFibers + held + pushed, "whose displacement along x is prescribed (since step \"hold\")"),
            "step[1].body[0].force");
  const std::string released =
      "[[step]]\nname = \"push\"\n  [[step.body]]\n  name = \"grip\"\n  displacement = [\"free\", 0, 0]\n  force = [1, 0, 0]\n";
  EXPECT_EQ(resolve_error(kTwoFibers + held + released, ""), "no error");
}

}  // namespace
}  // namespace fibra::test
