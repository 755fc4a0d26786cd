#pragma once
/// nodes.csv: the nodal values of a state, one row per node (fibers in case order, nodes in
/// order along each fiber), written by OutputWriter::write_nodes and read back by `fibra slice`.
/// Format: docs/outputs.md, "nodes.csv".
#include <string>

#include "fibra/core/types.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The header line (without its line break): fiber,node,x,y,z,g1x,g1y,g1z,g2x,g2y,g2z.
extern const char* const kNodesCsvHeader;

/// The whole file for state `q` of `model` (9 values per node, then the bodies', which are not
/// written): the header, then one row per node (the fiber's name, CSV-quoted when needed; the
/// node index local to the fiber; x0, g1, g2 in the shortest form that reads back exactly).
std::string nodes_csv_text(const Model& model, const VecX& q);

/// Reads a nodes.csv written for `model` (same fibers, same meshes) into a state: the node
/// values from the file, the bodies' values from the model's reference (centres from the case,
/// no rotation). Throws InputError (path, "line N" or "(file)") on a missing file, a wrong
/// header, an unknown fiber or node, a bad number, a node given twice or missing.
VecX read_nodes_csv(const std::string& path, const Model& model);

}  // namespace fibra
