#pragma once
// Fabric case files shared by the tests (TOML text).
#include <fmt/format.h>

#include <string>

namespace fibra::test {

/// A fabric of glass fibers (E = 72 GPa), tows 0.7 x 0.25 mm at 1 mm spacing, `margin` [m] free
/// beyond the outer crossings (0.5 mm unless given); `fabric_extra` goes into [fabric] (e.g.
/// "tension = 0.5\n"), `rest` after it ([contact], [solver] and the steps).
inline std::string glass_fabric(const std::string& pattern, int tows, int fibers, double radius, double element_length,
                                const std::string& fabric_extra, const std::string& rest, double margin = 0.5e-3) {
  return fmt::format(R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[fabric]
pattern = "{}"
warp = {{ tows = {}, spacing = 1.0e-3 }}
weft = {{ tows = {}, spacing = 1.0e-3 }}
margin = {}
{}  [fabric.tow]
  fibers = {}
  width = 0.7e-3
  thickness = 0.25e-3
  [fabric.fiber]
  radius = {}
  material = "glass"
  element_length = {}
{})",
                     pattern, tows, tows, margin, fabric_extra, fibers, radius, element_length, rest);
}

/// The weaving tests' friction sample: 2 x 2 plain weave, three fibers of r = 50 um per tow,
/// elements of 0.125 mm, 0.5 N per fiber on the edges, mu = 0.2; woven then relaxed, followed
/// by `more_steps`.
inline std::string plain_friction_sample(const std::string& more_steps = "") {
  return glass_fabric("plain", 2, 3, 5.0e-5, 1.25e-4, "tension = 0.5\n",
                      "[contact]\nfriction = 0.2\nelastic_slip = 5e-7\n"
                      "[[step]]\nname = \"weave\"\nkind = \"weave\"\nincrements = 10\n"
                      "[[step]]\nname = \"relax\"\nkind = \"relax\"\nincrements = 10\n" +
                          more_steps);
}

/// The J-shape test's sample: the friction sample's tows (2 x 2 plain weave, three fibers of
/// r = 50 um per tow, mu = 0.2) with 3 mm of free tow beyond the outer crossings, elements of
/// 0.25 mm and 0.01 N per fiber on the edges; woven then relaxed, followed by `more_steps`.
inline std::string long_tow_sample(const std::string& more_steps = "") {
  return glass_fabric("plain", 2, 3, 5.0e-5, 2.5e-4, "tension = 0.01\n",
                      "[contact]\nfriction = 0.2\nelastic_slip = 5e-7\n"
                      "[[step]]\nname = \"weave\"\nkind = \"weave\"\nincrements = 10\n"
                      "[[step]]\nname = \"relax\"\nkind = \"relax\"\nincrements = 10\n" +
                          more_steps,
                      3.0e-3);
}

}  // namespace fibra::test
