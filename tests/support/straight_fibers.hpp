#pragma once
// A small case of straight fibers in tows, shared by the tests of slices and of nodes.csv.
#include <string>

namespace fibra::test {

/// Five fibers along x crossing the plane x = 0.3e-3 at right angles: a1, a2 in warp tow "A",
/// b1 in weft tow "B", c1 in warp tow "C" (index 1), loose in no tow. The plane is not at a node
/// of any of them except `loose`, whose middle node lies on it.
inline const std::string kStraightFibers = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "a1"
material = "m"
radius = 0.05e-3
points = [[0, 0, 0], [1e-3, 0, 0]]
elements = 3

[[fiber]]
name = "a2"
material = "m"
radius = 0.05e-3
points = [[0, 0.2e-3, 0.05e-3], [1e-3, 0.2e-3, 0.05e-3]]
elements = 3

[[fiber]]
name = "b1"
material = "m"
radius = 0.05e-3
points = [[0, -0.3e-3, 0.2e-3], [1e-3, -0.3e-3, 0.2e-3]]
elements = 5

[[fiber]]
name = "c1"
material = "m"
radius = 0.05e-3
points = [[0, 0.5e-3, -0.1e-3], [1e-3, 0.5e-3, -0.1e-3]]
elements = 3

[[fiber]]
name = "loose"
material = "m"
radius = 0.05e-3
points = [[-0.3e-3, 0.8e-3, 0], [0.9e-3, 0.8e-3, 0]]
elements = 2

[[tow]]
name = "A"
direction = "warp"
index = 0
fibers = ["a1", "a2"]

[[tow]]
name = "B"
direction = "weft"
index = 0
fibers = ["b1"]

[[tow]]
name = "C"
direction = "warp"
index = 1
fibers = ["c1"]

[[step]]
)";

/// kStraightFibers with one more fiber, whose name CSV quotes ("with, comma", 1 element).
inline std::string straight_fibers_with_quoted_name() {
  std::string text = kStraightFibers;
  const std::string extra =
      "[[fiber]]\nname = \"with, comma\"\nmaterial = \"m\"\nradius = 0.05e-3\npoints = [[0, 1e-3, 0], [1e-3, 1e-3, 0]]\n"
      "elements = 1\n\n";
  return text.insert(text.find("[[tow]]"), extra);
}

}  // namespace fibra::test
