#pragma once
/// The case description: what a user writes in a case file (TOML or JSON), validated,
/// before any discretization. Units are SI throughout (m, N, Pa).
#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "fibra/core/types.hpp"

namespace fibra {

/// A St Venant–Kirchhoff material; axis 3 of the law is the fiber axis.
struct MaterialSpec {
  enum class Model { Isotropic, Transverse };
  std::string name;
  Model model = Model::Isotropic;
  double young = 0;               ///< E (isotropic) or E_L, along the fiber [Pa]
  double poisson = 0;             ///< nu (isotropic) or nu_LT (transverse strain / axial strain) [-]
  double young_transverse = 0;    ///< E_T [Pa] (transverse only)
  double shear_axial = 0;         ///< G_LT [Pa] (transverse only)
  double poisson_transverse = 0;  ///< nu_TT in the plane of the section (transverse only)
};

/// Centroid path of a fiber in its reference (stress-free) configuration.
struct PathSpec {
  enum class Kind { Polyline, Arc, Helix };
  Kind kind = Kind::Polyline;
  std::vector<Vec3> points;  ///< polyline vertices (>= 2, consecutive distinct)
  // Arc: circle of `radius` about `center`, in the plane normal to `axis`, from `start` to
  // `start + angle` (radians), with the start point at center + radius * reference direction.
  // Helix: about `axis` through `center`, `radius`, `pitch` (axial advance per turn), `turns`.
  Vec3 center = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double radius = 0;
  double start_angle = 0;  ///< [rad]
  double angle = 0;        ///< arc sweep [rad]
  double pitch = 0;        ///< helix: axial advance per turn [m]
  double turns = 0;        ///< helix: number of turns
};

/// One fiber: material, section, path and mesh.
struct FiberSpec {
  std::string name;
  std::string material;
  double radius = 0;          ///< circular section radius [m]; or the ellipse below
  double semi_axis_1 = 0;     ///< ellipse semi-axis along g1 [m] (== radius for a circle)
  double semi_axis_2 = 0;     ///< ellipse semi-axis along g2 [m]
  std::optional<Vec3> section_direction;  ///< direction of g1 at the start (projected); default chosen
  PathSpec path;
  int elements = 0;           ///< number of quadratic 3-node elements
};

/// A node of a fiber: "first", "last", an index, or the nearest node to a length fraction.
struct NodeRef {
  std::string fiber;
  enum class Kind { First, Last, NodeIndex, Fraction } kind = Kind::First;
  Index index = 0;      ///< for Kind::NodeIndex
  double fraction = 0;  ///< for Kind::Fraction, in [0, 1]
  std::string label() const;  ///< "first", "last", "12", or "at0.5" (used in column names)
};

/// A [[fix]] entry: dofs of one node held at their reference values.
struct FixSpec {
  NodeRef node;
  /// Held components, in node order x0 (x, y, z), g1 (x, y, z), g2 (x, y, z); all = clamp.
  std::array<bool, 9> dofs{true, true, true, true, true, true, true, true, true};
  bool position() const { return dofs[0] && dofs[1] && dofs[2]; }  ///< x0 fully held
  bool sections() const {                                          ///< g1 and g2 fully held
    for (int k = 3; k < 9; ++k)
      if (!dofs[k]) return false;
    return true;
  }
};

/// A nodal load (force on x0 and/or axial moment on the section vectors), total value at the
/// end of its step.
struct LoadSpec {
  NodeRef node;
  Vec3 force = Vec3::Zero();   ///< [N]
  Vec3 moment = Vec3::Zero();  ///< [N m]
};

/// A prescribed displacement of x0 (relative to the reference), total value at the end of its
/// step; a component that is std::nullopt is left free.
struct DisplacementSpec {
  NodeRef node;
  std::array<std::optional<double>, 3> value;
};

/// A rigid body ([[body]]): 6 dofs, the position of its centre and the orientation of its
/// orthonormal frame (D1, D2, D3). Its motion comes from [[step.body]] entries and from the
/// bindings that tie other nodes or bodies to it in average (METHOD §5).
struct BodySpec {
  std::string name;
  Vec3 center = Vec3::Zero();    ///< initial centre R [m]
  Mat3 axes = Mat3::Identity();  ///< initial frame: column i is D_i (orthonormal, right-handed)
};

/// An averaged binding ([[binding]]): the mean motion of its members (fiber nodes, usually
/// ends, and/or other bodies' centres and frames) follows the body, each member free to move
/// on its own.
struct BindingSpec {
  std::string body;                 ///< the body the members follow
  std::vector<NodeRef> ends;        ///< bound fiber nodes
  std::vector<std::string> bodies;  ///< bound bodies (hierarchy: a tow end to a fabric edge)
  /// Axes of the body (1, 2, 3: D1, D2, D3) along which each bound fiber node is also held by
  /// itself at its initial position in the body frame (a grip), not only in average; empty:
  /// the averaged conditions alone (the paper's binding).
  std::vector<int> grip;
  /// Each bound fiber node is also held by itself against turning about its fiber's axis (its
  /// section vectors' spin relative to the body): without it a fiber's spin is a mode of
  /// almost no stiffness where friction alone holds it.
  bool spin = false;
  int line = 0;                     ///< index of the [[binding]] entry (for messages)
};

/// A [[step.body]] entry: what is prescribed or applied to a body during a step. A component
/// given a number is prescribed (total value at the end of the step, ramped from where it
/// was); "free" releases it; an array that is absent leaves every component as it was.
struct BodyStepSpec {
  std::string name;                                   ///< the body
  bool has_displacement = false;                      ///< `displacement` given
  std::array<std::optional<double>, 3> displacement;  ///< of the centre from its initial position [m]
  bool has_rotation = false;                          ///< `rotation` given
  /// Accumulated spatial rotation components about the global axes [rad] (the rotation angle
  /// for a rotation about a fixed axis).
  std::array<std::optional<double>, 3> rotation;
  std::optional<Vec3> force;                          ///< force on the centre [N] (total at step end)
  std::optional<Vec3> moment;                         ///< moment about the centre [N m]
};

/// Fibers packed in a tow's elliptical section before weaving.
struct TowSectionSpec {
  int fibers = 0;        ///< fibers per tow
  double width = 0;      ///< ellipse axis in the fabric plane [m]
  double thickness = 0;  ///< ellipse axis normal to the fabric [m]
};

/// The fibers of one direction of a fabric.
struct FabricFiberSpec {
  double radius = 0;          ///< [m]
  std::string material;       ///< a [[material]] name
  double element_length = 0;  ///< target element length [m]
};

/// One direction of a fabric: warp tows run along x, weft tows along y.
struct FabricDirectionSpec {
  int tows = 0;          ///< number of tows
  double spacing = 0;    ///< distance between tow axes [m]
  TowSectionSpec tow;
  FabricFiberSpec fiber;
};

/// A [fabric] table: the fabric the generator builds (model/fabric.hpp).
struct FabricSpec {
  std::string pattern;                    ///< as written: "plain", "twill 2/1", ..., or "matrix"
  std::vector<std::vector<int>> matrix;   ///< repeat, matrix[weft row][warp column]: 1 = warp above
  FabricDirectionSpec warp, weft;
  double margin = 0;   ///< free length of every tow beyond the outer crossings [m]
  double tension = 0;  ///< force per fiber pulling the free edges during weaving [N]; 0 = default
  /// How a tow-end body holds its fiber ends: averaged (the paper: the ends' mean position and
  /// rotation follow the body), width (each end also held across the tow in the fabric's
  /// plane), clamped (each end held across the tow in both directions).
  enum class Grip { Averaged, Width, Clamped };
  Grip grip = Grip::Averaged;
};

/// A tow of a fiber assembly ([[tow]]): a named group of fibers, warp or weft; the weave
/// steps use it to orient the contacts between crossing tows.
struct TowSpec {
  enum class Direction { Warp, Weft };
  std::string name;
  Direction direction = Direction::Warp;
  int index = 0;                     ///< position among the tows of its direction (0-based)
  std::vector<std::string> fibers;   ///< fiber names
};

/// A load step: loads and displacements ramp linearly over the step from where the previous
/// step ended; an entry not listed again keeps its last value.
struct StepSpec {
  /// standard (or "load" in a file): the loads and conditions listed; weave: contacts between
  /// crossing tows pushed to the side the weave pattern says (METHOD §6); relax: usual
  /// normals, after weaving; biaxial, shear: mechanical tests of a fabric through its edge
  /// bodies (METHOD §7; conditions set at the step's start from the edges' positions then).
  enum class Kind { Standard, Weave, Relax, Biaxial, Shear };
  std::string name;
  Kind kind = Kind::Standard;
  /// The kind as a case file spells it ("standard", "weave", ...).
  static const char* kind_name(Kind k);
  /// A mechanical test of a woven sample (biaxial or shear).
  bool is_test() const { return kind == Kind::Biaxial || kind == Kind::Shear; }
  /// Increments are proximal steps, with a drag towards their start (relax and the tests).
  bool is_proximal() const { return kind == Kind::Relax || is_test(); }
  double strain = 0;  ///< biaxial: warp axial strain at the step's end, from its start
  double ratio = 1;   ///< biaxial: weft elongation / warp elongation (0: weft edges free)
  double angle = 0;   ///< shear: shear angle at the step's end, from its start [degrees]
  /// shear: the distance between the bottom and top edges held (the wefts stretch by
  /// 1/cos(angle) - 1), or free (the top edge keeps the force it had across: the wefts keep
  /// their tension and the sample's height shrinks as it shears).
  bool free_height = false;
  /// relax: the step ends once the drag's force is below this fraction of the reference
  /// force; biaxial, shear: a load level is a point of the curves once it is (each point is
  /// an equilibrium to this tolerance).
  double tolerance = 1e-4;
  int increments = 1;      ///< initial number of increments (the solver adapts)
  int max_increments = 0;  ///< 0 = 100 * increments
  std::vector<LoadSpec> loads;
  std::vector<DisplacementSpec> displacements;
  std::vector<BodyStepSpec> bodies;  ///< [[step.body]] entries
};

/// The fixed rules of the nonlinear method (docs/theory/solver.md). They are not case-file
/// keys: a user sets tolerances and limits ([solver]), the method sets itself. Tests and
/// benchmarks vary them to measure what each rule does.
struct SolverMethod {
  bool line_search = true;                ///< backtracking on stick-slip cycles and rising residuals
  /// The contact elements' tangent (docs/theory/contact.md, "A tangent above the contact
  /// energy"): "exact", "adaptive" (the exact Hessian, and one above the energy for the
  /// elements whose exact model fell below it on a step the line search shortened) or
  /// "majorizing" (above the energy for every element).
  std::string contact_tangent = "exact";
  std::string ordering = "metis";         ///< CHOLMOD fill-reducing ordering: "metis", "amd" or "auto"
  double weave_drag = 1.0;                ///< drag per node in weave steps, relative to the contact penalty k0
  /// First proximal drag of a relax or test step, relative to k0: the weave's (the stiffest);
  /// easy increments divide it by 4.
  double relax_drag = 1.0;
  double drag_axial = 1e-2;               ///< weave, relax and test steps' drag: weight of a node's motion along its fiber (1: isotropic)
  double test_inexact = 0.01;             ///< tests: Newton tolerance of pseudo-time increments / the drag force they leave, of settling ones / the step's tolerance (0: off)
  double relax_inexact = 0.01;            ///< relax steps: the same, but the release that ends the step is solved to residual_tolerance (0: off)
  double test_penetration_slack = 0.05;   ///< tests: a settled level's deepest penetration may exceed the cap by this fraction
  bool test_predictor = true;             ///< tests: each load level starts from the interior moved like the edges (interpolated)
  /// Held load steps (LoadDriver): a level is settled once the drag's force and the residual
  /// with updated normals are below this fraction of the load (applied forces and reactions).
  double held_tolerance = 1e-5;
  double pseudo_tolerance = 1e-6;         ///< Newton tolerance of pseudo-time increments (weave; relax/test while the drag force is above its tolerance)
  /// CG iterations preconditioned by the last factorization before a new one: < 0 = the
  /// factorization's price in CG iterations, from its flops (automatic); 0 = factorize every
  /// iteration; > 0 = that many.
  int krylov_iterations = -1;
  double krylov_tolerance = 1e-3;         ///< CG stops at this residual relative to the Newton residual (inexact Newton)
  double krylov_tolerance_pseudo = 3e-2;  ///< the same in pseudo-time increments (weave; relax and test increments with lagged normals)
  double max_step = -1;                   ///< largest motion per Newton iteration [m]; < 0 = half the smallest radius with contact, none without; 0 = none
  double binding_stiffness = 0;           ///< penalty of the augmented Lagrangian [N/m]; 0 = automatic
};

/// Nonlinear solver settings ([solver] table): tolerances, limits and the linear solver.
struct SolverSpec {
  double residual_tolerance = 1e-8;      ///< relative to the reference force
  double displacement_tolerance = 1e-8;   ///< largest correction, relative to the model size
  int max_iterations = 25;               ///< Newton iterations per increment
  int max_cuts = 12;                     ///< successive halvings of an increment
  std::string linear_solver = "cholmod";  ///< "cholmod" or "eigen"
  std::string krylov_precision = "auto";  ///< CG's preconditioning factor: "single" (rounded to floats), "half" (rows scaled, rounded to halves), "double", "auto" (single for large factors)
  double binding_tolerance = 1e-8;        ///< largest binding violation, relative to the model size
  int max_binding_updates = 30;           ///< multiplier updates per increment (augmented Lagrangian)
  SolverMethod method;                    ///< not read from case files
};

/// Contact and friction settings ([contact] table); contact is off when the table is absent.
struct ContactSpec {
  bool enabled = false;
  double friction = 0;            ///< Coulomb coefficient mu
  double max_penetration = 0.05;  ///< allowed penetration, fraction of the smaller radius of a pair
  double elastic_slip = 0;        ///< reversible slip delta [m]; 0 = 1e-3 times the smallest radius
  double stiffness = 0;           ///< initial penalty k [N/m]; 0 = E_T times the smallest radius
  double regularization = 0.5;    ///< p_r as a fraction of the allowed penetration
  double margin = 0;              ///< detection margin [m]; 0 = half the smaller radius of a pair
  double spacing = 0;             ///< contact element spacing [m]; 0 = the smaller radius of a pair
  double self_exclusion = 0;      ///< same-fiber arc length without self-contact [m]; 0 = default
  int max_detections = 8;         ///< detection loops per increment
  int max_normal_updates = 30;    ///< normal-update loops per detection
  double normal_tolerance = 1e-3; ///< normals converged when they turn less than this [rad]
};

/// Output settings ([output] table).
struct OutputSpec {
  int every = 1;               ///< write a .vtu every N converged increments (last always)
  bool test_levels = true;     ///< biaxial/shear steps with a drag: .vtu at each settled level only (not every increment)
  int tube_sides = 12;         ///< polygon sides of the tube view of each fiber
  bool plots = true;           ///< plots of the biaxial and shear steps' curves (plots/, needs matplotlib)
  /// When a run writes its checkpoint (state/checkpoint.bin, `fibra run --resume`): "auto" after
  /// each increment once its step has run a minute, as long as checkpoints take at most 2 % of
  /// the run's time; every N increments; every T seconds; never. Every mode but never also
  /// writes one at each step's end and when the run is interrupted.
  enum class Checkpoint { Auto, Increments, Seconds, Never };
  Checkpoint checkpoint = Checkpoint::Auto;
  int checkpoint_increments = 1;    ///< Increments: every N converged increments
  double checkpoint_seconds = 60;   ///< Seconds: every T seconds of wall time [s]
};

/// File name stem of a step's name (outputs named after a step: curves_<stem>.csv,
/// state/<stem>.bin, slices): characters other than letters, digits, '.', '-', '_' become '_'.
std::string step_file_stem(const std::string& step);

/// A whole case file.
struct Case {
  std::string file;   ///< path of the case file (for messages)
  std::string name;   ///< file stem, used for the default output directory
  std::string title;
  std::vector<MaterialSpec> materials;
  std::vector<FiberSpec> fibers;
  std::vector<FixSpec> fixes;
  std::vector<BodySpec> bodies;
  std::vector<BindingSpec> bindings;
  std::optional<FabricSpec> fabric;          ///< [fabric], expanded into fibers, bodies, tows
  std::vector<TowSpec> tows;                 ///< [[tow]] (or generated from [fabric])
  std::vector<std::vector<int>> weave;       ///< [weave] matrix (or from [fabric]); empty = none
  std::vector<StepSpec> steps;
  /// [start] from: the result directory whose model and state this case goes on from; empty:
  /// from the reference configuration.
  std::string start;
  std::string start_step;   ///< [start] step: the step of that run whose end state it goes on from
  std::string start_state;  ///< that state's file (start/state/<step>.bin)
  SolverSpec solver;
  ContactSpec contact;
  OutputSpec output;
};

}  // namespace fibra
