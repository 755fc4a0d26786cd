#include "fibra/io/case/schema.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace fibra::case_file {
namespace {

// One array per table, in the order docs/case-file.md shows them; its key tables are made from
// these (case_schema_markdown, case_schema_docs).

constexpr KeySpec kTop[] = {
    {.name = "title",
     .type = "string",
     .default_value = "`\"\"`",
     .meaning = "Free text describing the case."},
    {.name = "material",
     .type = "array of tables",
     .default_value = "required, at least 1",
     .meaning = "Materials, `[[material]]`.",
     .variant = "model",
     .expected = "@tables"},
    {.name = "fiber",
     .type = "array of tables",
     .default_value = "required, at least 1, unless there is a `[fabric]`",
     .meaning = "Fibers, `[[fiber]]`.",
     .variant = "model"},
    {.name = "fabric",
     .type = "table",
     .default_value = "none",
     .meaning = "A woven fabric, generated into fibers, bodies, bindings and tows, `[fabric]` (see *Woven fabrics*).",
     .variant = "model"},
    {.name = "fix",
     .type = "array of tables",
     .default_value = "none",
     .meaning = "Supports, `[[fix]]`.",
     .variant = "model"},
    {.name = "body",
     .type = "array of tables",
     .default_value = "none",
     .meaning = "Rigid bodies, `[[body]]` (see *Rigid bodies and averaged bindings*).",
     .variant = "model"},
    {.name = "binding",
     .type = "array of tables",
     .default_value = "none",
     .meaning = "Averaged bindings of fiber nodes and bodies to a body, `[[binding]]`.",
     .variant = "model"},
    {.name = "tow",
     .type = "array of tables",
     .default_value = "none",
     .meaning = "Tows: named groups of fibers, warp or weft, `[[tow]]` (see *Tows and the weave pattern*).",
     .variant = "model"},
    {.name = "weave",
     .type = "table",
     .default_value = "none",
     .meaning = "The weave pattern of the tows, `[weave]`; required by a weave step unless there is a `[fabric]`.",
     .variant = "model"},
    {.name = "start",
     .type = "table",
     .default_value = "none",
     .meaning = "Go on from the state an earlier run saved at the end of one of its steps, `[start]` (see *Going on from an earlier run*); the model then comes from that run.",
     .variant = "start"},
    {.name = "step",
     .type = "array of tables",
     .default_value = "required, at least 1",
     .meaning = "Load steps, `[[step]]`, run in order.",
     .expected = "@tables"},
    {.name = "solver",
     .type = "table",
     .default_value = "defaults below",
     .meaning = "Nonlinear solver settings, `[solver]`."},
    {.name = "contact",
     .type = "table",
     .default_value = "absent: no contact",
     .meaning = "Contact and friction between fibers, `[contact]`."},
    {.name = "output",
     .type = "table",
     .default_value = "defaults below",
     .meaning = "Output settings, `[output]`."},
};

constexpr std::string_view kMaterialModels[] = {"isotropic", "transverse"};
constexpr KeySpec kMaterial[] = {
    {.name = "name",
     .type = "string",
     .default_value = "required",
     .allowed = "non-empty, unique among materials",
     .meaning = "Referred to by `fiber.material`.",
     .expected = "a string"},
    {.name = "model",
     .type = "string",
     .default_value = "`\"isotropic\"`",
     .allowed = "`\"isotropic\"`, `\"transverse\"`",
     .meaning = "Material law.",
     .choices = kMaterialModels},
    {.name = "young",
     .type = "number",
     .default_value = "required",
     .allowed = "> 0",
     .unit = "Pa",
     .meaning = "Young's modulus E [Pa]; for `transverse`, E_L along the fiber.",
     .expected = "a number > 0 [Pa]"},
    {.name = "poisson",
     .type = "number",
     .default_value = "required",
     .allowed = "isotropic: 0 ≤ ν < 0.5; transverse: see below",
     .meaning = "Poisson's ratio ν; for `transverse`, ν_LT = −(transverse strain)/(axial strain) under axial load.",
     .expected = "a number in [0, 0.5)"},
    {.name = "young_transverse",
     .type = "number",
     .default_value = "required for `transverse`",
     .allowed = "> 0",
     .unit = "Pa",
     .meaning = "E_T in the plane of the section [Pa].",
     .variant = "transverse",
     .expected = "a number > 0 [Pa]"},
    {.name = "shear_axial",
     .type = "number",
     .default_value = "required for `transverse`",
     .allowed = "> 0",
     .unit = "Pa",
     .meaning = "G_LT [Pa].",
     .variant = "transverse",
     .expected = "a number > 0 [Pa]"},
    {.name = "poisson_transverse",
     .type = "number",
     .default_value = "required for `transverse`",
     .allowed = "> −1, see below",
     .meaning = "ν_TT in the plane of the section.",
     .variant = "transverse",
     .expected = "a number in (-1, 1)"},
};

constexpr KeySpec kFiber[] = {
    {.name = "name",
     .type = "string",
     .default_value = "required",
     .allowed = "non-empty, unique among fibers",
     .meaning = "Referred to by fixes, loads and displacements.",
     .expected = "a string"},
    {.name = "material",
     .type = "string",
     .default_value = "required",
     .allowed = "the `name` of a `[[material]]`",
     .meaning = "Material of the fiber.",
     .expected = "a string naming a [[material]]"},
    {.name = "radius",
     .type = "number",
     .default_value = "one of `radius` / `semi_axes`",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Circular section of this radius [m]."},
    {.name = "semi_axes",
     .type = "array of 2 numbers",
     .default_value = "one of `radius` / `semi_axes`",
     .allowed = "both > 0",
     .unit = "m",
     .meaning = "Elliptical section `[a, b]`: semi-axis `a` along the section vector g1, `b` along g2 [m]."},
    {.name = "section_direction",
     .type = "direction",
     .default_value = "chosen by the program",
     .allowed = "not parallel to the start tangent",
     .meaning = "Direction of g1 at the start of the fiber (projected onto the section plane)."},
    {.name = "points",
     .type = "array of vectors",
     .default_value = "one of `points` / `arc` / `helix`",
     .allowed = "≥ 2 points, consecutive points distinct",
     .unit = "m",
     .meaning = "Polyline through these points [m]."},
    {.name = "arc",
     .type = "table",
     .default_value = "one of `points` / `arc` / `helix`",
     .allowed = "see below",
     .meaning = "Circular arc."},
    {.name = "helix",
     .type = "table",
     .default_value = "one of `points` / `arc` / `helix`",
     .allowed = "see below",
     .meaning = "Circular helix."},
    {.name = "elements",
     .type = "integer",
     .default_value = "required",
     .allowed = "≥ 1, within the model size limits (below)",
     .meaning = "Number of quadratic (3-node) elements; the fiber has `2 * elements + 1` nodes, numbered 0 to `2 * elements` from the start.",
     .expected = "an integer >= 1"},
};

constexpr KeySpec kFiberArc[] = {
    {.name = "center",
     .type = "vector",
     .default_value = "`[0, 0, 0]`",
     .allowed = "",
     .unit = "m",
     .meaning = "Centre of the circle [m]."},
    {.name = "axis",
     .type = "direction",
     .default_value = "`[0, 0, 1]`",
     .allowed = "nonzero",
     .meaning = "Normal of the plane of the arc; angles are measured about it (right-hand rule)."},
    {.name = "radius",
     .type = "number",
     .default_value = "required",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Radius of the circle [m].",
     .expected = "a number > 0 [m]"},
    {.name = "start_angle",
     .type = "number",
     .default_value = "`0`",
     .allowed = "",
     .unit = "degrees",
     .meaning = "Angle of the start point, measured from the reference direction in the plane of the arc [degrees]."},
    {.name = "angle",
     .type = "number",
     .default_value = "required",
     .allowed = "≠ 0",
     .unit = "degrees",
     .meaning = "Sweep of the arc [degrees]; negative turns the other way.",
     .expected = "a nonzero number of degrees"},
};

constexpr KeySpec kFiberHelix[] = {
    {.name = "center",
     .type = "vector",
     .default_value = "`[0, 0, 0]`",
     .allowed = "",
     .unit = "m",
     .meaning = "A point on the helix axis [m]."},
    {.name = "axis",
     .type = "direction",
     .default_value = "`[0, 0, 1]`",
     .allowed = "nonzero",
     .meaning = "Direction of the helix axis (advance direction)."},
    {.name = "radius",
     .type = "number",
     .default_value = "required",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Radius of the helix [m].",
     .expected = "a number > 0 [m]"},
    {.name = "pitch",
     .type = "number",
     .default_value = "required",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Axial advance per turn [m].",
     .expected = "a number >= 0 [m per turn]"},
    {.name = "turns",
     .type = "number",
     .default_value = "required",
     .allowed = "> 0",
     .meaning = "Number of turns (need not be an integer).",
     .expected = "a number > 0"},
    {.name = "start_angle",
     .type = "number",
     .default_value = "`0`",
     .allowed = "",
     .unit = "degrees",
     .meaning = "Angle of the start point about the axis, from the same reference direction as an arc's [degrees] (the strands of a rope differ by it)."},
};

constexpr KeySpec kNode[] = {
    {.name = "fiber",
     .type = "string",
     .meaning = "Required: the `name` of a `[[fiber]]` (or of a fiber a `[fabric]` generates).",
     .expected = "a string naming a [[fiber]]"},
    {.name = "node",
     .type = "string or integer",
     .meaning = "`\"first\"`, `\"last\"`, or a node index `i` with 0 ≤ i < 2·`elements`+1."},
    {.name = "at",
     .type = "number",
     .meaning = "Instead of `node`: a fraction of the fiber length in [0, 1]; the nearest node is used."},
};

constexpr KeySpec kFix[] = {
    {.name = "dofs",
     .type = "string or array of strings",
     .default_value = "`\"all\"`",
     .allowed = "`\"all\"`, `\"position\"`, `\"sections\"`, or a list of components from `x`, `y`, `z` (of x0), `g1`, `g2` (whole section vectors), `g1x` … `g2z`",
     .meaning = "`\"position\"`: the centroid x0 only (a pin); `\"sections\"`: the section vectors g1, g2 only; `\"all\"`: both (a clamp). A list holds just those components, e.g. `[\"y\", \"g1\"]` keeps a node in the plane y = const with g1 fixed (planar problems, symmetry planes)."},
};

constexpr std::string_view kShearHeights[] = {"held", "free"};
constexpr std::string_view kStepKinds[] = {"standard", "load", "weave", "relax", "biaxial", "shear"};
constexpr KeySpec kStep[] = {
    {.name = "name",
     .type = "string",
     .default_value = "`\"step<k>\"` where k is the index of the step from 0 (`step0`, `step1`, …)",
     .allowed = "non-empty, unique among steps",
     .meaning = "Name used in output."},
    {.name = "kind",
     .type = "string",
     .default_value = "`\"standard\"`",
     .allowed = "`\"standard\"` (or `\"load\"`), `\"weave\"`, `\"relax\"`, `\"biaxial\"`, `\"shear\"`",
     .meaning = "What the step does, see below.",
     .choices = kStepKinds},
    {.name = "increments",
     .type = "integer",
     .default_value = "`1`",
     .allowed = "≥ 1",
     .meaning = "Initial number of increments (the solver adapts it).",
     .number_default = 1,
     .minimum = 1},
    {.name = "max_increments",
     .type = "integer",
     .default_value = "`0`",
     .allowed = "0, or ≥ `increments`",
     .meaning = "Maximum number of increments; 0 means 100 × `increments`."},
    {.name = "load",
     .type = "array of tables",
     .default_value = "none",
     .allowed = "",
     .meaning = "Nodal loads, `[[step.load]]`."},
    {.name = "displacement",
     .type = "array of tables",
     .default_value = "none",
     .allowed = "",
     .meaning = "Prescribed displacements, `[[step.displacement]]`."},
    {.name = "body",
     .type = "array of tables",
     .default_value = "none",
     .allowed = "each body at most once per step",
     .meaning = "Motions and loads of rigid bodies, `[[step.body]]` (see *Rigid bodies and averaged bindings*)."},
    {.name = "strain",
     .type = "number",
     .default_value = "required in biaxial steps",
     .allowed = "in (−0.5, 0.5), not 0; only with `kind = \"biaxial\"`",
     .meaning = "Warp axial strain at the end of the step, measured from the edge bodies' positions at its start."},
    {.name = "ratio",
     .type = "number",
     .default_value = "`1`",
     .allowed = "[0, 10]; only with `kind = \"biaxial\"`",
     .meaning = "α = weft elongation / warp elongation (1: equibiaxial; 0: uniaxial, the weft edges free along the weft)."},
    {.name = "angle",
     .type = "number",
     .default_value = "required in shear steps",
     .allowed = "in (−80, 80) degrees, not 0; only with `kind = \"shear\"`",
     .unit = "degrees",
     .meaning = "Shear angle at the end of the step [degrees], measured from the edge bodies' positions at its start."},
    {.name = "height",
     .type = "string",
     .default_value = "`\"held\"`",
     .allowed = "`\"held\"` or `\"free\"`; only with `kind = \"shear\"`",
     .meaning = "The distance between the bottom and top edges: held (the wefts stretch by 1/cos(`angle`) − 1 as the sample shears), or free (the top edge keeps the force it had across, the weft tension: the wefts turn without stretching and the sample's height shrinks as cos(`angle`)).",
     .choices = kShearHeights},
    {.name = "tolerance",
     .type = "number",
     .default_value = "`1e-4`",
     .allowed = "(0, 1); relax, biaxial and shear steps only",
     .meaning = "The drag force on the nodes' positions and the bodies, relative to the reference force, below which a relax step ends and a test level becomes a point of its curves; each such state is then solved on with that drag released, an equilibrium of the forces to `[solver] residual_tolerance` at a relax step's end and to a hundredth of this tolerance (or `residual_tolerance`, when looser) at a test level (the fibers' spin about their own axes stays held, `docs/theory/fabric.md`). A looser one is faster: `2e-3` on the 480-fiber plain weave's equibiaxial test gives edge forces within 0.9 % of those at `1e-3` in two thirds of the time (`docs/performance.md`, \"Test levels\")."},
};

constexpr KeySpec kStepLoad[] = {
    {.name = "force",
     .type = "vector",
     .default_value = "`[0, 0, 0]`",
     .unit = "N",
     .meaning = "Force on the centroid at the end of the step [N]."},
    {.name = "moment",
     .type = "vector",
     .default_value = "`[0, 0, 0]`",
     .unit = "N m",
     .meaning = "Moment on the section at the end of the step [N m]."},
};

constexpr KeySpec kStepDisplacement[] = {
    {.name = "value",
     .type = "array of 3 entries, each a number or `\"free\"`",
     .default_value = "required",
     .unit = "m",
     .meaning = "Displacement of the centroid from its reference position at the end of the step [m]; a `\"free\"` component is not prescribed. At least one component must be a number.",
     .expected = "an array of 3 components, each a number or \"free\""},
};

constexpr KeySpec kBody[] = {
    {.name = "name",
     .type = "string",
     .default_value = "required",
     .allowed = "non-empty, unique among bodies",
     .meaning = "Referred to by bindings and `[[step.body]]`.",
     .expected = "a string"},
    {.name = "center",
     .type = "vector",
     .default_value = "required",
     .allowed = "",
     .unit = "m",
     .meaning = "Initial position of the centre [m].",
     .expected = "an array of 3 numbers [m]"},
    {.name = "axes",
     .type = "array of 3 vectors",
     .default_value = "`[[1, 0, 0], [0, 1, 0], [0, 0, 1]]`",
     .allowed = "orthonormal and right-handed",
     .meaning = "Initial frame: the rows are D1, D2, D3 (global components)."},
};

constexpr KeySpec kBinding[] = {
    {.name = "body",
     .type = "string",
     .default_value = "required",
     .allowed = "the `name` of a `[[body]]`",
     .meaning = "The body the members follow.",
     .expected = "a string naming a [[body]]"},
    {.name = "ends",
     .type = "array of inline tables",
     .default_value = "`[]`",
     .allowed = "node references (see *Node references*), each node once",
     .meaning = "Bound fiber nodes, e.g. `{ fiber = \"f1\", node = \"last\" }`, `{ fiber = \"f2\", at = 1 }`."},
    {.name = "bodies",
     .type = "array of strings",
     .default_value = "`[]`",
     .allowed = "names of `[[body]]` entries other than `body`",
     .meaning = "Bound bodies (their centres and frames)."},
    {.name = "grip",
     .type = "array of integers",
     .default_value = "`[]`",
     .allowed = "at most two of 1, 2, 3, each once; needs `ends`",
     .meaning = "Body axes (D1, D2, D3) along which each bound fiber node is also held by itself at its initial position in the body frame, not only in average (`docs/theory/bodies.md`, *Grips*). E.g. `[2, 3]` across fibers laid along D1."},
    {.name = "spin",
     .type = "boolean",
     .default_value = "`false`",
     .allowed = "needs `ends`",
     .meaning = "Each bound fiber node is also held against turning about its fiber's axis relative to the body (its section's spin; tilt and stretch stay free). Without it a fiber's spin is held only by friction (`docs/theory/bodies.md`, *Spin holds*)."},
};

constexpr KeySpec kStepBody[] = {
    {.name = "name",
     .type = "string",
     .default_value = "required",
     .meaning = "The `name` of a `[[body]]`.",
     .expected = "a string naming a [[body]]"},
    {.name = "displacement",
     .type = "array of 3 entries, each a number or `\"free\"`",
     .default_value = "absent: unchanged",
     .unit = "m",
     .meaning = "Displacement of the centre from its initial position at the end of the step [m]."},
    {.name = "rotation",
     .type = "array of 3 entries, each a number or `\"free\"`",
     .default_value = "absent: unchanged",
     .unit = "rad",
     .meaning = "Rotation of the body at the end of the step [rad], see below."},
    {.name = "force",
     .type = "vector",
     .default_value = "absent: unchanged",
     .unit = "N",
     .meaning = "Force on the centre at the end of the step [N]."},
    {.name = "moment",
     .type = "vector",
     .default_value = "absent: unchanged",
     .unit = "N m",
     .meaning = "Moment about the centre at the end of the step [N m]."},
};

constexpr std::string_view kFabricGrips[] = {"averaged", "width", "clamped"};
constexpr KeySpec kFabric[] = {
    {.name = "pattern",
     .type = "string",
     .default_value = "one of `pattern` / `matrix`",
     .allowed = "see below",
     .meaning = "A named weave."},
    {.name = "matrix",
     .type = "array of arrays of integers",
     .default_value = "one of `pattern` / `matrix`",
     .allowed = "see below",
     .meaning = "The repeat of the weave: `matrix[j][i]` for weft row `j` and warp column `i`, 1 where the warp is above the weft, 0 where it is below."},
    {.name = "warp",
     .type = "table",
     .default_value = "required",
     .allowed = "see below",
     .meaning = "The warp tows (along x).",
     .expected = "@table such as { tows = 5, spacing = 1.0e-3 }"},
    {.name = "weft",
     .type = "table",
     .default_value = "required",
     .allowed = "see below",
     .meaning = "The weft tows (along y).",
     .expected = "@table such as { tows = 5, spacing = 1.0e-3 }"},
    {.name = "margin",
     .type = "number",
     .default_value = "half the larger spacing",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Free length of every tow beyond the outermost crossing [m]."},
    {.name = "tension",
     .type = "number",
     .default_value = "`0` (= automatic)",
     .allowed = "≥ 0",
     .unit = "N",
     .meaning = "Force per fiber pulling the free edges during weaving [N]; 0 lets the generator choose it."},
    {.name = "grip",
     .type = "string",
     .default_value = "`\"averaged\"`",
     .allowed = "`\"averaged\"`, `\"width\"`, `\"clamped\"`",
     .meaning = "How each tow-end body holds its fiber ends: `averaged` (the paper's binding: the ends' mean position and rotation), `width` (each end also held across the tow in the fabric's plane: D2 for warp ends, D1 for weft ends), `clamped` (and across the thickness, D3). With `width` and `clamped` each end's spin about its fiber's axis is held too. The generated `[[binding]]`s get the matching `grip` and `spin` (`docs/theory/fabric.md`, *Tow ends*).",
     .choices = kFabricGrips},
    {.name = "tow",
     .type = "table",
     .default_value = "none",
     .allowed = "see below",
     .meaning = "The tows' section, shared by warp and weft."},
    {.name = "fiber",
     .type = "table",
     .default_value = "none",
     .allowed = "see below",
     .meaning = "The tows' fibers, shared by warp and weft."},
};

constexpr KeySpec kFabricDirection[] = {
    {.name = "tows",
     .type = "integer",
     .default_value = "required",
     .allowed = "≥ 1",
     .meaning = "Number of tows in this direction.",
     .expected = "an integer >= 1"},
    {.name = "spacing",
     .type = "number",
     .default_value = "required",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Distance between the axes of neighbouring tows [m]; not below the tow width when there are several tows.",
     .expected = "a number > 0 [m]"},
    {.name = "tow",
     .type = "table",
     .default_value = "none",
     .allowed = "keys of `[fabric.tow]`",
     .meaning = "Overrides keys of the shared `[fabric.tow]` for this direction."},
    {.name = "fiber",
     .type = "table",
     .default_value = "none",
     .allowed = "keys of `[fabric.fiber]`",
     .meaning = "Overrides keys of the shared `[fabric.fiber]` for this direction."},
};

constexpr KeySpec kFabricTow[] = {
    {.name = "fibers",
     .type = "integer",
     .allowed = "≥ 1 (the generator needs ≥ 3)",
     .meaning = "Fibers per tow."},
    {.name = "width",
     .type = "number",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Axis of the tow's elliptical section in the fabric plane [m]."},
    {.name = "thickness",
     .type = "number",
     .allowed = "> 0, ≤ `width`",
     .unit = "m",
     .meaning = "Axis of the section normal to the fabric [m]."},
};

constexpr KeySpec kFabricFiber[] = {
    {.name = "radius",
     .type = "number",
     .allowed = "> 0",
     .unit = "m",
     .meaning = "Fiber radius [m]."},
    {.name = "material",
     .type = "string",
     .allowed = "the `name` of a `[[material]]`",
     .meaning = "Fiber material."},
    {.name = "element_length",
     .type = "number",
     .allowed = "> 0, within the model size limits",
     .unit = "m",
     .meaning = "Target element length [m]: each fiber gets the fewest elements not longer than this (at least 2). A fabric whose model would be too large to run is refused naming this key and the estimated size (\"Model size\", under `[[fiber]]`)."},
};

constexpr std::string_view kTowDirections[] = {"warp", "weft"};
constexpr KeySpec kTow[] = {
    {.name = "name",
     .type = "string",
     .default_value = "required",
     .allowed = "non-empty, unique among tows",
     .meaning = "",
     .expected = "a string"},
    {.name = "direction",
     .type = "string",
     .default_value = "required",
     .allowed = "`\"warp\"`, `\"weft\"`",
     .meaning = "Warp tows are the columns of the weave matrix, weft tows its rows.",
     .choices = kTowDirections,
     .expected = "\"warp\" or \"weft\""},
    {.name = "index",
     .type = "integer",
     .default_value = "required",
     .allowed = "≥ 0, unique among the tows of its direction",
     .meaning = "Position among the tows of its direction: the column (warp) or row (weft) of the tiled weave matrix.",
     .expected = "an integer >= 0, the position among the tows of its direction"},
    {.name = "fibers",
     .type = "array of strings",
     .default_value = "required",
     .allowed = "at least one; names of `[[fiber]]` entries",
     .meaning = "The fibers of the tow. A fiber belongs to at most one tow and is listed once.",
     .expected = "an array of fiber names"},
};

constexpr KeySpec kWeave[] = {
    {.name = "matrix",
     .type = "array of arrays of integers",
     .default_value = "one of `matrix` / `pattern`",
     .meaning = "The repeat, as `fabric.matrix`."},
    {.name = "pattern",
     .type = "string",
     .default_value = "one of `matrix` / `pattern`",
     .meaning = "A named weave, as `fabric.pattern`; the case holds its matrix."},
};

constexpr KeySpec kStart[] = {
    {.name = "from",
     .type = "string",
     .default_value = "required",
     .meaning = "The earlier run's output directory (`--out`), holding its `case.toml` and `state/`; a relative path is taken from this case file's directory.",
     .expected = "a string: the result directory (--out) of an earlier run to go on from"},
    {.name = "step",
     .type = "string",
     .default_value = "the last step of that run with a saved state",
     .meaning = "The step of that run whose end state to start from."},
};

constexpr std::string_view kLinearSolvers[] = {"cholmod", "eigen"};
constexpr std::string_view kKrylovPrecisions[] = {"auto", "single", "half", "double"};
constexpr KeySpec kSolver[] = {
    {.name = "residual_tolerance",
     .type = "number",
     .default_value = "`1e-8`",
     .allowed = "> 0",
     .meaning = "Convergence when the residual norm, relative to the reference force, is below this.",
     .number_default = 1e-8,
     .minimum = 0,
     .exclusive = true},
    {.name = "displacement_tolerance",
     .type = "number",
     .default_value = "`1e-8`",
     .allowed = "> 0",
     .meaning = "Convergence when the Newton correction, relative to the model size, is below this.",
     .number_default = 1e-8,
     .minimum = 0,
     .exclusive = true},
    {.name = "max_iterations",
     .type = "integer",
     .default_value = "`25`",
     .allowed = "≥ 1",
     .meaning = "Newton iterations per increment before the increment is cut (an increment with nothing to cut, at its stiffest drag, is tried again with 2 then 4 times as many: `docs/theory/solver.md`).",
     .number_default = 25,
     .minimum = 1},
    {.name = "max_cuts",
     .type = "integer",
     .default_value = "`12`",
     .allowed = "≥ 0",
     .meaning = "Successive halvings of an increment before the run fails.",
     .number_default = 12,
     .minimum = 0},
    {.name = "linear_solver",
     .type = "string",
     .default_value = "`\"cholmod\"`",
     .allowed = "`\"cholmod\"`, `\"eigen\"`",
     .meaning = "Sparse linear solver.",
     .choices = kLinearSolvers},
    {.name = "krylov_precision",
     .type = "string",
     .default_value = "`\"auto\"`",
     .allowed = "`\"auto\"`, `\"single\"`, `\"half\"`, `\"double\"`",
     .meaning = "The factor the conjugate-gradient solves precondition with (`docs/theory/solver.md`, \"Reusing the factorization\"): `\"single\"` rounds a copy of it to floats after each factorization (half the memory traffic per CG iteration, substitutions on two threads; same iterations within a few), `\"half\"` scales each of its rows to unit length and rounds it to halves (IEEE binary16: a quarter of the traffic; faster than single only where the substitutions wait on memory, and a poorer preconditioner on badly conditioned factors), `\"double\"` uses the factor itself, `\"auto\"` takes single for factors of at least 1e7 nonzeros (CHOLMOD only).",
     .choices = kKrylovPrecisions},
    {.name = "binding_tolerance",
     .type = "number",
     .default_value = "`1e-8`",
     .allowed = "> 0",
     .meaning = "Bindings are satisfied when their largest violation, relative to the model size (the diagonal of the bounding box), is below this (like `displacement_tolerance`).",
     .number_default = 1e-8,
     .minimum = 0,
     .exclusive = true},
    {.name = "max_binding_updates",
     .type = "integer",
     .default_value = "`30`",
     .allowed = "≥ 1",
     .meaning = "Largest number of multiplier updates of the augmented Lagrangian per increment.",
     .number_default = 30,
     .minimum = 1},
};

constexpr KeySpec kContact[] = {
    {.name = "friction",
     .type = "number",
     .default_value = "`0`",
     .allowed = "≥ 0",
     .meaning = "Coulomb coefficient μ.",
     .number_default = 0,
     .minimum = 0},
    {.name = "max_penetration",
     .type = "number",
     .default_value = "`0.05`",
     .allowed = "(0, 1)",
     .meaning = "Largest penetration allowed at convergence, as a fraction of the radius; a proximity zone that penetrates deeper gets a stiffer penalty and the increment is solved again."},
    {.name = "elastic_slip",
     .type = "number",
     .default_value = "`0` (= 1e-3 × smallest radius)",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Reversible slip δ [m] of the friction law: tangential stiffness μ f_n / δ.",
     .number_default = 0,
     .minimum = 0},
    {.name = "stiffness",
     .type = "number",
     .default_value = "`0` (= 0.1 E_T × smallest radius)",
     .allowed = "≥ 0",
     .unit = "N/m",
     .meaning = "Initial penalty stiffness k [N/m] of every contact element; only raised afterwards.",
     .number_default = 0,
     .minimum = 0},
    {.name = "regularization",
     .type = "number",
     .default_value = "`0.5`",
     .allowed = "(0, 1]",
     .meaning = "Depth p_r of the quadratic start of the normal law, as a fraction of the allowed penetration."},
    {.name = "margin",
     .type = "number",
     .default_value = "`0` (= half the radius)",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Detection distance beyond r_i + r_j [m].",
     .number_default = 0,
     .minimum = 0},
    {.name = "spacing",
     .type = "number",
     .default_value = "`0` (= the radius)",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Spacing of contact elements along a proximity zone [m].",
     .number_default = 0,
     .minimum = 0},
    {.name = "self_exclusion",
     .type = "number",
     .default_value = "`0` (= default of the detector)",
     .allowed = "≥ 0",
     .unit = "m",
     .meaning = "Arc length along one fiber within which it cannot touch itself [m].",
     .number_default = 0,
     .minimum = 0},
    {.name = "max_detections",
     .type = "integer",
     .default_value = "`8`",
     .allowed = "≥ 1",
     .meaning = "Detection loops per increment.",
     .number_default = 8,
     .minimum = 1},
    {.name = "max_normal_updates",
     .type = "integer",
     .default_value = "`30`",
     .allowed = "≥ 1",
     .meaning = "Normal-update loops per detection.",
     .number_default = 30,
     .minimum = 1},
    {.name = "normal_tolerance",
     .type = "number",
     .default_value = "`1e-3`",
     .allowed = "> 0",
     .unit = "rad",
     .meaning = "Normals are settled when none turns by more than this [rad].",
     .number_default = 1e-3,
     .minimum = 0,
     .exclusive = true},
};

constexpr KeySpec kOutput[] = {
    {.name = "every",
     .type = "integer",
     .default_value = "`1`",
     .allowed = "≥ 1",
     .meaning = "Write a `.vtu` file every N converged increments (the last one is always written).",
     .number_default = 1,
     .minimum = 1},
    {.name = "tube_sides",
     .type = "integer",
     .default_value = "`12`",
     .allowed = "≥ 3",
     .meaning = "Number of polygon sides of the tube view of each fiber.",
     .number_default = 12,
     .minimum = 3},
    {.name = "plots",
     .type = "boolean",
     .default_value = "`true`",
     .allowed = "",
     .meaning = "Draw the loading curves of the `biaxial` and `shear` steps (`plots/STEP.png`, `.svg`, `.json`; `docs/outputs.md`, *Plots*). It takes Python 3 with matplotlib, about a second per step; `false` skips them (`fibra plot DIR` draws them later)."},
    {.name = "test_levels",
     .type = "boolean",
     .default_value = "`true`",
     .allowed = "",
     .meaning = "Biaxial and shear steps (with contact and a drag): write the `.vtu` files at each settled load level only, the points of the curves, instead of every `every` increments; the increments within a level are pseudo-time states that the drag still holds (`docs/theory/fabric.md`). On the 480-fiber sample each such state is about 45 MB. `false` writes them as other steps do."},
    {.name = "checkpoint",
     .type = "string or integer",
     .default_value = "`\"auto\"`",
     .allowed = "`\"auto\"`, `\"never\"`, an integer ≥ 1, or a time `\"T s\"`, `\"T min\"`, `\"T h\"` with T > 0",
     .meaning = "When the run writes `state/checkpoint.bin`, from which `fibra run CASE --out DIR --resume` goes on after the run was killed or interrupted: `\"auto\"` after each increment once its step has run a minute, at most 2 % of the run's time; N every N increments; a time every T of wall time; `\"never\"` not at all. Every rate but `\"never\"` also writes one at each step's end and when the run is interrupted (`docs/outputs.md`, *Checkpoints and --resume*)."},
};

const std::vector<SectionSpec>& sections() {
  static const std::vector<SectionSpec> all = {
      {.name = "top", .keys = kTop, .node_reference = false, .default_column = true, .allowed_column = false},
      {.name = "material", .keys = kMaterial, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "fiber", .keys = kFiber, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "fiber.arc", .keys = kFiberArc, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "fiber.helix", .keys = kFiberHelix, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "node", .keys = kNode, .node_reference = false, .default_column = false, .allowed_column = false},
      {.name = "fix", .keys = kFix, .node_reference = true, .default_column = true, .allowed_column = true},
      {.name = "step", .keys = kStep, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "step.load", .keys = kStepLoad, .node_reference = true, .default_column = true, .allowed_column = false},
      {.name = "step.displacement", .keys = kStepDisplacement, .node_reference = true, .default_column = true, .allowed_column = false},
      {.name = "body", .keys = kBody, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "binding", .keys = kBinding, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "step.body", .keys = kStepBody, .node_reference = false, .default_column = true, .allowed_column = false},
      {.name = "fabric", .keys = kFabric, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "fabric.direction", .keys = kFabricDirection, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "fabric.tow", .keys = kFabricTow, .node_reference = false, .default_column = false, .allowed_column = true},
      {.name = "fabric.fiber", .keys = kFabricFiber, .node_reference = false, .default_column = false, .allowed_column = true},
      {.name = "tow", .keys = kTow, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "weave", .keys = kWeave, .node_reference = false, .default_column = true, .allowed_column = false},
      {.name = "start", .keys = kStart, .node_reference = false, .default_column = true, .allowed_column = false},
      {.name = "solver", .keys = kSolver, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "contact", .keys = kContact, .node_reference = false, .default_column = true, .allowed_column = true},
      {.name = "output", .keys = kOutput, .node_reference = false, .default_column = true, .allowed_column = true},
  };
  return all;
}

}  // namespace

const std::vector<SectionSpec>& case_schema() { return sections(); }

const SectionSpec& schema_section(std::string_view name) {
  for (const SectionSpec& s : sections())
    if (s.name == name) return s;
  throw std::logic_error("no table \"" + std::string(name) + "\" in the case file schema");
}

const KeySpec& schema_key(std::string_view section, std::string_view key) {
  for (const KeySpec& k : schema_section(section).keys)
    if (k.name == key) return k;
  throw std::logic_error("no key \"" + std::string(key) + "\" in table \"" + std::string(section) +
                         "\" of the case file schema");
}

std::vector<std::string_view> schema_choices(std::string_view section, std::string_view key) {
  const KeySpec& k = schema_key(section, key);
  return {k.choices.begin(), k.choices.end()};
}

std::vector<std::string_view> schema_keys(std::string_view section, std::string_view variant) {
  const SectionSpec& s = schema_section(section);
  std::vector<std::string_view> names;
  if (s.node_reference)
    for (const KeySpec& k : schema_section("node").keys) names.push_back(k.name);
  for (const KeySpec& k : s.keys)
    if (variant.empty() || k.variant.empty() || k.variant == variant) names.push_back(k.name);
  return names;
}

namespace {

/// One row of a markdown table: `| a | b |`, an empty cell as `| |`.
std::string markdown_row(const std::vector<std::string>& cells) {
  std::string row = "|";
  for (const std::string& c : cells) {
    if (!c.empty()) row.append(" ").append(c);
    row.append(" |");
  }
  row.append("\n");
  return row;
}

}  // namespace

std::string case_schema_markdown(std::string_view names) {
  std::vector<const SectionSpec*> parts;
  for (std::size_t begin = 0; begin < names.size();) {
    std::size_t end = names.find(' ', begin);
    if (end == std::string_view::npos) end = names.size();
    if (end > begin) parts.push_back(&schema_section(names.substr(begin, end - begin)));
    begin = end + 1;
  }
  if (parts.empty()) throw std::logic_error("case_schema_markdown: no table named");
  const SectionSpec& first = *parts.front();
  const bool table_column = parts.size() > 1;
  std::vector<std::string> header;
  if (table_column) header.push_back("Table");
  header.insert(header.end(), {"Key", "Type"});
  if (first.default_column) header.push_back("Default");
  if (first.allowed_column) header.push_back("Allowed");
  header.push_back("Meaning");
  std::string out = markdown_row(header);
  out += "|";
  for (const std::string& h : header) out += std::string(h.size() + 2, '-') + "|";
  out += "\n";
  for (const SectionSpec* s : parts) {
    const std::string_view table = s->name.substr(s->name.rfind('.') + 1);
    const auto row = [&](std::string key, std::string_view type, std::string_view default_value,
                         std::string_view allowed, std::string_view meaning) {
      std::vector<std::string> cells;
      if (table_column) cells.push_back(fmt::format("`{}`", table));
      cells.push_back(std::move(key));
      cells.emplace_back(type);
      if (first.default_column) cells.emplace_back(default_value);
      if (first.allowed_column) cells.emplace_back(allowed);
      cells.emplace_back(meaning);
      out += markdown_row(cells);
    };
    if (s->node_reference) row("`fiber`, `node` / `at`", "", "required", "", "The node (see *Node references*).");
    for (const KeySpec& k : s->keys)
      row(fmt::format("`{}`", k.name), k.type, k.default_value, k.allowed, k.meaning);
  }
  return out;
}

std::string with_case_schema_tables(std::string_view markdown) {
  constexpr std::string_view open = "<!-- schema: ", close = " -->";
  std::string out;
  bool in_table = false;  // in a table that follows a marker, which is replaced
  for (std::size_t begin = 0; begin < markdown.size();) {
    std::size_t end = markdown.find('\n', begin);
    end = end == std::string_view::npos ? markdown.size() : end + 1;
    const std::string_view line = markdown.substr(begin, end - begin);
    begin = end;
    if (in_table && line.starts_with("|")) continue;
    in_table = false;
    out += line;
    std::string_view text = line;
    if (text.ends_with("\n")) text.remove_suffix(1);
    if (text.starts_with(open) && text.ends_with(close) && text.size() > open.size() + close.size()) {
      if (!line.ends_with("\n")) out += "\n";
      out += case_schema_markdown(text.substr(open.size(), text.size() - open.size() - close.size()));
      in_table = true;
    }
  }
  return out;
}

}  // namespace fibra::case_file
