#pragma once
/// The discretized model: fibers meshed into quadratic beam elements, the reference state
/// and the section stiffnesses. Node k of the model owns dofs [9k, 9k+9): x0, g1, g2; the
/// nodes of one fiber are consecutive, so each element's 27 dofs are contiguous.
#include <string>
#include <vector>

#include "fibra/beam/beam_element.hpp"
#include "fibra/beam/section.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model_size.hpp"

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

/// A rigid body: 6 dofs after all the nodes' dofs, the centre R (3) then the incremental
/// rotation vector theta (3) of its frame, D = exp([theta]x) D_ref (see body/bodies.hpp).
struct Body {
  std::string name;
  Index first_dof = 0;            ///< global index of R_x
  Vec3 center = Vec3::Zero();     ///< initial centre [m]
  Mat3 axes = Mat3::Identity();   ///< initial frame, columns D1, D2, D3
};

/// The whole discretized model.
struct Model {
  std::vector<MaterialSpec> materials;
  std::vector<Section> sections;
  std::vector<Fiber> fibers;
  std::vector<BeamElement> elements;
  std::vector<Body> bodies;
  VecX reference;          ///< reference values: 9 per node, then 6 per body (R0, theta = 0)
  Index node_dofs = 0;     ///< 9 * nodes: the bodies' dofs start here
  double length_scale = 1; ///< diagonal of the reference bounding box [m]

  Index num_nodes() const { return node_dofs / kNodeDofs; }  ///< all nodes
  Index num_dofs() const { return reference.size(); }        ///< 9 * nodes + 6 * bodies
  Index num_groups() const { return num_nodes() + static_cast<Index>(bodies.size()); }  ///< nodes, then bodies
  /// Matrix group of body b (after the nodes).
  Index body_group(Index b) const { return num_nodes() + b; }
  /// Group sizes for the sparsity pattern: 9 per node, 6 per body.
  std::vector<int> group_sizes() const;
  /// Index of a fiber by name, or -1.
  int fiber_index(const std::string& name) const;
  /// Index of a body by name, or -1.
  int body_index(const std::string& name) const;
  /// Index of the fiber that holds global node `node`, or -1 (not a fiber's node).
  int fiber_of_node(Index node) const;
  /// Global node index of a node reference; throws InputError (file, key) when invalid.
  Index node_index(const NodeRef& ref, const std::string& file, const std::string& key) const;
};

/// The size of the fibers and bodies a case lists (a [fabric] not yet expanded is not in it).
ModelSize case_size(const Case& c);

/// Meshes all fibers of a case.
Model build_model(const Case& c);

/// Appends a fiber (already validated spec) to a model; returns its index. Fibers come
/// before bodies (throws std::logic_error otherwise).
int add_fiber(Model& model, const FiberSpec& spec, int material);

/// Appends a rigid body; returns its index.
int add_body(Model& model, const BodySpec& spec);

}  // namespace fibra
