#pragma once
/// Woven fabrics: weave patterns, the packing of fibers in a tow's section, and the generator
/// that turns a [fabric] table into the starting assembly of the weaving (METHOD §6): straight
/// tows in one plane, fibers packed in elliptical sections, a rigid body on each tow end and
/// on each fabric edge, averaged bindings fiber ends -> tow-end body -> edge body, the tows
/// and the weave matrix for the weave steps, and the edges' boundary conditions.
#include <array>
#include <string>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model_size.hpp"

namespace fibra {

/// The repeat of a named pattern: "plain", "twill A/B" (e.g. "twill 2/1", "twill 2/2"; a warp
/// goes over A wefts then under B, shifted by one per weft), "basket" or "basket N" (N x N
/// plain blocks, N = 2 by default), "satin N" or "satin N/M" (warp-faced: each weft passes over
/// one warp per repeat, at column M j mod N; M coprime with N, 1 < M < N - 1; default the
/// smallest such M). matrix[weft row][warp column] = 1 where the warp is above. Returns an
/// empty matrix and sets `error` when the name is not understood.
std::vector<std::vector<int>> named_weave(const std::string& pattern, std::string& error);

/// Checks a repeat: rectangular, not empty, entries 0 or 1, every row and every column with
/// both values (a tow that never changes side does not interlace). Returns "" or the reason.
std::string check_weave(const std::vector<std::vector<int>>& matrix);

/// Whether warp `i` is above weft `j` (the repeat tiled over the fabric).
inline bool warp_above(const std::vector<std::vector<int>>& matrix, int i, int j) {
  const int rows = static_cast<int>(matrix.size()), cols = static_cast<int>(matrix[0].size());
  return matrix[((j % rows) + rows) % rows][((i % cols) + cols) % cols] == 1;
}

/// Centres of `count` circles of radius `r` packed without overlap in the ellipse of axes
/// `width` x `thickness` (centred at 0): the largest hexagonal lattice spacing (>= 2r) that
/// holds them, the `count` lattice sites nearest the centre (elliptic distance), as symmetric
/// as the count allows: an even count maps onto itself by the half-turn p -> -p, an odd count
/// by the half-turn or the mirror x -> -x (docs/theory/fabric.md). Returns an empty vector when
/// they do not fit even touching.
std::vector<Eigen::Vector2d> pack_ellipse(int count, double r, double width, double thickness);

/// Length of every generated fiber of the warp (`warp` true) or the weft: from the first to the
/// last tow of the other direction plus a margin at each end [m].
double fabric_fiber_length(const FabricSpec& f, bool warp);

/// Elements of every generated fiber of the warp or the weft: the fewest not longer than the
/// element length, ceil(length / element_length), at least 2. A real, so that a count no
/// integer holds is reported instead of overflowing (read_case refuses such a fabric).
double fabric_fiber_elements(const FabricSpec& f, bool warp);

/// The size of the model a fabric generates: its fibers, their elements, and its bodies (two
/// per tow and four edges). Computed from the spec alone, before anything is expanded.
ModelSize fabric_size(const FabricSpec& f);

/// Expands c.fabric (if any) into fibers, bodies, bindings, tows and the weave matrix, and
/// adds the edges' boundary conditions to the first step; throws InputError (c.file,
/// "fabric...") on impossible input (more fibers than fit, spacing below the tow width, ...).
void expand_fabric(Case& c);

/// The four edge bodies a fabric generates, in this order: the warp starts and ends (x- and
/// x+), the weft starts and ends (y- and y+). Biaxial and shear steps drive them.
inline constexpr std::array<const char*, 4> kEdgeBodies = {"edge.x-", "edge.x+", "edge.y-", "edge.y+"};

}  // namespace fibra
