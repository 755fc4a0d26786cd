#pragma once
/// The discretized model: fibers meshed into quadratic beam elements, the reference state
/// and the section stiffnesses. Node k of the model owns dofs [9k, 9k+9): x0, g1, g2; the
/// nodes of one fiber are consecutive, so each element's 27 dofs are contiguous.
#include <string>
#include <vector>

#include "fibra/beam/beam_element.hpp"
#include "fibra/beam/section.hpp"
#include "fibra/model/case.hpp"

namespace fibra {

/// A meshed fiber.
struct Fiber {
  std::string name;
  int material = 0;          ///< index into Model::materials
  int section = 0;           ///< index into Model::sections
  Index first_node = 0;      ///< global index of its node 0
  Index num_nodes = 0;       ///< 2 * elements + 1
  Index first_element = 0;   ///< global index of its element 0
  Index num_elements = 0;
  double length = 0;         ///< reference length [m]
};

/// The whole discretized model.
struct Model {
  std::vector<MaterialSpec> materials;
  std::vector<Section> sections;
  std::vector<Fiber> fibers;
  std::vector<BeamElement> elements;
  VecX reference;          ///< reference nodal values (9 per node)
  double length_scale = 1; ///< diagonal of the reference bounding box [m]

  Index num_nodes() const { return reference.size() / kNodeDofs; }  ///< all nodes
  Index num_dofs() const { return reference.size(); }               ///< 9 * nodes
  /// Index of a fiber by name, or -1.
  int fiber_index(const std::string& name) const;
  /// Global node index of a node reference; throws InputError (file, key) when invalid.
  Index node_index(const NodeRef& ref, const std::string& file, const std::string& key) const;
};

/// Meshes all fibers of a case.
Model build_model(const Case& c);

/// Appends a fiber (already validated spec) to a model; returns its index.
int add_fiber(Model& model, const FiberSpec& spec, int material);

}  // namespace fibra
