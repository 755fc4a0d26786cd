// Cases of the export tests (tests/export): straight and curved tows built from TOML text, at
// their reference state.
#pragma once

#include <fmt/format.h>

#include <string>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"

namespace fibra::test {

/// A case, its model and a state (the reference).
struct BuiltCase {
  Case c;
  Model model;
  VecX q;
};

inline BuiltCase build_case(const std::string& toml) {
  BuiltCase b;
  b.c = parse_case_toml(toml, "export_test.toml");
  b.model = build_model(b.c);
  b.q = b.model.reference;
  return b;
}

inline const char* kMaterial = "[[material]]\nname = \"m\"\nyoung = 1e9\npoisson = 0.3\n";
inline const char* kStep = "[[step]]\nname = \"s\"\n";

/// A straight fiber from `a` to `b` [m]: circular (radius) or elliptical (semi-axes a, b with g1
/// towards `section_direction`).
inline std::string straight_fiber(const std::string& name, const Vec3& a, const Vec3& b, double radius, int elements,
                                  double semi_b = 0, const Vec3& section_direction = Vec3::Zero()) {
  std::string section =
      semi_b > 0 ? fmt::format("semi_axes = [{:.17g}, {:.17g}]\nsection_direction = [{:.17g}, {:.17g}, {:.17g}]\n",
                               radius, semi_b, section_direction.x(), section_direction.y(), section_direction.z())
                 : fmt::format("radius = {:.17g}\n", radius);
  return fmt::format(
      "[[fiber]]\nname = \"{}\"\nmaterial = \"m\"\n{}points = [[{:.17g}, {:.17g}, {:.17g}], [{:.17g}, "
      "{:.17g}, {:.17g}]]\nelements = {}\n",
      name, section, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), elements);
}

inline std::string tow(const std::string& name, const char* direction, int index,
                       const std::vector<std::string>& fibers) {
  std::string list;
  for (const std::string& f : fibers) list += (list.empty() ? "\"" : ", \"") + f + "\"";
  return fmt::format("[[tow]]\nname = \"{}\"\ndirection = \"{}\"\nindex = {}\nfibers = [{}]\n", name, direction, index,
                     list);
}

/// The axis of the straight test tow: oblique to every coordinate axis.
inline Vec3 straight_axis() { return Vec3(1.0, 0.3, 0.2).normalized(); }

/// Two unit vectors normal to the straight tow's axis and to each other.
inline std::pair<Vec3, Vec3> straight_frame() {
  const Vec3 e1 = straight_axis().cross(Vec3::UnitZ()).normalized();
  return {e1, straight_axis().cross(e1)};
}

/// Seven straight fibers of 2 mm along straight_axis() from around the origin (a hexagon of six
/// about one, 0.11 mm apart; four circular of r = 50 um, three elliptical of 50 x 30 um turned
/// differently), all in tow "T".
inline std::string straight_tow_case(int elements = 4) {
  const double r = 0.05e-3, spacing = 0.11e-3, length = 2e-3;
  const auto [e1, e2] = straight_frame();
  std::string text = kMaterial;
  std::vector<std::string> names;
  for (int k = 0; k < 7; ++k) {
    const double angle = k * 3.14159265358979323846 / 3.0;
    const Vec3 offset = k == 6 ? Vec3::Zero() : Vec3(spacing * (std::cos(angle) * e1 + std::sin(angle) * e2));
    const std::string name = fmt::format("f{}", k);
    const Vec3 turn = std::cos(0.7 * k) * e1 + std::sin(0.7 * k) * e2;
    text += straight_fiber(name, offset, offset + length * straight_axis(), r, elements, k % 2 ? 0.03e-3 : 0, turn);
    names.push_back(name);
  }
  return text + tow("T", "warp", 0, names) + kStep;
}

/// Three fibers bent on coaxial arcs (radii 2, 2.12 and 2.24 mm, 60 degrees about z), in tow
/// "C", 8 elements each.
inline std::string curved_tow_case() {
  std::string text = kMaterial;
  for (int k = 0; k < 3; ++k)
    text += fmt::format(
        "[[fiber]]\nname = \"c{}\"\nmaterial = \"m\"\nradius = 0.05e-3\nelements = 8\n"
        "arc = {{ center = [0, 0, 0], axis = [0, 0, 1], radius = {:.17g}, start_angle = 0, angle = 60 }}\n",
        k, 2e-3 + 0.12e-3 * k);
  return text + tow("C", "warp", 0, {"c0", "c1", "c2"}) + kStep;
}

}  // namespace fibra::test
