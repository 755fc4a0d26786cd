#pragma once
/// What a user wants to know about a woven sample at a given state, computed from the geometry
/// of the fibers (not from any log): crimp, tow amplitude and cross-sections per tow; crimp,
/// thickness, shrinkage, remaining penetration and fiber volume fraction of the fabric.
/// Warp tows run along x, weft tows along y, the fabric plane is z = 0 (model/fabric.hpp).
/// Definitions: docs/theory/fabric.md.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fibra/contact/contact_element.hpp"
#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The fibers of a tow cut by a plane normal to the tow axis. Values are NaN when no fiber is
/// cut.
struct TowSectionReport {
  double position = 0;         ///< coordinate of the plane along the tow axis [m]
  int fibers = 0;              ///< fibers cut by the plane
  double width = 0;            ///< spread of the cut centres across the tow (in the fabric plane) + 2r [m]
  double thickness = 0;        ///< spread of the cut centres in z + 2r [m]
  double area = 0;             ///< convex hull of the centres grown by r: A + P r + pi r^2 [m^2]
  double volume_fraction = 0;  ///< sum of the cut fibers' section areas / area [-]
  double center_z = 0;         ///< mean z of the cut centres [m]
  /// Angle from the fabric plane of the principal (major) axis of the cut centres' second
  /// moments, about the tow axis, in (-pi/2, pi/2]: positive when the section rises towards
  /// +across (+y for a warp, +x for a weft). A section symmetric about a vertical line has 0
  /// (pi/2 if its centres spread more in z than across); NaN with fewer than 2 fibers [rad].
  double tilt = 0;
};

/// One tow ([[tow]] or generated).
struct TowReport {
  std::string name;
  TowSpec::Direction direction = TowSpec::Direction::Warp;
  int index = 0;
  double axis = 0;         ///< current position of the tow axis across (y of a warp, x of a weft) [m]
  int crossings = 0;       ///< crossing positions: axes of the tows of the other direction
  double start = 0, end = 0;  ///< woven range along the axis: first and last crossing [m]
  /// Mean over its fibers of arc length / length of its projection on the tow's mean line - 1,
  /// between the first and last crossings along that line [-] (NaN: fewer than 2 crossings).
  double crimp = 0;
  /// Angle of the tow's mean line in the fabric plane from its nominal axis (x for a warp, y for
  /// a weft), counterclockwise about z, in [-pi/2, pi/2] [rad].
  double angle = 0;
  double z_amplitude = 0;  ///< max - min over the woven range of the tow's mean centre z [m]
  TowSectionReport mid;       ///< half-way between the two middle crossings (needs 2 crossings)
  TowSectionReport crossing;  ///< at the middle crossing
};

/// The whole sample. Quantities that cannot be defined (no crossing, no contact given) are NaN
/// (null in JSON).
struct FabricReport {
  std::vector<TowReport> tows;
  double warp_crimp = 0;       ///< mean crimp of the warp tows [-]
  double weft_crimp = 0;       ///< mean crimp of the weft tows [-]
  double thickness = 0;        ///< max - min z of the fibers' surfaces over the woven region [m]
  double shrinkage_x = 0;      ///< 1 - current / initial length along x (edge bodies, else outer weft axes) [-]
  double shrinkage_y = 0;      ///< 1 - current / initial length along y (edge bodies, else outer warp axes) [-]
  bool has_penetration = false;     ///< contact responses were given
  double max_penetration = 0;       ///< largest penetration of a contact element [m] (>= 0)
  double max_penetration_ratio = 0; ///< the same / the smaller radius of its pair [-]
  double volume_fraction = 0;  ///< mean fiber volume fraction of the tows' sections [-]
  double x_min = 0, x_max = 0; ///< woven region along x: outer weft axes [m]
  double y_min = 0, y_max = 0; ///< woven region along y: outer warp axes [m]
  double section_x = 0;        ///< plane x half-way between the two middle weft axes [m]
  double section_y = 0;        ///< plane y half-way between the two middle warp axes [m]
};

/// Geometry of a set of cut fibers: `centres` are (across, z) coordinates in the plane of the
/// cut [m], `radius` the fiber radius used to grow them [m], `fiber_area` the sum of the cut
/// fibers' section areas [m^2]. Sets every field but `position`.
TowSectionReport section_geometry(const std::vector<Eigen::Vector2d>& centres, double radius, double fiber_area);

/// The section of `tow` (its fibers meshed in `model`; one absent from the model is ignored) at
/// state `q`, cut by the plane normal to its axis at `position` along it (x of a warp, y of a
/// weft): the cut and the measures of the report's sections, at any plane.
TowSectionReport tow_section(const Model& model, const VecX& q, const TowSpec& tow, double position);

/// The report of the tows of `c` (c.tows, fibers meshed in `model`) at state `q` (all dofs,
/// bodies included). `contacts` and `responses` (same length) are optional: without them
/// has_penetration is false. A fiber named by a tow but absent from the model is ignored.
FabricReport fabric_report(const Case& c, const Model& model, const VecX& q,
                           const std::vector<ContactElement>* contacts = nullptr,
                           const std::vector<ContactResponse>* responses = nullptr);

/// The report as JSON (docs/outputs.md, summary.json "fabric"); NaN becomes null.
nlohmann::json to_json(const FabricReport& report);

}  // namespace fibra
