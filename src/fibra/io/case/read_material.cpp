// The readers of [[material]] and [[fiber]] (its path: points, arc or helix).
#include "fibra/io/case/reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case/suggest.hpp"

namespace fibra::case_file {

MaterialSpec Reader::read_material(const Value& t, const std::string& path) const {
  MaterialSpec m;
  if (const Value* v = find(t, "model"))
    m.model = one_of(*v, join(path, "model"), schema_choices("material", "model")) == "isotropic"
                  ? MaterialSpec::Model::Isotropic
                  : MaterialSpec::Model::Transverse;
  if (m.model == MaterialSpec::Model::Isotropic) {
    // The keys of the transverse model alone, named as such.
    std::vector<KeyHint> hints;
    for (const KeySpec& k : schema_section("material").keys)
      if (k.variant == "transverse") hints.push_back({k.name, "only allowed with model = \"transverse\""});
    check_keys(t, path, schema_keys("material", "isotropic"), hints);
  } else {
    check_keys(t, path, schema_keys("material", "transverse"));
  }

  m.name = to_name(require_key(t, path, "material", "name"), join(path, "name"));
  m.young = positive(require_key(t, path, "material", "young"), join(path, "young"));
  const std::string poisson_key = join(path, "poisson");
  if (m.model == MaterialSpec::Model::Isotropic) {
    const Value& v = require_key(t, path, "material", "poisson");
    m.poisson = to_number(v, poisson_key);
    if (!(m.poisson >= 0 && m.poisson < 0.5)) {
      fail(poisson_key, fmt::format("must be in [0, 0.5) for an isotropic material, got {}", m.poisson),
           &v);
    }
    return m;
  }

  m.poisson = to_number(require(t, path, "poisson", "a number (nu_LT)"), poisson_key);
  m.young_transverse = positive(require_key(t, path, "material", "young_transverse"),
                                join(path, "young_transverse"));
  m.shear_axial =
      positive(require_key(t, path, "material", "shear_axial"), join(path, "shear_axial"));
  const std::string nu_tt_key = join(path, "poisson_transverse");
  const Value& nu_tt = require_key(t, path, "material", "poisson_transverse");
  m.poisson_transverse = to_number(nu_tt, nu_tt_key);
  // The normal block of the compliance matrix (axis 3 = fiber axis) is
  //   [ 1/ET     -nuTT/ET  -nuLT/EL ]
  //   [ -nuTT/ET  1/ET     -nuLT/EL ]
  //   [ -nuLT/EL -nuLT/EL   1/EL    ]
  // with determinant (1 + nuTT)/ET * ((1 - nuTT)/(ET EL) - 2 nuLT^2/EL^2); the shear terms are
  // 1/G_LT and 2 (1 + nuTT)/ET. It is positive definite iff nuTT > -1 and
  // 1 - nuTT - 2 nuLT^2 ET/EL > 0.
  if (!(m.poisson_transverse > -1)) {
    fail(nu_tt_key,
         fmt::format("must be > -1 (otherwise the compliance matrix is not positive definite), got {}",
                     m.poisson_transverse),
         &nu_tt);
  }
  const double margin = 1 - m.poisson_transverse -
                        2 * m.poisson * m.poisson * m.young_transverse / m.young;
  if (!(margin > 0)) {
    fail(path,
         fmt::format("the compliance matrix is not positive definite: need 1 - poisson_transverse - "
                     "2 poisson^2 young_transverse / young > 0, got {}",
                     margin),
         &t);
  }
  return m;
}

PathSpec Reader::read_path(const Value& t, const std::string& path) const {
  const Value* points = find(t, "points");
  const Value* arc = find(t, "arc");
  const Value* helix = find(t, "helix");
  std::vector<std::string_view> given;
  if (points) given.push_back("points");
  if (arc) given.push_back("arc");
  if (helix) given.push_back("helix");
  if (given.empty()) {
    fail(join(path, "points"),
         "missing the fiber path: give exactly one of points (a polyline), arc or helix", &t);
  }
  if (given.size() > 1) {
    fail(path,
         fmt::format("give exactly one of points, arc or helix, not several (found {})",
                     list_names(given)),
         &t);
  }

  PathSpec p;
  if (points) {
    p.kind = PathSpec::Kind::Polyline;
    const std::string key = join(path, "points");
    if (points->type != Value::Type::Array) {
      fail(key, fmt::format("expected an array of points (arrays of 3 numbers), got {}",
                            describe(*points)),
           points);
    }
    if (points->items.size() < 2) {
      fail(key, fmt::format("expected at least 2 points, got {}", points->items.size()), points);
    }
    for (std::size_t i = 0; i < points->items.size(); ++i) {
      p.points.push_back(to_vec3(points->items[i], item(key, i)));
    }
    double extent = 0;
    for (const Vec3& x : p.points) extent = std::max(extent, (x - p.points.front()).norm());
    for (std::size_t i = 1; i < p.points.size(); ++i) {
      if (!std::isfinite((p.points[i] - p.points[i - 1]).squaredNorm())) {
        fail(item(key, i),
             fmt::format("points {} and {} are too far apart: the square of their distance overflows (give the "
                         "geometry in smaller units or nearer the origin)",
                         i - 1, i),
             &points->items[i]);
      }
      if ((p.points[i] - p.points[i - 1]).norm() <= 1e-12 * extent) {
        fail(item(key, i),
             fmt::format("points {} and {} coincide (consecutive points must be distinct)", i - 1, i),
             &points->items[i]);
      }
    }
    return p;
  }

  const bool is_arc = arc != nullptr;
  const Value& table = is_arc ? *arc : *helix;
  const std::string base = join(path, is_arc ? "arc" : "helix");
  expect_table(table, base);
  if (is_arc) {
    p.kind = PathSpec::Kind::Arc;
    check_keys(table, base, schema_keys("fiber.arc"));
  } else {
    p.kind = PathSpec::Kind::Helix;
    check_keys(table, base, schema_keys("fiber.helix"));
  }
  if (const Value* v = find(table, "center")) p.center = to_vec3(*v, join(base, "center"));
  if (const Value* v = find(table, "axis")) p.axis = to_direction(*v, join(base, "axis"));
  p.radius = positive(require_key(table, base, is_arc ? "fiber.arc" : "fiber.helix", "radius"), join(base, "radius"));
  if (const Value* v = find(table, "start_angle")) p.start_angle = to_number(*v, join(base, "start_angle")) * kDegree;
  if (is_arc) {
    const std::string angle_key = join(base, "angle");
    const Value& angle = require_key(table, base, "fiber.arc", "angle");
    const double degrees = to_number(angle, angle_key);
    if (degrees == 0) fail(angle_key, "must be nonzero (the sweep of the arc, in degrees), got 0", &angle);
    p.angle = degrees * kDegree;
  } else {
    const std::string pitch_key = join(base, "pitch");
    const Value& pitch = require_key(table, base, "fiber.helix", "pitch");
    p.pitch = to_number(pitch, pitch_key);
    if (!(p.pitch >= 0)) fail(pitch_key, fmt::format("must be >= 0, got {}", p.pitch), &pitch);
    p.turns = positive(require_key(table, base, "fiber.helix", "turns"), join(base, "turns"));
  }
  return p;
}

FiberSpec Reader::read_fiber(const Value& t, const std::string& path,
                             const std::vector<MaterialSpec>& materials) const {
  check_keys(t, path, schema_keys("fiber"));
  FiberSpec f;
  f.name = to_name(require_key(t, path, "fiber", "name"), join(path, "name"));

  const std::string material_key = join(path, "material");
  const Value& material = require_key(t, path, "fiber", "material");
  f.material = to_string(material, material_key);
  expect_material(f.material, material, material_key, materials);

  const Value* radius = find(t, "radius");
  const Value* semi_axes = find(t, "semi_axes");
  if (radius && semi_axes) fail(path, "give either radius or semi_axes, not both", &t);
  if (radius) {
    f.radius = positive(*radius, join(path, "radius"));
    f.semi_axis_1 = f.semi_axis_2 = f.radius;
  } else if (semi_axes) {
    const std::string key = join(path, "semi_axes");
    const std::vector<double> a = to_numbers(*semi_axes, key, 2);
    if (!(a[0] > 0 && a[1] > 0)) {
      fail(key, fmt::format("both semi-axes must be > 0, got [{}, {}]", a[0], a[1]), semi_axes);
    }
    f.semi_axis_1 = a[0];
    f.semi_axis_2 = a[1];
    f.radius = std::sqrt(a[0] * a[1]);
  } else {
    fail(join(path, "radius"),
         "missing the section: give radius (a number > 0) or semi_axes (an array of 2 numbers > 0)",
         &t);
  }

  f.path = read_path(t, path);

  if (const Value* v = find(t, "section_direction")) {
    const std::string key = join(path, "section_direction");
    const Vec3 d = to_direction(*v, key);
    if (f.path.kind == PathSpec::Kind::Polyline) {
      const Vec3 tangent = (f.path.points[1] - f.path.points[0]).normalized();
      if (d.cross(tangent).norm() <= 1e-8) {
        fail(key,
             "must not be parallel to the start tangent of the fiber (the first segment of points)",
             v);
      }
    }
    f.section_direction = d;
  }

  const std::string elements_key = join(path, "elements");
  const Value& elements = require_key(t, path, "fiber", "elements");
  f.elements = to_int(elements, elements_key, 1);
  if (const std::string why = size_excess(fiber_size(f.elements), m_limits); !why.empty())
    fail(elements_key, fmt::format("{} elements make a model too large to run: {}", f.elements, why), &elements);
  return f;
}
}  // namespace fibra::case_file
