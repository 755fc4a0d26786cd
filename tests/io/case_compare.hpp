#pragma once
/// expect_same_case: field-by-field comparison of two cases (GoogleTest expectations), shared by
/// the reader tests (TOML against JSON) and the writer tests (parse -> write -> parse).
#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "fibra/model/case.hpp"

namespace fibra::test {

/// Doubles identical (every number of a case reads back exactly: shortest round-trip decimals,
/// angles in degrees chosen to give the same radians).
inline void expect_same_double(double a, double b, const std::string& what) { EXPECT_EQ(a, b) << what; }

inline void expect_same_vec(const Vec3& a, const Vec3& b, const std::string& what) {
  for (int i = 0; i < 3; ++i) expect_same_double(a[i], b[i], what + "[" + std::to_string(i) + "]");
}

/// Directions to within 4 units in the last place: the reader normalizes them, and normalizing
/// a unit vector again may move a component by an ulp.
inline void expect_same_direction(const Vec3& a, const Vec3& b, const std::string& what) {
  for (int i = 0; i < 3; ++i) {
    if (a[i] == 0 || b[i] == 0) {
      EXPECT_NEAR(a[i], b[i], 1e-15) << what << "[" << i << "]";
    } else {
      EXPECT_DOUBLE_EQ(a[i], b[i]) << what << "[" << i << "]";
    }
  }
}

inline void expect_same_node(const NodeRef& a, const NodeRef& b, const std::string& what) {
  EXPECT_EQ(a.fiber, b.fiber) << what;
  EXPECT_EQ(a.kind, b.kind) << what;
  EXPECT_EQ(a.index, b.index) << what;
  expect_same_double(a.fraction, b.fraction, what + ".fraction");
}

inline void expect_same_fabric_direction(const FabricDirectionSpec& a, const FabricDirectionSpec& b,
                                         const std::string& what) {
  EXPECT_EQ(a.tows, b.tows) << what;
  expect_same_double(a.spacing, b.spacing, what + ".spacing");
  EXPECT_EQ(a.tow.fibers, b.tow.fibers) << what;
  expect_same_double(a.tow.width, b.tow.width, what + ".tow.width");
  expect_same_double(a.tow.thickness, b.tow.thickness, what + ".tow.thickness");
  expect_same_double(a.fiber.radius, b.fiber.radius, what + ".fiber.radius");
  EXPECT_EQ(a.fiber.material, b.fiber.material) << what;
  expect_same_double(a.fiber.element_length, b.fiber.element_length, what + ".fiber.element_length");
}

/// Checks two cases hold the same data: every field except `file` and `name`, and except
/// `fabric` when `compare_fabric` is false (a written case holds the expanded assembly only).
inline void expect_same_case(const Case& a, const Case& b, bool compare_fabric = true) {
  EXPECT_EQ(a.title, b.title);

  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (std::size_t i = 0; i < a.materials.size(); ++i) {
    const MaterialSpec& x = a.materials[i];
    const MaterialSpec& y = b.materials[i];
    const std::string w = "material[" + std::to_string(i) + "]";
    EXPECT_EQ(x.name, y.name) << w;
    EXPECT_EQ(x.model, y.model) << w;
    expect_same_double(x.young, y.young, w + ".young");
    expect_same_double(x.poisson, y.poisson, w + ".poisson");
    expect_same_double(x.young_transverse, y.young_transverse, w + ".young_transverse");
    expect_same_double(x.shear_axial, y.shear_axial, w + ".shear_axial");
    expect_same_double(x.poisson_transverse, y.poisson_transverse, w + ".poisson_transverse");
  }

  ASSERT_EQ(a.fibers.size(), b.fibers.size());
  for (std::size_t i = 0; i < a.fibers.size(); ++i) {
    const FiberSpec& x = a.fibers[i];
    const FiberSpec& y = b.fibers[i];
    const std::string w = "fiber[" + std::to_string(i) + "]";
    EXPECT_EQ(x.name, y.name) << w;
    EXPECT_EQ(x.material, y.material) << w;
    expect_same_double(x.radius, y.radius, w + ".radius");
    expect_same_double(x.semi_axis_1, y.semi_axis_1, w + ".semi_axis_1");
    expect_same_double(x.semi_axis_2, y.semi_axis_2, w + ".semi_axis_2");
    ASSERT_EQ(x.section_direction.has_value(), y.section_direction.has_value()) << w;
    if (x.section_direction) {
      expect_same_direction(*x.section_direction, *y.section_direction, w + ".section_direction");
    }
    EXPECT_EQ(x.elements, y.elements) << w;
    EXPECT_EQ(x.path.kind, y.path.kind) << w;
    ASSERT_EQ(x.path.points.size(), y.path.points.size()) << w;
    for (std::size_t k = 0; k < x.path.points.size(); ++k) {
      expect_same_vec(x.path.points[k], y.path.points[k], w + ".points[" + std::to_string(k) + "]");
    }
    expect_same_vec(x.path.center, y.path.center, w + ".center");
    expect_same_direction(x.path.axis, y.path.axis, w + ".axis");
    expect_same_double(x.path.radius, y.path.radius, w + ".path.radius");
    expect_same_double(x.path.start_angle, y.path.start_angle, w + ".start_angle");
    expect_same_double(x.path.angle, y.path.angle, w + ".angle");
    expect_same_double(x.path.pitch, y.path.pitch, w + ".pitch");
    expect_same_double(x.path.turns, y.path.turns, w + ".turns");
  }

  ASSERT_EQ(a.fixes.size(), b.fixes.size());
  for (std::size_t i = 0; i < a.fixes.size(); ++i) {
    const std::string w = "fix[" + std::to_string(i) + "]";
    expect_same_node(a.fixes[i].node, b.fixes[i].node, w);
    EXPECT_EQ(a.fixes[i].dofs, b.fixes[i].dofs) << w;
  }

  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    const std::string w = "body[" + std::to_string(i) + "]";
    EXPECT_EQ(a.bodies[i].name, b.bodies[i].name) << w;
    expect_same_vec(a.bodies[i].center, b.bodies[i].center, w + ".center");
    for (int k = 0; k < 3; ++k) {
      expect_same_vec(a.bodies[i].axes.col(k), b.bodies[i].axes.col(k), w + ".axes[" + std::to_string(k) + "]");
    }
  }

