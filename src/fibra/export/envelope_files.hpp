#pragma once
/// The files of the tows' envelopes: binary STL (one surface) and VTK XML PolyData (every
/// tow's surface with a "tow" cell array; the section contours as closed lines). Coordinates in
/// metres (docs/export.md).
#include <string>
#include <vector>

#include "fibra/export/tow_envelope.hpp"
#include "fibra/export/triangle_mesh.hpp"

namespace fibra {

/// Binary STL of a surface: an 80-byte header holding `title`, the triangle count, then per
/// triangle its unit normal and its three corners as 32-bit floats.
std::string stl_binary(const TriangleMesh& mesh, const std::string& title);

/// VTK PolyData of the envelopes' surfaces, with the cell array "tow" (index into the case's
/// tows).
std::string envelopes_vtp(const std::vector<TowEnvelope>& envelopes);

/// VTK PolyData of the envelopes' section contours, one closed line per station, with the cell
/// arrays "tow" and "station".
std::string contours_vtp(const std::vector<TowEnvelope>& envelopes);

}  // namespace fibra
