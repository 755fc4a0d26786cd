#include "fibra/model/model.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/fiber_path.hpp"

namespace fibra {

namespace {

/// Refuses a fiber whose built geometry or section the beam's arithmetic cannot hold: a path
/// of no length or of an infinite one, coordinates whose squares overflow, elements shorter
/// than the rounding of their coordinates resolves (1e-9 of them), an arc or helix element
/// sweeping more than a half turn (a quadratic element cannot follow it), a section whose
/// stiffness is zero, subnormal or infinite. `key` names the fiber in the case file
/// (fiber[i], or the [fabric] direction that generates it).
void check_fiber_geometry(const Model& model, const Fiber& fib, const FiberSpec& spec, const std::string& file,
                          const std::string& key, bool generated) {
  const std::string path_key =
      generated ? key
                : key + (spec.path.kind == PathSpec::Kind::Polyline ? ".points"
                         : spec.path.kind == PathSpec::Kind::Arc    ? ".arc"
                                                                     : ".helix");
  const std::string who = generated ? fmt::format("fiber \"{}\": ", fib.name) : std::string();
  const double length = fib.length;
  if (!(std::isfinite(length) && length > 0))
    throw InputError(file, path_key,
                     fmt::format("{}the path is {:.6g} m long: expected a finite length > 0", who, length));
  double extent = 0;  // the largest coordinate of the fiber's nodes
  for (Index j = 0; j < fib.num_nodes; ++j)
    extent = std::max(extent, model.reference.segment<3>(kNodeDofs * (fib.first_node + j)).cwiseAbs().maxCoeff());
  if (!std::isfinite(extent * extent))
    throw InputError(file, path_key,
                     fmt::format("{}coordinates up to {:.6g} m: their squares overflow (the beam computes squared "
                                 "lengths); give the geometry in smaller units or nearer the origin",
                                 who, extent));
  const double h = length / static_cast<double>(fib.num_elements);
  if (!(h * h >= DBL_MIN))
    throw InputError(file, path_key,
                     fmt::format("{}{} elements of {:.6g} m on a {:.6g} m fiber: the squares of their lengths "
                                 "underflow (below 1e-308); give the geometry in larger units",
                                 who, fib.num_elements, h, length));
  if (h < 1e-9 * extent)
    throw InputError(file, path_key,
                     fmt::format("{}{} elements of {:.6g} m on a {:.6g} m fiber with coordinates up to {:.6g} m: an "
                                 "element shorter than 1e-9 of the coordinates is lost in their rounding (positions "
                                 "hold 16 digits); give fewer elements, a longer fiber or coordinates nearer the "
                                 "origin",
                                 who, fib.num_elements, h, length, extent));
  if (spec.path.kind != PathSpec::Kind::Polyline) {
    const double half_turns = spec.path.kind == PathSpec::Kind::Arc ? std::abs(spec.path.angle) / std::numbers::pi
                                                                    : 2.0 * spec.path.turns;
    const double per_element = 180.0 * half_turns / static_cast<double>(fib.num_elements);
    if (!(per_element <= 180.0))
      throw InputError(
          file, generated ? key : key + ".elements",
          fmt::format("{}{} elements on a sweep of {:.6g} degrees: each element would span {:.6g} degrees, more than "
                      "the half turn a quadratic element can follow; give at least {:.6g} elements",
                      who, fib.num_elements, 180.0 * half_turns, per_element, std::ceil(half_turns)));
  }
  const Section& sec = model.sections[fib.section];
  const double largest = sec.stiffness.cwiseAbs().maxCoeff();
  const bool stiffness_finite = sec.stiffness.allFinite() && sec.stiffness_inplane.allFinite();
  for (const double v : {sec.area, sec.inertia_1, sec.inertia_2, largest})
    if (!(std::isfinite(v) && v >= DBL_MIN && stiffness_finite))
      throw InputError(file, generated ? key : key + (spec.semi_axis_1 != spec.semi_axis_2 ? ".semi_axes" : ".radius"),
                       fmt::format("{}a section of semi-axes {:.6g} x {:.6g} m of this material has an area of "
                                   "{:.6g} m^2, bending inertias {:.6g} and {:.6g} m^4 and a largest stiffness entry "
                                   "of {:.6g}: expected finite values > 0 (not zero, not below 1e-308)",
                                   who, sec.a, sec.b, sec.area, sec.inertia_1, sec.inertia_2, largest));
}

}  // namespace

int Model::fiber_index(const std::string& name) const {
  for (size_t i = 0; i < fibers.size(); ++i)
    if (fibers[i].name == name) return static_cast<int>(i);
  return -1;
}

int Model::fiber_of_node(Index node) const {
  for (size_t i = 0; i < fibers.size(); ++i)
    if (node >= fibers[i].first_node && node < fibers[i].first_node + fibers[i].num_nodes) return static_cast<int>(i);
  return -1;
}

Index Model::node_index(const NodeRef& ref, const std::string& file, const std::string& key) const {
  const int f = fiber_index(ref.fiber);
  if (f < 0) throw InputError(file, key + ".fiber", fmt::format("no fiber named \"{}\"", ref.fiber));
  const Fiber& fib = fibers[f];
  switch (ref.kind) {
    case NodeRef::Kind::First:
      return fib.first_node;
    case NodeRef::Kind::Last:
      return fib.first_node + fib.num_nodes - 1;
    case NodeRef::Kind::NodeIndex:
      if (ref.index < 0 || ref.index >= fib.num_nodes)
        throw InputError(file, key + ".node",
                         fmt::format("node index {} out of range: fiber \"{}\" has nodes 0..{}", ref.index,
                                     fib.name, fib.num_nodes - 1));
      return fib.first_node + ref.index;
    case NodeRef::Kind::Fraction: {
      if (!(ref.fraction >= 0.0 && ref.fraction <= 1.0))
        throw InputError(file, key + ".at", "expected a fraction of the length in [0, 1]");
      // Nodes are equally spaced in reference arc length.
      const Index local = std::llround(ref.fraction * static_cast<double>(fib.num_nodes - 1));
      return fib.first_node + local;
    }
  }
  return fib.first_node;
}

std::vector<int> Model::group_sizes() const {
  std::vector<int> sizes(num_nodes(), kNodeDofs);
  sizes.resize(num_groups(), 6);
  return sizes;
}

int Model::body_index(const std::string& name) const {
  for (size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

int add_body(Model& model, const BodySpec& spec) {
  Body b;
  b.name = spec.name;
  b.first_dof = model.reference.size();
  b.center = spec.center;
  b.axes = spec.axes;
  model.reference.conservativeResize(b.first_dof + 6);
  model.reference.segment<3>(b.first_dof) = spec.center;
  model.reference.segment<3>(b.first_dof + 3).setZero();
  model.bodies.push_back(b);
  return static_cast<int>(model.bodies.size()) - 1;
}

int add_fiber(Model& model, const FiberSpec& spec, int material) {
  if (!model.bodies.empty()) throw std::logic_error("add_fiber: fibers must be added before bodies");
  const Index n_el = spec.elements;
  const Index n_nodes = 2 * n_el + 1;
  Fiber fib;
  fib.name = spec.name;
  fib.material = material;
  fib.first_node = model.num_nodes();
  fib.num_nodes = n_nodes;
  fib.first_element = static_cast<Index>(model.elements.size());
  fib.num_elements = n_el;
  fib.length = path_length(spec.path);

  // Share sections between fibers of the same material and shape.
  const double a = spec.semi_axis_1 > 0 ? spec.semi_axis_1 : spec.radius;
  const double b = spec.semi_axis_2 > 0 ? spec.semi_axis_2 : spec.radius;
  int sec = -1;
  for (size_t i = 0; i < model.sections.size(); ++i) {
    bool same_material = false;
    for (const Fiber& other : model.fibers)
      if (other.section == static_cast<int>(i) && other.material == material) same_material = true;
    if (same_material && model.sections[i].a == a && model.sections[i].b == b) sec = static_cast<int>(i);
  }
  if (sec < 0) {
    model.sections.push_back(make_section(model.materials[material], a, b));
    sec = static_cast<int>(model.sections.size()) - 1;
  }
  fib.section = sec;

  const std::vector<PathFrame> frames = sample_path(spec.path, static_cast<int>(n_nodes), spec.section_direction);
  const Index base = model.reference.size();
  model.reference.conservativeResize(base + kNodeDofs * n_nodes);
  model.node_dofs = model.reference.size();
  for (Index k = 0; k < n_nodes; ++k) {
    model.reference.segment<3>(base + 9 * k) = frames[k].position;
    model.reference.segment<3>(base + 9 * k + 3) = frames[k].g1;
    model.reference.segment<3>(base + 9 * k + 6) = frames[k].g2;
  }
  const int fiber_id = static_cast<int>(model.fibers.size());
  for (Index e = 0; e < n_el; ++e) {
    BeamElement el;
    el.first_dof = base + 9 * 2 * e;
    el.section = sec;
    el.fiber = fiber_id;
    beam_reference(model.reference.data() + el.first_dof, el);
    model.elements.push_back(el);
  }
  model.fibers.push_back(fib);
  return fiber_id;
}

ModelSize case_size(const Case& c) {
  ModelSize size;
  for (const FiberSpec& spec : c.fibers) size += fiber_size(spec.elements);
  size.bodies = static_cast<double>(c.bodies.size());
  return size;
}

Model build_model(const Case& c) {
  // read_case refuses a model too large; a case made in code is checked here, before any
  // count is converted or allocated.
  const ModelSize size = case_size(c);
  if (const std::string why = size_excess(size, machine_size_limits()); !why.empty())
    throw InputError(c.file, "fiber",
                     fmt::format("the {} fibers ({:.6g} elements in all) make a model too large to run: {}",
                                 c.fibers.size(), size.elements, why));
  Model model;
  model.materials = c.materials;
  for (size_t i = 0; i < c.fibers.size(); ++i) {
    const FiberSpec& spec = c.fibers[i];
    int mat = -1;
    for (size_t m = 0; m < c.materials.size(); ++m)
      if (c.materials[m].name == spec.material) mat = static_cast<int>(m);
    if (mat < 0)
      throw InputError(c.file, fmt::format("fiber[{}].material", i),
                       fmt::format("no material named \"{}\"", spec.material));
    const int f = add_fiber(model, spec, mat);
    // A [fabric]'s fibers come after the file's, named warp<i>.f<k> and weft<j>.f<k>.
    const bool generated =
        c.fabric && static_cast<double>(c.fibers.size() - i) <= fabric_size(*c.fabric).fibers;
    const std::string key = generated ? (spec.name.starts_with("warp") ? "fabric.warp" : "fabric.weft")
                                      : fmt::format("fiber[{}]", i);
    check_fiber_geometry(model, model.fibers[f], spec, c.file, key, generated);
  }
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (Index k = 0; k < model.num_nodes(); ++k) {
    lo = lo.cwiseMin(model.reference.segment<3>(9 * k));
    hi = hi.cwiseMax(model.reference.segment<3>(9 * k));
  }
  model.length_scale = model.num_nodes() > 0 ? std::max((hi - lo).norm(), 1e-30) : 1.0;
  for (const BodySpec& b : c.bodies) add_body(model, b);
  return model;
}

}  // namespace fibra
