#pragma once
/// The voxel model as an Abaqus input file (docs/export.md, "Abaqus input"): one C3D8R element
/// per voxel, an element set per tow and one for the matrix, a local orientation per element
/// from its fiber direction (*DISTRIBUTION + *ORIENTATION), node sets of the box's six faces,
/// and a *SOLID SECTION per element set naming a material the user defines.
#include <string>
#include <vector>

#include "fibra/export/voxel_model.hpp"

namespace fibra {

/// The element set of each tow, "TOW_" and its name with every character other than a letter,
/// a digit or "_" made "_"; names equal but for case (Abaqus ignores it) get "_2", "_3", ...
std::vector<std::string> abaqus_tow_sets(const std::vector<std::string>& tow_names);

/// The local axes of an element of fiber direction `a` (unit, or zero for none): axis 1
/// along a; axis 3 the global z made normal to a (the global x for a fiber within 0.1 degree
/// of z); axis 2 = 3 x 1. Returns (axis 1, axis 2): the global x and y for a zero a.
std::pair<Vec3, Vec3> local_axes(const Vec3& a);

/// The .inp file of a voxel model; `tow_names` are the case's tows, `heading` one line.
std::string abaqus_inp(const VoxelModel& vm, const std::vector<std::string>& tow_names, const std::string& heading);

}  // namespace fibra
