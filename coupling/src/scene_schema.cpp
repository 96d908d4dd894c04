// The declaration of every scene key. docs/scene-keys.md is generated from it
// (`flowire help scene`).
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/spec.hpp"

#include <string_view>

namespace flowire::coupling {

namespace {
using config::Key;
using config::Type;
using D = units::Dimension;

config::Schema make_schema() {
  config::Schema s;
  auto add = [&](std::string path, Type t, std::string def, D dim, std::string doc,
                 std::vector<std::string> choices = {}) {
    s.add(Key{std::move(path), t, std::move(def), dim, std::move(doc), std::move(choices)});
  };
  // ---- vessels
  add("name", Type::String, "", D::None, "a name for the scene, copied to summary.json");
  add("vessels", Type::Section, "", D::None, "the vessel network (required by flow, contact and fem)");
  add("vessels.file", Type::String, "", D::None,
      "centerline / network file: VMTK or SimVascular .vtp, legacy .vtk, flowire .vtp/.yaml, svOneDSolver .in");
  add("vessels.length_unit", Type::Enum, "", D::None, "unit of the file's coordinates and radii (default: the file's own, else m)",
      {"m", "cm", "mm", "um"});
  add("vessels.surface", Type::String, "", D::None,
      "lumen surface (.vtp, .stl, .obj; in length_unit): the wall the wire touches instead of the network's "
      "cylinders (signed distance to the triangles, open ends open, caps at the network's ends removed); the "
      "network still carries the flow; fem.geometry: lumen meshes it for the FEM comparison");
  add("vessels.surface_smoothing", Type::Number, "", D::Length,
      "width of the soft minimum over nearby triangles that makes the surface's distance smooth for Newton "
      "(default a fifth of the mean edge length; 0: the exact distance)");
  add("vessels.max_segment_length", Type::Number, "5 mm", D::Length, "branches are split into cylinders no longer than this");
  add("vessels.radius_change", Type::Number, "0.1", D::None, "also split where the radius changes by more than this fraction");
  add("vessels.keep_inlet_piece", Type::Bool, "false", D::None,
      "if the network is in several pieces keep the one holding the inlet (with a warning) instead of failing");
  add("vessels.generator", Type::Section, "", D::None, "a built-in anatomy instead of a file");
  add("vessels.generator.type", Type::Enum, "", D::None, "which anatomy",
      {"straight_tube", "y_bifurcation", "aortic_arch", "binary_tree", "arterial_tree"});
  add("vessels.generator.length", Type::Number, "0.1", D::Length, "straight_tube: length");
  add("vessels.generator.radius", Type::Number, "2 mm", D::Length, "straight_tube: radius");
  add("vessels.generator.parent_radius", Type::Number, "5 mm", D::Length, "y_bifurcation: parent radius (daughters by Murray's law)");
  add("vessels.generator.parent_length", Type::Number, "40 mm", D::Length, "y_bifurcation: parent length");
  add("vessels.generator.child_length", Type::Number, "40 mm", D::Length, "y_bifurcation: daughter length");
  add("vessels.generator.angle", Type::Number, "0.6 rad", D::Angle, "y_bifurcation / binary_tree: branching half-angle");
  add("vessels.generator.asymmetry", Type::Number, "0", D::None, "y_bifurcation: flow-split asymmetry in (-1, 1)");
  add("vessels.generator.scale", Type::Number, "1", D::None, "aortic_arch / arterial_tree: size factor (1 = adult)");
  add("vessels.generator.depth", Type::Integer, "5", D::None, "binary_tree: generations (2^(depth+1) - 1 vessels)");
  add("vessels.generator.root_radius", Type::Number, "2 mm", D::Length, "binary_tree: root radius");
  add("vessels.generator.root_length", Type::Number, "20 mm", D::Length, "binary_tree: root length");
  add("vessels.generator.radius_ratio", Type::Number, "0.7937005259840998", D::None, "binary_tree: r(k+1)/r(k) (Murray 2^-1/3)");
  add("vessels.generator.length_ratio", Type::Number, "0.7937005259840998", D::None, "binary_tree: L(k+1)/L(k)");

  flow::declare_scene_keys(s);

  // ---- wire
  add("wire", Type::Section, "", D::None, "the guidewire (absent: no rod is simulated)");
  add("wire.length", Type::Number, "1.0", D::Length, "total wire length");
  add("wire.radius", Type::Number, "0.45 mm", D::Length, "wire radius (0.035 inch wire: 0.445 mm)");
  add("wire.youngs_modulus", Type::Number, "60 GPa", D::Pressure, "shaft Young's (flexural) modulus");
  add("wire.poisson_ratio", Type::Number, "0.33", D::None, "Poisson ratio (shear modulus G = E / (2 (1 + nu)))");
  add("wire.shear_modulus", Type::Number, "", D::Pressure, "shear modulus (overrides poisson_ratio)");
  add("wire.density", Type::Number, "6450", D::Density, "wire density");
  add("wire.segments", Type::Integer, "100", D::None, "number of rod segments");
  add("wire.segment_length", Type::Number, "", D::Length, "rod segment length (overrides segments)");
  add("wire.damping", Type::Number, "0", D::None, "viscous damping (1/s, mass-proportional)");
  add("wire.tip", Type::Section, "", D::None, "a softer, possibly pre-shaped tip");
  add("wire.tip.length", Type::Number, "3 cm", D::Length, "tip length");
  add("wire.tip.youngs_modulus", Type::Number, "10 GPa", D::Pressure, "tip Young's modulus");
  add("wire.tip.shape", Type::Enum, "straight", D::None, "tip shape", {"straight", "angled", "j"});
  add("wire.tip.angle", Type::Number, "", D::Angle,
      "angled/j: total bend angle of the tip (default by shape: 45 deg angled, 180 deg j, the J of the published "
      "experiment)");
  add("wire.tip.bend_radius", Type::Number, "3 mm", D::Length, "angled/j: radius of the pre-bent arc");
  add("wire.adapt", Type::Section, "", D::None,
      "curvature-adaptive resampling: split edges where the wire bends, merge them back where it is straight");
  add("wire.adapt.min_segment_length", Type::Number, "", D::Length, "finest edge (default a quarter of the segment length)");
  add("wire.adapt.max_segment_length", Type::Number, "", D::Length,
      "coarsest edge (default the segment length: merging only undoes refinement)");
  add("wire.adapt.split_angle", Type::Number, "0.1 rad", D::Angle, "turning angle at a vertex above which its edges are split");
  add("wire.adapt.merge_angle", Type::Number, "", D::Angle, "turning angle below which edges merge (default split_angle / 4)");
  add("wire.base", Type::Section, "", D::None, "where the wire is held");
  add("wire.base.position", Type::Vector3, "[0, 0, 0]", D::Length, "base position (vessel scenes: the entry node)");
  add("wire.base.direction", Type::Vector3, "[1, 0, 0]", D::None, "base direction (vessel scenes: into the entry vessel)");
  add("wire.entry", Type::StringOrInteger, "auto", D::None, "network end where the wire enters (node id, or auto)");

  add("catheter", Type::Section, "", D::None,
      "a hollow catheter over the wire, entering at the same point (docs/catheter.md); the wire runs in its lumen");
  add("catheter.length", Type::Number, "1.0", D::Length, "total catheter length");
  add("catheter.outer_radius", Type::Number, "1 mm", D::Length, "outer radius (the wall contact uses it)");
  add("catheter.inner_radius", Type::Number, "0.55 mm", D::Length,
      "lumen radius: the wire's axis stays within inner_radius - wire.radius of the catheter's axis");
  add("catheter.youngs_modulus", Type::Number, "2 GPa", D::Pressure, "Young's modulus of the catheter wall");
  add("catheter.density", Type::Number, "1200", D::Density, "density of the catheter wall");
  add("catheter.initial_length", Type::Number, "2 cm", D::Length, "catheter length inside at t = 0");
  add("catheter.stiffness", Type::Number, "3e4", D::None,
      "lumen penalty per wire vertex (N/m): a wire vertex pushing on the lumen with force F sinks F/k into it");
  add("catheter.insertion", Type::Section, "", D::None, "pushing and turning the catheter at the entry");
  add("catheter.insertion.speed", Type::Number, "0", D::Velocity, "catheter insertion speed (negative: pull back)");
  add("catheter.insertion.rotation_speed", Type::Number, "0", D::AngularSpeed, "catheter rotation speed");

  add("loads", Type::List, "", D::None, "external loads on the wire");
  add("loads[].type", Type::Enum, "", D::None, "load kind", {"tip_force", "tip_moment", "gravity", "point_force"});
  add("loads[].value", Type::Vector3, "", D::None, "force (N), moment (N*m) or acceleration (m/s^2), SI");
  add("loads[].s", Type::Number, "", D::Length, "point_force: arc length from the base");

  add("insertion", Type::Section, "", D::None, "pushing and turning the wire at its base");
  add("insertion.speed", Type::Number, "0", D::Velocity, "insertion speed (negative: pull back)");
  add("insertion.rotation_speed", Type::Number, "0", D::AngularSpeed, "base rotation speed");
  add("insertion.rotation_angle", Type::Number, "0", D::Angle, "base rotation at the start (turns a pre-shaped tip)");
  add("insertion.initial_length", Type::Number, "2 cm", D::Length, "length inside at t = 0");
  add("insertion.schedule", Type::String, "", D::None,
      "CSV with columns time,speed,rotation_speed (SI): from each row's time on, push (> 0), pull (< 0) or hold, "
      "and turn; replaces speed and rotation_speed (docs/insertion.md)");
  add("insertion.max_length", Type::Number, "", D::Length, "stop pushing at this inserted length");
  add("insertion.max_force", Type::Number, "", D::Force,
      "force-limited feeding: hold the feed in steps that start with the wire pushed in harder than this "
      "(a drive's or a hand's limit); default unlimited (the feed is kinematic)");

  add("insertion.force", Type::Number, "", D::Force,
      "force-driven feeding: push the base with this constant force; each step's feed is the one for which the "
      "clamp's axial force equals it (replaces speed; docs/insertion.md)");

  add("contact", Type::Section, "", D::None, "wall contact (present by default when a wire moves in vessels)");
  add("contact.enabled", Type::Bool, "true", D::None,
      "false: no wall contact at all (no lookup or wall distance unless the blood drag needs them)");
  add("contact.friction", Type::Number, "0.1", D::None, "Coulomb friction coefficient (shaft)");
  add("contact.tip_friction", Type::Number, "", D::None, "Coulomb friction coefficient of the tip (default: friction)");
  add("contact.stiffness", Type::Number, "3e4", D::None,
      "penalty stiffness per vertex of the segment_length grid (N/m): a vertex pressed with force F sinks F/k into the wall (scaled with the edge length where wire.adapt refines)");
  add("contact.settle", Type::Bool, "true", D::None,
      "start a dynamic run from the static equilibrium of the initial wire against the walls (a pre-shaped tip "
      "squeezed into the lumen) instead of from its free shape");
  add("contact.allow_outside", Type::Bool, "false", D::None,
      "a wire that ends up more than its radius outside the lumen makes the run fail (status outside, exit 3) "
      "unless this is true (status outside, exit 0)");
  add("contact.introducer", Type::Bool, "true", D::None,
      "the entry is an introducer sheath: the wire cannot come back out behind the entry plane (within twice the "
      "entry vessel's radius of its axis)");
  add("contact.viscous_friction", Type::Number, "0", D::None, "viscous wall friction (N*s/m per unit length)");

  add("obstacles", Type::List, "", D::None, "regions that resist the tip (a clot, a tight lesion)");
  add("obstacles[].center", Type::Vector3, "", D::Length, "centre of the spherical region");
  add("obstacles[].radius", Type::Number, "", D::Length, "radius of the region");
  add("obstacles[].force", Type::Number, "", D::Force, "resistance opposing the tip's advance while it is inside");

  add("coupling", Type::Section, "", D::None, "how blood acts on the wire");
  add("coupling.drag", Type::Enum, "cylinder", D::None,
      "cylinder: cross-flow drag from the cylinder drag curve C_D(Re) (creeping flow to Re 2e5) and the exact "
      "annular Poiseuille shear along the wire | slender_body: resistive-force (Stokes) drag, Re << 1 only | "
      "velocity_offset: the published form (blood velocity added to the velocity update) | none",
      {"cylinder", "slender_body", "velocity_offset", "none"});
  add("coupling.drag_scale", Type::Number, "1", D::None, "multiplies the drag force");
  add("coupling.occlusion", Type::Enum, "annulus", D::None,
      "annulus: the wire raises the resistance of the segments it lies in (concentric to eccentric annular "
      "Poiseuille flow at its offset; updated every flow evaluation; needs flow.solver superposition, sparse or "
      "flow.model rlc) | none: the flow ignores the wire",
      {"annulus", "none"});
  add("coupling.flow_every", Type::Integer, "1", D::None, "evaluate the flow every this many rod steps");
  add("coupling.steering", Type::Section, "", D::None, "a lateral force on the tip towards a chosen branch");
  add("coupling.steering.branch", Type::String, "", D::None, "name of the branch to steer into");
  add("coupling.steering.force", Type::Number, "5 mN", D::Force, "steering force");
  add("coupling.steering.range", Type::Number, "2 cm", D::Length, "active while the tip is this close to the target");
  add("coupling.steering.offset", Type::Number, "1 cm", D::Length, "target: this far along the branch from its start");

  add("solve", Type::Section, "{}", D::None, "time stepping (also drives flow-only scenes: one flow frame per step)");
  add("solve.mode", Type::Enum, "dynamic", D::None, "static: equilibrium; dynamic: time stepping", {"static", "dynamic"});
  add("solve.dt", Type::Number, "1 ms", D::Time, "time step");
  add("solve.duration", Type::Number, "0", D::Time, "simulated time (0: one frame / the steady state)");
  add("solve.integrator", Type::Enum, "implicit_euler", D::None, "rod time integrator", {"implicit_euler", "implicit_midpoint"});

  add("fem", Type::Section, "", D::None, "finite-element comparison of the flow (needs FLOWIRE_WITH_FEM)");
  add("fem.geometry", Type::Enum, "network", D::None,
      "network: the lumen of the vessels (compared with the flow); dfg_3d_1z: the DFG benchmark 3D-1Z channel "
      "around a cylinder with its own fluid and inflow (needs no vessels or flow; writes fem_forces.csv, c_D, c_L "
      "and the pressure difference in summary.json); lumen: the real lumen of vessels.surface, its open ends "
      "tagged by the nearest centerline ends, compared with the flow as network is",
      {"network", "dfg_3d_1z", "lumen"});
  add("fem.mesh_size", Type::Number, "", D::Length,
      "target tetrahedron size (network: default from the smallest radius; dfg_3d_1z: far field, default 0.08 m)");
  add("fem.size_factor", Type::Number, "0.3", D::None,
      "network / lumen without fem.mesh_size: tetrahedron size = this times the radius of the nearest vessel");
  add("fem.obstacle_mesh_size", Type::Number, "", D::Length,
      "dfg_3d_1z: tetrahedron size on the cylinder (default a quarter of fem.mesh_size), growing with the distance "
      "from it by fem.mesh_growth");
  add("fem.mesh_growth", Type::Number, "0.3", D::None,
      "dfg_3d_1z: increase of the tetrahedron size per unit distance from the obstacle");
  add("fem.equations", Type::Enum, "stokes", D::None, "stokes | navier_stokes", {"stokes", "navier_stokes"});
  add("fem.solver", Type::Enum, "mumps", D::None, "direct (mumps) or iterative (fieldsplit, Stokes only)", {"mumps", "fieldsplit"});
  add("fem.stabilization", Type::Enum, "supg", D::None,
      "navier_stokes: supg (SUPG + grad-div, consistent) or none (plain Galerkin)", {"supg", "none"});
  add("fem.inlet", Type::Enum, "profile", D::None,
      "navier_stokes: profile (a Poiseuille velocity profile scaled to the inlet pressure or flow) or traction",
      {"profile", "traction"});
  add("fem.backflow", Type::Number, "1", D::None, "navier_stokes: outlet backflow stabilization coefficient (0: off)");
  add("fem.time_dependent", Type::Bool, "false", D::None,
      "frames from time-dependent Stokes (BDF2, inertia included) instead of quasi-steady solves; needs fem.frames");
  add("fem.steps_per_period", Type::Integer, "200", D::None,
      "time steps per period of a time-dependent series or of windkessel outlets (rounded up to a multiple of fem.frames)");
  add("fem.samples_per_branch", Type::Integer, "10", D::None, "comparison points per branch");
  add("fem.frames", Type::Integer, "0", D::None,
      "0: steady comparison only; N: also N quasi-steady frames over one inlet period (fem_pulsatile*.csv, fem.pvd)");

  add("output", Type::Section, "{}", D::None, "what is written and where");
  add("output.dir", Type::String, "out", D::None, "output folder (relative to the working directory)");
  add("output.every", Type::Number, "0", D::Time, "output interval of simulated time (0: only the final state)");
  add("output.vtk", Type::Bool, "true", D::None, "write .vtp/.pvd files");
  add("output.csv", Type::Bool, "true", D::None, "write .csv files");
  add("output.png", Type::Bool, "false", D::None, "render PNG pictures (needs an X server, e.g. xvfb-run)");
  return s;
}
}  // namespace

const config::Schema& scene_schema() {
  static const config::Schema schema = make_schema();
  return schema;
}

}  // namespace flowire::coupling