  ASSERT_EQ(a.bindings.size(), b.bindings.size());
  for (std::size_t i = 0; i < a.bindings.size(); ++i) {
    const std::string w = "binding[" + std::to_string(i) + "]";
    EXPECT_EQ(a.bindings[i].body, b.bindings[i].body) << w;
    EXPECT_EQ(a.bindings[i].line, b.bindings[i].line) << w;
    EXPECT_EQ(a.bindings[i].bodies, b.bindings[i].bodies) << w;
    EXPECT_EQ(a.bindings[i].grip, b.bindings[i].grip) << w;
    EXPECT_EQ(a.bindings[i].spin, b.bindings[i].spin) << w;
    ASSERT_EQ(a.bindings[i].ends.size(), b.bindings[i].ends.size()) << w;
    for (std::size_t k = 0; k < a.bindings[i].ends.size(); ++k) {
      expect_same_node(a.bindings[i].ends[k], b.bindings[i].ends[k], w + ".ends[" + std::to_string(k) + "]");
    }
  }

  ASSERT_EQ(a.tows.size(), b.tows.size());
  for (std::size_t i = 0; i < a.tows.size(); ++i) {
    const std::string w = "tow[" + std::to_string(i) + "]";
    EXPECT_EQ(a.tows[i].name, b.tows[i].name) << w;
    EXPECT_EQ(a.tows[i].direction, b.tows[i].direction) << w;
    EXPECT_EQ(a.tows[i].index, b.tows[i].index) << w;
    EXPECT_EQ(a.tows[i].fibers, b.tows[i].fibers) << w;
  }
  EXPECT_EQ(a.weave, b.weave);

  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    const StepSpec& x = a.steps[i];
    const StepSpec& y = b.steps[i];
    const std::string w = "step[" + std::to_string(i) + "]";
    EXPECT_EQ(x.name, y.name) << w;
    EXPECT_EQ(x.kind, y.kind) << w;
    EXPECT_EQ(x.increments, y.increments) << w;
    EXPECT_EQ(x.max_increments, y.max_increments) << w;
    expect_same_double(x.tolerance, y.tolerance, "step.tolerance");
    EXPECT_EQ(x.strain, y.strain) << w;
    EXPECT_EQ(x.ratio, y.ratio) << w;
    EXPECT_EQ(x.angle, y.angle) << w;
    EXPECT_EQ(x.free_height, y.free_height) << w;
    ASSERT_EQ(x.loads.size(), y.loads.size()) << w;
    for (std::size_t k = 0; k < x.loads.size(); ++k) {
      const std::string v = w + ".load[" + std::to_string(k) + "]";
      expect_same_node(x.loads[k].node, y.loads[k].node, v);
      expect_same_vec(x.loads[k].force, y.loads[k].force, v + ".force");
      expect_same_vec(x.loads[k].moment, y.loads[k].moment, v + ".moment");
    }
    ASSERT_EQ(x.displacements.size(), y.displacements.size()) << w;
    for (std::size_t k = 0; k < x.displacements.size(); ++k) {
      const std::string v = w + ".displacement[" + std::to_string(k) + "]";
      expect_same_node(x.displacements[k].node, y.displacements[k].node, v);
      EXPECT_EQ(x.displacements[k].value, y.displacements[k].value) << v;
    }
    ASSERT_EQ(x.bodies.size(), y.bodies.size()) << w;
    for (std::size_t k = 0; k < x.bodies.size(); ++k) {
      const BodyStepSpec& p = x.bodies[k];
      const BodyStepSpec& q = y.bodies[k];
      const std::string v = w + ".body[" + std::to_string(k) + "]";
      EXPECT_EQ(p.name, q.name) << v;
      EXPECT_EQ(p.has_displacement, q.has_displacement) << v;
      EXPECT_EQ(p.displacement, q.displacement) << v;
      EXPECT_EQ(p.has_rotation, q.has_rotation) << v;
      EXPECT_EQ(p.rotation, q.rotation) << v;
      ASSERT_EQ(p.force.has_value(), q.force.has_value()) << v;
      if (p.force) expect_same_vec(*p.force, *q.force, v + ".force");
      ASSERT_EQ(p.moment.has_value(), q.moment.has_value()) << v;
      if (p.moment) expect_same_vec(*p.moment, *q.moment, v + ".moment");
    }
  }

  const SolverSpec& s = a.solver;
  const SolverSpec& t = b.solver;
  expect_same_double(s.residual_tolerance, t.residual_tolerance, "solver.residual_tolerance");
  expect_same_double(s.displacement_tolerance, t.displacement_tolerance, "solver.displacement_tolerance");
  EXPECT_EQ(s.max_iterations, t.max_iterations);
  EXPECT_EQ(s.max_cuts, t.max_cuts);
  EXPECT_EQ(s.linear_solver, t.linear_solver);
  EXPECT_EQ(s.krylov_precision, t.krylov_precision);
  expect_same_double(s.binding_tolerance, t.binding_tolerance, "solver.binding_tolerance");
  EXPECT_EQ(s.max_binding_updates, t.max_binding_updates);

  const ContactSpec& p = a.contact;
  const ContactSpec& q = b.contact;
  EXPECT_EQ(p.enabled, q.enabled);
  expect_same_double(p.friction, q.friction, "contact.friction");
  expect_same_double(p.max_penetration, q.max_penetration, "contact.max_penetration");
  expect_same_double(p.elastic_slip, q.elastic_slip, "contact.elastic_slip");
  expect_same_double(p.stiffness, q.stiffness, "contact.stiffness");
  expect_same_double(p.regularization, q.regularization, "contact.regularization");
  expect_same_double(p.margin, q.margin, "contact.margin");
  expect_same_double(p.spacing, q.spacing, "contact.spacing");
  expect_same_double(p.self_exclusion, q.self_exclusion, "contact.self_exclusion");
  EXPECT_EQ(p.max_detections, q.max_detections);
  EXPECT_EQ(p.max_normal_updates, q.max_normal_updates);
  expect_same_double(p.normal_tolerance, q.normal_tolerance, "contact.normal_tolerance");

  EXPECT_EQ(a.output.every, b.output.every);
  EXPECT_EQ(a.output.tube_sides, b.output.tube_sides);
  EXPECT_EQ(a.output.plots, b.output.plots);
  EXPECT_EQ(a.output.test_levels, b.output.test_levels);
  EXPECT_EQ(a.output.checkpoint, b.output.checkpoint);
  EXPECT_EQ(a.output.checkpoint_increments, b.output.checkpoint_increments);
  EXPECT_EQ(a.output.checkpoint_seconds, b.output.checkpoint_seconds);

  if (!compare_fabric) return;
  ASSERT_EQ(a.fabric.has_value(), b.fabric.has_value());
  if (!a.fabric) return;
  const FabricSpec& f = *a.fabric;
  const FabricSpec& g = *b.fabric;
  EXPECT_EQ(f.pattern, g.pattern);
  EXPECT_EQ(f.matrix, g.matrix);
  expect_same_fabric_direction(f.warp, g.warp, "fabric.warp");
  expect_same_fabric_direction(f.weft, g.weft, "fabric.weft");
  expect_same_double(f.margin, g.margin, "fabric.margin");
  expect_same_double(f.tension, g.tension, "fabric.tension");
}

}  // namespace fibra::test
