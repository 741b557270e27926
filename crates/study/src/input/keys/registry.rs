//! The registry's data: every table of a study file and its keys, in the order the doc lists
//! them. A key's kinds, when given, are the only kinds of its table that take it.

use super::{Key, Presence, Table};

const REQ: Presence = Presence::Required;
const OPT: Presence = Presence::Optional;

const fn def(value: &'static str) -> Presence {
    Presence::Default(value)
}

/// `key!(name, type, unit, presence, [kinds [..] or a const array,] [range "..",] doc)`
macro_rules! key {
    ($name:literal, $ty:expr, $unit:literal, $presence:expr, $(kinds $kinds:expr,)? $(range $range:literal,)? $doc:literal $(,)?) => {
        Key {
            name: $name,
            kinds: key!(@kinds $($kinds)?),
            ty: $ty,
            unit: $unit,
            presence: $presence,
            range: key!(@range $($range)?),
            doc: $doc,
        }
    };
    (@kinds) => { &[] };
    (@kinds $kinds:expr) => { &$kinds };
    (@range) => { "" };
    (@range $range:literal) => { $range };
}

/// `a` followed by `b`, for a kinds list that extends another one.
const fn concat<const A: usize, const B: usize, const N: usize>(
    a: [&'static str; A],
    b: [&'static str; B],
) -> [&'static str; N] {
    assert!(A + B == N, "the lengths of the kinds lists do not add up");
    let mut out = [""; N];
    let mut i = 0;
    while i < A {
        out[i] = a[i];
        i += 1;
    }
    while i < N {
        out[i] = b[i - A];
        i += 1;
    }
    out
}

/// The sensors that measure something named by `of` (a point, body, joint, driver, actuator).
const MEASURED_SENSORS: [&str; 16] = [
    "position",
    "displacement",
    "relative-position",
    "rotation",
    "velocity",
    "angular-velocity",
    "deflection",
    "joint",
    "joint-rate",
    "modal",
    "reaction",
    "driver-effort",
    "actuator-effort",
    "stress",
    "acceleration",
    "angular-acceleration",
];

/// Every sensor: the measured ones and those of the whole mechanism.
const SENSOR_KINDS: [&str; 19] = concat(MEASURED_SENSORS, ["energy", "momentum", "energy-balance"]);

const VEC3: &str = "[x, y, z]";

/// Every table of a study file.
pub static TABLES: &[Table] = &[
    Table::plain(
        "",
        "the file",
        &[
            key!("study", "table", "", OPT, "title and description, for reports"),
            key!("materials", "list of tables", "", OPT, "linear elastic materials"),
            key!("sections", "list of tables", "", OPT, "beam cross-sections"),
            key!("parts", "list of tables", "", OPT, "FE models: generated beams, generated boxes, meshes"),
            key!("bodies", "list of tables", "", OPT, "flexible bodies of the mechanism"),
            key!("rigid_bodies", "list of tables", "", OPT, "rigid bodies of the mechanism"),
            key!("point_masses", "list of tables", "", OPT, "point masses of the mechanism"),
            key!("springs", "list of tables", "", OPT, "point-to-point spring-dampers"),
            key!("supports", "list of tables", "", OPT, "points of the mechanism held by the ground"),
            key!("joints", "list of tables", "", OPT, "joints of the mechanism"),
            key!("drivers", "list of tables", "", OPT, "joint coordinates given as functions of time"),
            key!("loads", "list of tables", "", OPT, "gravity and point loads on the mechanism"),
            key!("sensors", "list of tables", "", OPT, "named outputs of the mechanism's analyses"),
            key!("initial", "list of tables", "", OPT, "initial values and velocities of the mechanism"),
            key!("joint_springs", "list of tables", "", OPT, "spring-dampers on joint coordinates"),
            key!("joint_limits", "list of tables", "", OPT, "stops on joint coordinates"),
            key!("actuators", "list of tables", "", OPT, "forces or torques on joint coordinates"),
            key!("output", "table", "", OPT, "how often the mechanism's analyses write"),
            key!("analyses", "list of tables", "", OPT, "what to compute"),
        ],
    ),
    Table::plain(
        "study",
        "[study]",
        &[
            key!("title", "string", "", OPT, "the study's title, for reports"),
            key!("description", "string", "", OPT, "what the study is about, for reports"),
        ],
    ),
    Table::plain(
        "materials",
        "[[materials]]",
        &[
            key!("name", "string", "", REQ, "unique among the materials"),
            key!("E", "number", "Pa", REQ, range "> 0", "Young's modulus"),
            key!("nu", "number", "", OPT, range "(-1, 0.5)", "Poisson's ratio; give `nu` or `G`, one of them"),
            key!("G", "number", "Pa", OPT, range "> 0", "or the shear modulus (then nu = E/2G - 1 must be in range)"),
            key!("rho", "number", "kg/m³", REQ, range ">= 0", "density"),
        ],
    ),
    Table {
        path: "sections",
        header: "[[sections]]",
        kinds_from: "`shape`",
        kinds: &["rectangle", "circle", "tube", "values"],
        keys: &[
            key!("name", "string", "", REQ, "unique among the sections"),
            key!("shape", "string", "", REQ, range "`rectangle`, `circle`, `tube`, `values`", "how the section is given"),
            key!("b", "number", "m", REQ, kinds ["rectangle"], range "> 0", "width along local y (Saint-Venant torsion constant, Cowper's shear factor with the part material's nu)"),
            key!("h", "number", "m", REQ, kinds ["rectangle"], range "> 0", "height along local z"),
            key!("d", "number", "m", REQ, kinds ["circle"], range "> 0", "diameter"),
            key!("d_outer", "number", "m", REQ, kinds ["tube"], range "> 0", "outer diameter"),
            key!("d_inner", "number", "m", REQ, kinds ["tube"], range "[0, `d_outer`)", "inner diameter, 0 for a solid circle"),
            key!("A", "number", "m²", REQ, kinds ["values"], range "> 0", "area"),
            key!("Iy", "number", "m⁴", REQ, kinds ["values"], range "> 0", "second moment about local y: resists bending in the x-z plane"),
            key!("Iz", "number", "m⁴", REQ, kinds ["values"], range "> 0", "second moment about local z: resists bending in the x-y plane"),
            key!("J", "number", "m⁴", REQ, kinds ["values"], range "> 0", "torsion constant"),
            key!("ky", "number", "", def("5/6"), kinds ["values"], range "(0, 1]", "shear factor for shear along local y"),
            key!("kz", "number", "", def("5/6"), kinds ["values"], range "(0, 1]", "shear factor for shear along local z"),
        ],
    },
    Table::plain(
        "parts",
        "[[parts]]",
        &[
            key!("name", "string", "", REQ, "unique among the parts"),
            key!("material", "string", "", OPT, "the material of every element; required, except for meshes with `mesh.materials` and files that bring their own"),
            key!("mass", "string", "", def("`consistent`"), range "`consistent`, `lumped`", "the mass matrix"),
            key!("beam", "table", "", OPT, "`[parts.beam]`: a generated beam structure; give `beam`, `box` or `mesh`, exactly one"),
            key!("box", "table", "", OPT, "`[parts.box]`: a generated solid box"),
            key!("mesh", "table", "", OPT, "`[parts.mesh]`: a gmsh, Abaqus or Nastran mesh"),
            key!("interfaces", "list of tables", "", OPT, "`[[parts.interfaces]]`: the 6-dof connection points of the part"),
            key!("reduction", "table", "", OPT, "`[parts.reduction]`: Craig-Bampton settings"),
        ],
    ),
    Table {
        path: "parts.beam",
        header: "[parts.beam]",
        kinds_from: "`kind`",
        kinds: &["straight", "arc", "frame"],
        keys: &[
            key!("kind", "string", "", REQ, range "`straight`, `arc`, `frame`", "the generator"),
            key!("section", "string", "", REQ, "the section of every element"),
            key!("theory", "string", "", def("`timoshenko`"), range "`timoshenko`, `euler-bernoulli`", "the beam theory"),
            key!("orientation", VEC3, "", OPT, kinds ["straight", "frame"], "a vector in the local x-y plane of the elements; default global z, or global y for a beam within about 6° of z"),
            key!("elements", "integer", "", REQ, kinds ["straight", "arc"], range "1 to 100000", "number of elements"),
            key!("from", VEC3, "m", REQ, kinds ["straight"], "first end point"),
            key!("to", VEC3, "m", REQ, kinds ["straight"], "last end point"),
            key!("center", VEC3, "m", REQ, kinds ["arc"], "centre of the arc; local y points to the centre, so `Iz` is the in-plane stiffness"),
            key!("start", VEC3, "m", REQ, kinds ["arc"], "first point of the arc"),
            key!("axis", VEC3, "", REQ, kinds ["arc"], "normal of the arc's plane"),
            key!("angle_deg", "number", "°", REQ, kinds ["arc"], "swept angle, right-handed about `axis`"),
            key!("points", "list of [x, y, z]", "m", REQ, kinds ["frame"], "joint points `[[x, y, z], ...]`; members meeting at a point share its node (a rigid joint)"),
            key!("members", "list of tables", "", REQ, kinds ["frame"], "members `[{ from = 0, to = 1, elements = 4 }, ...]` (below)"),
        ],
    },
    Table::plain(
        "parts.beam.members",
        "members = [{ ... }]",
        &[
            key!("from", "integer", "", REQ, "first point (0-based index into `points`)"),
            key!("to", "integer", "", REQ, "last point (0-based index into `points`)"),
            key!("elements", "integer", "", REQ, range "1 to 100000", "number of elements"),
            key!("section", "string", "", def("the beam's `section`"), "the member's section"),
            key!("orientation", VEC3, "", def("the beam's `orientation`"), "a vector in the local x-y plane of the member's elements"),
        ],
    ),
    Table::plain(
        "parts.box",
        "[parts.box]",
        &[
            key!("size", "[Lx, Ly, Lz]", "m", REQ, range "> 0", "the box's edges along x, y, z"),
            key!("divisions", "[nx, ny, nz]", "", REQ, range ">= 1", "bricks along each axis, at most 2,000,000 cells in all"),
            key!("element", "string", "", REQ, range "`hex8`, `hex20`, `tet4`, `tet10`, `wedge6`", "`hex8`, `hex20`, `tet4` (six per brick; locks in bending, for contrast), `tet10` (six per brick), `wedge6` (two per brick)"),
            key!("origin", VEC3, "m", def("`[0, 0, 0]`"), "the corner with the lowest coordinates"),
        ],
    ),
    Table::plain(
        "parts.mesh",
        "[parts.mesh]",
        &[
            key!("file", "string", "", REQ, "the mesh file, relative to the study file: gmsh `.msh` (MSH 4.1 or 2.2, ASCII or binary), Abaqus `.inp`, or Nastran bulk data `.bdf`, `.nas`, `.dat` (the extension says which)"),
            key!("units", "string", "", def("`SI`"), range "`SI`, `m-kg-s`, `mm-t-s`, `mm-kg-ms`", "the unit system the file is written in, converted to SI on read: `mm-t-s` reads lengths in mm, moduli in MPa, densities in t/mm^3 (steel: 210000, 7.85e-9); `mm-kg-ms` lengths in mm, moduli in GPa, densities in kg/mm^3. An Abaqus or Nastran material whose constants no solid has is a warning that names the unit system its numbers fit"),
            key!("materials", "{ set = string }", "", OPT, r#"a material per physical volume (gmsh) or element set (Abaqus `*ELSET`, Nastran `PSOLID_<pid>`), `{ body = "steel", insert = "brass" }`; every volume (or beam) cell must be in exactly one of them"#),
        ],
    ),
    Table {
        path: "parts.interfaces",
        header: "[[parts.interfaces]]",
        kinds_from: "the part's elements",
        kinds: &["beam", "solid"],
        keys: &[
            key!("name", "string", "", REQ, "unique in the part (`auxiliary` is reserved)"),
            key!("set", "string", "", OPT, r#"beams: a node set with one node, such as `"beam.end"`; solids: the surface nodes, a node set (physical group, Abaqus or Nastran set, or `x0` ... of a box)"#),
            key!("near", VEC3, "m", OPT, kinds ["solid"], "or every node within `radius` of the point `near`"),
            key!("radius", "number", "m", OPT, kinds ["solid"], range "> 0", "with `near`: the radius of the patch"),
            key!("node_at", VEC3, "m", OPT, kinds ["beam"], "or the node at this position (within a millionth of the part's size)"),
            key!("spider", "string", "", OPT, kinds ["solid"], range "`rbe2`, `rbe3`", "`rbe2` (the surface follows the interface rigidly: stiffens it) or `rbe3` (the interface follows the weighted mean motion of the surface: adds no stiffness); default for a Nastran `RBE2_<eid>` / `RBE3_<eid>` set: that element's kind. RBE3 weights are the tributary areas of the boundary faces whose nodes all lie in the set; set nodes on none of them (inside the solid, or at the fringe of a `near`/`radius` patch) get weight zero"),
            key!("node_position", VEC3, "m", OPT, kinds ["solid"], "where the interface node goes; default: the Nastran RBE's reference grid for its set, else the area centroid of those faces (or the mean of the nodes when the set covers no whole face)"),
        ],
    },
    Table::plain(
        "parts.reduction",
        "[parts.reduction]",
        &[
            key!("modes", "integer", "", OPT, range "0 to 10000", "number of fixed-interface modes to keep (0: static modes only); fewer than the part's interior dofs (the free dofs not on an interface): a larger count is refused with the part and both counts named. Give `modes` or `cutoff_hz`"),
            key!("cutoff_hz", "number", "Hz", OPT, range "> 0", "or keep every fixed-interface mode below this frequency"),
            key!("auxiliary_node", "bool", "", def("`false`"), "`true`: add an interface at the centre of mass, held during the reduction (the `auxiliary-node` frame choice). Beams: the beam node there (use an even number of elements on a symmetric beam); solids: an RBE3 spider on every node"),
            key!("keep_mesh_shapes", "bool", "", def("`true`"), "keep the mode shapes on every mesh node in the reduced-body file (for ParaView and stress recovery)"),
            key!("geometric_stiffening", "bool", "", def("`false`"), r"`true`: also store the reduced geometric stiffness $\mathbf G_k$ of every CB coordinate's stress, so the body's strain energy gains the cubic term through which an axial force changes its bending stiffness (a column's buckling load, a rotor's centrifugal stiffening). Use it when one body carries axial forces that are a sizeable fraction of its buckling load (e.g. a connecting rod modelled as one body); it costs $n^3$ numbers in the file and two passes over them per evaluation"),
            key!("inertia_correction", "bool", "", def("`false`"), r"`true`: also add to the modes the static response of the body to the inertia of its interfaces' motion, $\mathbf K_{ii}^{-1}(\mathbf M_{ii}\boldsymbol\Psi + \mathbf M_{ib})$ ([theory guide, 3.7](theory.md#37-static-correction-for-the-interfaces-inertia)), so that the quasi-static deformation and stress under the body's own inertia, such as the axial force along a connecting rod or a spinning beam, are in the basis whatever the number of modes. Use it with `geometric_stiffening` on one body that carries a large axial force from its own inertia: there the axial force sets the bending stiffness, and without the correction every axial mode that enters the basis moves the result (by up to 0.2 % on the slider-crank rod as one body, which converges in the modes only once two axial modes are in; with the correction it is converged from 6 modes on: [benchmarks](../BENCHMARKS.md#one-beam-superelement-convergence-in-the-modes)). Costs 6 more coordinates per interface (12 for a rod with two interfaces; on the slider-crank rod with 2 modes, 26 coordinates instead of 14 and 2.5 times the CPU time per step)"),
            key!("planar", "bool", "", def("`false`"), r"`true`: reduce a beam part that lies in one plane $z = z_0$ of its own axes as a planar part, and evaluate its bodies in the global xy-plane (`planar` of `[[bodies]]`). The out-of-plane dofs $u_z, \theta_x, \theta_y$ of every node that is not an interface are supported during the reduction, so every fixed-interface mode bends in the plane (`modes = 2` keeps the first two in-plane modes, where a round rod reduced in 3D would keep one in-plane and one out-of-plane mode of the same frequency); the interfaces keep their six dofs. A planar body has 3 coordinates per interface ($x$, $y$, the rotation about $z$) instead of 6: on the C2 slider-crank one planar rod with 3 modes costs a third of the spatial two-body rod's instructions per step, within the same 0.05 % of the reference ([benchmarks](../BENCHMARKS.md#the-slider-crank-as-a-planar-mechanism)). Refused by name: a part with an element that is not a beam, a node off the plane of the others, a section whose principal axes are not along $z$ and in the plane (the in-plane and out-of-plane motions would couple). The mechanism must keep every node of the body in the plane (below, `[[bodies]]`)"),
            key!("stress_shapes", "bool", "", def("`false`"), r"`true`: also store the stress of every CB coordinate (solids: the stress tensor at every mesh node, from the element stresses at the integration points extrapolated to the nodes and averaged there, plain mean over the elements at a node; beams: the section forces $N, V_y, V_z, T, M_y, M_z$ at both ends of every element, and the extreme-fibre stresses of sections given by shape). The mechanism's analyses then write the stresses of the body and its hot spot. Costs $6 n_{nodes} n$ numbers in the file"),
            key!("load_points", "list of tables", "", OPT, r#"points inside the body where loads act, with static correction: `[{ name = "hub", node_at = [x, y, z] }, ...]` or `{ name = ..., set = "a-one-node-set" }`. Each adds one attachment mode per free dof of its node (3 for a solid node, 6 for a beam node): the static response to a unit load there with the interfaces held, made orthogonal to the kept modes (residual flexibility). The quasi-static response, and stress, to loads at the points is then exact whatever the number of modes. Not on an interface node (its constraint modes already do this)"#),
            key!("factor", "string", "", def(r#"`"auto"`"#), range r#"`"auto"`, `"double"`, `"single"`"#, r#"precision of the sparse Cholesky factor of the interior stiffness $\mathbf K_{ii}$. A single-precision factor takes half the memory (the factor dominates a large body's memory: 29 GB in double precision for a 1M-dof tet10 body); its solves are refined in double precision (residual with $\mathbf K_{ii}$ itself, corrections with the factor) to a double-precision solve's accuracy, and the modes come from a Lanczos on $\mathbf K_{ii}^{-1}\mathbf M_{ii}$ in the mass inner product, so the body is the same (eigenvalues to $10^{-10}$) while the eigensolver takes about 3x the CPU time (3 single-precision solves per vector; measured on a 50k-dof block). `"auto"` takes double precision when the factor with the larger of its workspace (freed when the factorisation ends) and the reduction's vectors fits in 90 % of the available memory (`MemAvailable` of `/proc/meminfo`, measured after the symbolic analysis with the stiffness and mass already in memory, and a control group's limit), else single precision. A precision that does not fit is refused before the factorisation, with the factor's size and the memory available in GB; a stiffness too poorly conditioned for single precision (a pivot breaking down, or refinement that stops converging) is refused by name with the advice to use `"double"`. Changing it does not invalidate the cached body"#),
        ],
    ),
    Table::plain(
        "parts.reduction.load_points",
        "load_points = [{ ... }]",
        &[
            key!("name", "string", "", REQ, "unique in the part; loads name it `body.name`"),
            key!("set", "string", "", OPT, "a node set with one node"),
            key!("node_at", VEC3, "m", OPT, "or the node at this position"),
        ],
    ),
    Table {
        path: "analyses",
        header: "[[analyses]]",
        kinds_from: "`type`",
        kinds: &["static", "modal", "reduce", "equilibrium", "dynamic", "linearized", "buckling"],
        keys: &[
            key!("type", "string", "", REQ, range "`static`, `modal`, `reduce`, `equilibrium`, `dynamic`, `linearized`, `buckling`", "what to compute"),
            key!("name", "string", "", def("`<type>-<part>`, or the type for a multibody analysis"), "names the results folder; unique among the analyses"),
            key!("part", "string", "", REQ, kinds ["static", "modal", "reduce"], "the part the analysis runs on (`reduce`: a part with a `[parts.reduction]`)"),
            key!("supports", "list of tables", "", OPT, kinds ["static", "modal"], r#"`[{ at = "root", dofs = "all" }, ...]`: `at` is an interface or a node set of the part (every node of the set is held), or `node_at = [x, y, z]`; `dofs` is `"all"` (default), `"translations"`, `"rotations"` or a list such as `["ux", "uy", "rz"]` (rotations of solid mesh nodes do not exist and are ignored). `modal` without supports: the first six modes are rigid-body modes, reported at 0 Hz (never negative) and flagged in the `rigid body` column of `frequencies.csv`"#),
            key!("loads", "list of tables", "", REQ, kinds ["static"], r#"`[{ at = "tip", force = [Fx, Fy, Fz], moment = [Mx, My, Mz] }, ...]` [N, N m] in global axes, at an interface, a one-node set or `node_at`; to load a face, load an RBE3 interface on it. Solid mesh nodes take no moments"#),
            key!("modes", "integer", "", def("required (`modal`), 10 (`linearized`), 4 (`buckling`)"), kinds ["modal", "linearized", "buckling"], range "1 to 10000", "`modal`: how many modes; `linearized`: how many frequencies to report; `buckling`: how many critical load factors to report"),
            key!("solver", "string", "", def("`auto`"), kinds ["modal"], range "`auto`, `dense`, `sparse`", "the eigensolver: `auto` is dense up to 1500 free dofs, sparse shift-invert above"),
            key!("steps", "integer", "", def("1"), kinds ["equilibrium", "buckling"], range "1 to 100000", "load steps: the load factor grows in `steps` increments, longer when Newton converges fast, halved when it fails"),
            key!("t_end", "number", "s", REQ, kinds ["dynamic"], range "> 0", "the end time; with `start`, after the start's time; a `t_end` that is not a multiple of `dt` is reached exactly by a shortened last step"),
            key!("dt", "number", "s", OPT, kinds ["dynamic", "linearized"], range "> 0", "`dynamic`: the time step (required; at most `t_end`, the first step of an adaptive run); `linearized`: with `at_time`, the step of the dynamic run that reaches the state"),
            key!("rho_inf", "number", "", def("0.9"), kinds ["dynamic"], range "[0, 1]", "spectral radius at infinity of generalized-α"),
            key!("tolerance", "number", "", def("1e-10 (`equilibrium`, `buckling`), 1e-9 (`dynamic`)"), kinds ["equilibrium", "dynamic", "buckling"], range "[1e-14, 1)", "Newton tolerance on the relative residual (round-off in double precision leaves about 1e-15, so a smaller one is never reached; 1 accepts any state)"),
            key!("method", "string", "", def("`newton`"), kinds ["equilibrium"], range "`newton`, `arc-length`", "`newton`: load stepping; `arc-length`: Crisfield's spherical arc-length continuation, which passes limit points (the first arc spans about 1/`steps` of the load and the path ends at load factor 1)"),
            key!("max_iterations", "integer", "", def("25 (`equilibrium`, `buckling`), 20 (`dynamic`)"), kinds ["equilibrium", "dynamic", "buckling"], range ">= 1", "Newton iterations per step"),
            key!("newton", "string", "", def(r#"`"full"`"#), kinds ["dynamic"], range r#"`"full"`, `"modified"`"#, r#"`"full"`: new tangents at every correction; `"modified"`: the factorised iteration matrix kept across corrections and steps, rebuilt when a correction contracts the residual by less than 100 times, and full Newton for a step that fails"#),
            key!("translations", "string", "", def(r#"`"fixed"`"#), kinds ["dynamic"], range r#"`"fixed"`, `"body"`"#, r#"`"body"`: the translations of free nodes carried in their body axes by the integrator, as rotations always are; for long runs of fast steady rotation, where the fixed-axis form can let a high mode grow at `rho_inf` near 1"#),
            key!("about", "string", "", def(r#"`"initial"`"#), kinds ["linearized"], range r#"`"initial"`, `"equilibrium"`"#, "the state linearised about: the initial configuration, or the static equilibrium; or give `start`, or `at_time` with `dt`"),
            key!("at_time", "number", "s", def("0 (`equilibrium`)"), kinds ["equilibrium", "linearized"], range ">= 0", "`equilibrium`: the time at which drivers and load functions are evaluated; `linearized`: the state reached at this time by a dynamic run with step `dt`"),
            key!("start", "string", "", OPT, kinds ["equilibrium", "dynamic", "linearized", "buckling"], "start from the final state of the earlier `equilibrium` or `dynamic` analysis of this name (below)"),
            key!("dt_min", "number", "s", def("`dt`/1024"), kinds ["dynamic"], range "> 0", "smallest step of the retry after a failed step and of the adaptive step"),
            key!("dt_max", "number", "s", def("`t_end`"), kinds ["dynamic"], range "> 0", "largest adaptive step"),
            key!("error_tolerance", "number", "", OPT, kinds ["dynamic"], range "> 0", "local error tolerance of the adaptive step (selects it; below)"),
        ],
    },
    Table::plain(
        "analyses.supports",
        "supports = [{ ... }]",
        &[
            key!("at", "string", "", OPT, "an interface or a node set of the part (every node of the set is held)"),
            key!("node_at", VEC3, "m", OPT, "or the node at this position"),
            key!("dofs", "string or list of strings", "", def(r#"`"all"`"#), range r#"`"all"`, `"translations"`, `"rotations"`"#, r#"the held dofs, or a list of them such as `["ux", "rz"]`"#),
        ],
    ),
    Table::plain(
        "analyses.loads",
        "loads = [{ ... }]",
        &[
            key!("at", "string", "", OPT, "an interface or a one-node set of the part"),
            key!("node_at", VEC3, "m", OPT, "or the node at this position"),
            key!("force", VEC3, "N", OPT, "force in global axes"),
            key!("moment", VEC3, "N m", OPT, "moment in global axes"),
        ],
    ),
    Table::plain(
        "bodies",
        "[[bodies]]",
        &[
            key!("name", "string", "", REQ, "unique among flexible and rigid bodies; no `.`, not `ground`"),
            key!("part", "string", "", OPT, "a part with `[parts.reduction]` (reduced through the cache); give `part`, `file` or `matrices`, one of them"),
            key!("file", "string", "", OPT, "or a reduced-body file (`.rbody`) or an MBDyn modal element file (`.fem`: every exposed node is an interface, named by its label), relative to the study file"),
            key!("matrices", "table", "", OPT, "or `[bodies.matrices]` below"),
            key!("frame", "string", "", def("`center-of-mass`"), range "`center-of-mass`, `interface-node`, `auxiliary-node`", r#"the floating frame: `interface-node` with `frame_interface = "A"`, `auxiliary-node` for a part reduced with `auxiliary_node = true`"#),
            key!("frame_interface", "string", "", OPT, r#"with `frame = "interface-node"`: which interface"#),
            key!("inertia", "string", "", def("`exact`"), range "`exact`, `lumped`", "the inertia terms (theory guide §6)"),
            key!("position", VEC3, "m", def("`[0, 0, 0]`"), "where the part's origin goes: interface `k` sits at `rotation * x_k + position`"),
            key!("rotation", "table", "", OPT, "the part's rotation `{ axis = [..], angle_deg = .. }`"),
            key!("damping", "table", "", OPT, "`{ alpha = .., beta = .. }` Rayleigh factors [1/s, s] and/or `{ modal_ratio = .. }` [-] (the fraction of critical damping of every fixed-interface mode, 0.02 for 2 %; at most 1, a warning from 0.2)"),
            key!("planar", "bool", "", def("its part's `planar`"), r"`true`: evaluate the body in the global xy-plane, with the in-plane coordinates of its interfaces and its modes only (`false` for a body from a file). Its `rotation` must be about $z$, and every point of the body must stay in the xy-plane turning about $z$ only: held by a support (`clamp`, `slider` or `plane`/`planar` with axis in or normal to the plane as fits, `hinge` about $z$) or the child of a joint that keeps it there (revolute about $z$, prismatic along an in-plane axis, planar with normal $z$) whose parent is held so too. A point between two planar bodies that nothing else holds needs a `planar` support with axis $z$. Otherwise the run is refused at the body, naming the point and what lets it leave the plane (a planar body gives the out-of-plane motion no stiffness or mass)"),
        ],
    ),
    Table::plain(
        "bodies.matrices",
        "[bodies.matrices]",
        &[
            key!("stiffness", "string", "", REQ, "Matrix Market file (`coordinate real`, `general` or `symmetric`) of K [N/m, N m/rad], one row per dof"),
            key!("mass", "string", "", REQ, "Matrix Market file of M [kg, kg m²], one row per dof"),
            key!("nodes", "string", "", REQ, "node table: one line `x y z` [m] per node; node `k` is the `k`-th data line, from 0; `#` starts a comment line"),
            key!("dofs", "string", "", OPT, "dof table: one line `node dof` per matrix row, `dof` one of `ux uy uz rx ry rz`; give `dofs` or `dofs_per_node`, one of them"),
            key!("dofs_per_node", "integer", "", OPT, range "3, 6", "or `3` (solids) / `6` (beams): every node's dofs in node order"),
            key!("interfaces", "{ name = integer }", "", REQ, "`{ a = 0, b = 12 }`: interface name = node (from 0); each needs its six dofs in the matrices"),
            key!("modes", "integer", "", OPT, "fixed-interface modes: a count; give `modes` or `cutoff_hz`, one of them"),
            key!("cutoff_hz", "number", "Hz", OPT, range "> 0", "or every fixed-interface mode below this frequency"),
        ],
    ),
    Table::plain(
        "bodies.rotation",
        "rotation = { ... }",
        &[
            key!("axis", VEC3, "", REQ, "the axis of the rotation, in global axes"),
            key!("angle_deg", "number", "°", REQ, "the angle, right-handed about `axis`"),
        ],
    ),
    Table::plain(
        "bodies.damping",
        "damping = { ... }",
        &[
            key!("alpha", "number", "1/s", OPT, range ">= 0", "Rayleigh mass factor (on the CB matrices)"),
            key!("beta", "number", "s", OPT, range ">= 0", "Rayleigh stiffness factor (on the CB matrices)"),
            key!("modal_ratio", "number", "", OPT, range "[0, 1]", "damping ratio of every fixed-interface mode (0.02 for 2 %; a warning from 0.2)"),
        ],
    ),
    Table::plain(
        "rigid_bodies",
        "[[rigid_bodies]]",
        &[
            key!("name", "string", "", REQ, "unique among flexible and rigid bodies"),
            key!("mass", "number", "kg", REQ, range "> 0", "the mass"),
            key!("center_of_mass", VEC3, "m", REQ, "the centre of mass at t = 0"),
            key!("inertia", "3x3 numbers", "kg m²", REQ, "about the centre of mass in global axes at t = 0; symmetric, principal moments non-negative and obeying the triangle inequality"),
            key!("points", "{ name = [x, y, z] }", "m", def("none"), "the body's named points (its nodes), `{ A = [x, y, z], ... }`"),
        ],
    ),
    Table::plain(
        "point_masses",
        "[[point_masses]]",
        &[
            key!("name", "string", "", REQ, "unique among the point masses"),
            key!("at", "string", "", REQ, r#"the point, `"body.point"`"#),
            key!("mass", "number", "kg", REQ, range "> 0", "translational inertia only"),
        ],
    ),
    Table::plain(
        "springs",
        "[[springs]]",
        &[
            key!("name", "string", "", REQ, "unique among the springs"),
            key!("between", "[string, string]", "", REQ, r#"two points, `["a.P", "b.Q"]`, or `["a.P", "ground"]` with `ground_point`"#),
            key!("ground_point", VEC3, "m", OPT, r#"where a spring to `"ground"` is attached"#),
            key!("stiffness", "number", "N/m", REQ, range ">= 0", "the stiffness"),
            key!("damping", "number", "N s/m", def("0"), range ">= 0", "the damping"),
            key!("rest_length", "number", "m", def("the initial length"), range ">= 0", "unstretched length"),
        ],
    ),
    Table::plain(
        "supports",
        "[[supports]]",
        &[
            key!("at", "string", "", REQ, r#"the point held, `"body.point"`"#),
            key!("type", "string", "", REQ, range "`clamp`, `pin`, `hinge`, `slider`, `plane`, `planar`", "`clamp` (all six dofs), `pin` (translations), `hinge` (translations, and rotations but about `axis`), `slider` (translation along `axis` only, rotation held), `plane` (translations in the plane of normal `axis`, rotation held), `planar` (translations in the plane of normal `axis` and the rotation about it: a point of a planar mechanism that nothing else holds in its plane)"),
            key!("axis", VEC3, "", OPT, "the axis of a `hinge` or `slider`, the normal of a `plane` or `planar` support"),
        ],
    ),
    Table::plain(
        "joints",
        "[[joints]]",
        &[
            key!("name", "string", "", REQ, "unique among the joints"),
            key!("type", "string", "", REQ, range "`fixed`, `spherical`, `revolute`, `prismatic`, `cylindrical`, `universal`, `planar`", "`fixed`: the two points become one (they must coincide; with `ground`, a clamp)"),
            key!("between", "[string, string]", "", REQ, r#"`[parent, child]`: points, or `"ground"` first (a ground node is created at the child)"#),
            key!("axis", VEC3, "", OPT, "revolute, prismatic, cylindrical; the normal of a planar joint; the first axis of a universal joint"),
            key!("axis2", VEC3, "", OPT, "the second axis of a universal joint (not parallel to `axis`)"),
        ],
    ),
    Table::plain(
        "drivers",
        "[[drivers]]",
        &[
            key!("name", "string", "", REQ, "unique among the drivers"),
            key!("joint", "string", "", REQ, "the driven joint"),
            key!("coordinate", "integer", "", def("0"), "which scalar coordinate of the joint (removed from the unknowns)"),
            key!("function", "table", "", REQ, "a function of time, below; value, rate and acceleration are fed in"),
        ],
    ),
    Table {
        path: "function",
        header: "function = { ... }",
        kinds_from: "`type`",
        kinds: &["constant-speed", "ramp", "spin-up", "harmonic", "table"],
        keys: &[
            key!("type", "string", "", REQ, range "`constant-speed`, `ramp`, `spin-up`, `harmonic`, `table`", "the function"),
            key!("speed", "number", "", REQ, kinds ["constant-speed", "spin-up"], "the rate [rad/s or m/s]: ω_s of a `spin-up`"),
            key!("initial", "number", "", def("0"), kinds ["constant-speed"], "the value at t = 0"),
            key!("ramp_time", "number", "s", REQ, kinds ["spin-up"], range "> 0", "T_s: the spin-up angle of benchmark C1, ω_s (t²/2 + (T_s/2π)²(cos 2πt/T_s − 1))/T_s, then ω_s(t − T_s/2)"),
            key!("t_start", "number", "s", def("0"), kinds ["ramp"], "when the ramp starts"),
            key!("t_end", "number", "s", REQ, kinds ["ramp"], "when the ramp ends (after `t_start`)"),
            key!("from", "number", "", def("0"), kinds ["ramp"], "the value before `t_start`"),
            key!("to", "number", "", REQ, kinds ["ramp"], "the value after `t_end`"),
            key!("smooth", "bool", "", def("`true`"), kinds ["ramp"], "`true`: the quintic 10s³ − 15s⁴ + 6s⁵, zero rate and acceleration at both ends; `false`: linear"),
            key!("amplitude", "number", "", REQ, kinds ["harmonic"], "offset + amplitude sin(2πft + φ)"),
            key!("frequency_hz", "number", "Hz", REQ, kinds ["harmonic"], "f"),
            key!("phase_deg", "number", "°", def("0"), kinds ["harmonic"], "φ"),
            key!("offset", "number", "", def("0"), kinds ["harmonic"], "the mean value"),
            key!("t", "list of numbers", "s", OPT, kinds ["table"], "the times of the table (increasing); give `t` and `value`, or `file`"),
            key!("value", "list of numbers", "", OPT, kinds ["table"], "the values at the times `t`; constant outside the table"),
            key!("file", "string", "", OPT, kinds ["table"], "or a CSV file of `time, value` rows, relative to the study file; `#` comments and a header line are skipped"),
            key!("interpolation", "string", "", def("`cubic` (drivers), `linear` (loads)"), kinds ["table"], range "`linear`, `cubic`", r#"`"cubic"`: continuous rate and acceleration; `"linear"`"#),
        ],
    },
    Table {
        path: "loads",
        header: "[[loads]]",
        kinds_from: "`type`",
        kinds: &["gravity", "point"],
        keys: &[
            key!("name", "string", "", REQ, "unique among the loads; names the load in messages and in `summary.json`"),
            key!("type", "string", "", REQ, range "`gravity`, `point`", "the load"),
            key!("g", VEC3, "m/s²", REQ, kinds ["gravity"], "the gravitational acceleration (one gravity load at most)"),
            key!("at", "string", "", REQ, kinds ["point"], "the point loaded: a point, or a load point of a flexible body (below)"),
            key!("force", VEC3, "N", OPT, kinds ["point"], "the force; give `force` and/or `moment`"),
            key!("moment", VEC3, "N m", OPT, kinds ["point"], "the moment"),
            key!("axes", "string", "", def(r#"`"global"`"#), kinds ["point"], range r#"`"global"`, `"body"`"#, r#"`"global"`: a dead load; `"body"`: a follower load, the vector given at t = 0 turns with the point"#),
            key!("function", "table", "", def("1"), kinds ["point"], "a factor in time (a function of time, as for `[[drivers]]`)"),
        ],
    },
    Table {
        path: "sensors",
        header: "[[sensors]]",
        kinds_from: "`type`",
        kinds: &SENSOR_KINDS,
        keys: &[
            key!("name", "string", "", REQ, "unique among the sensors: the results are `<name>.csv` and `<name>.png`, so the name may contain ASCII letters, digits, `-`, `_` and `.`"),
            key!("type", "string", "", REQ, "what is measured (below)"),
            key!("of", "string", "", REQ, kinds MEASURED_SENSORS, "the point, body, joint, driver or actuator measured"),
            key!("chord", "[string, string]", "", REQ, kinds ["deflection"], r#"`["a.P", "a.Q"]`: the deflection is the distance of `of` from the line through these points"#),
            key!("normal", VEC3, "", OPT, kinds ["deflection"], "signs the deflection: (chord direction × (p − a)) · normal"),
            key!("reference", "string", "", REQ, kinds ["relative-position"], "the point in whose axes the position of `of` is measured"),
            key!("coordinate", "integer", "", def("0"), kinds ["joint", "joint-rate"], "which scalar coordinate of the joint"),
            key!("node", "integer", "", OPT, kinds ["stress"], "a mesh node by index, 0-based, as in the VTU files and the hot spot's `node`; give `node`, `label`, `node_at` or `set`, one of them"),
            key!("label", "integer", "", OPT, kinds ["stress"], "or the mesh node by its number in the part's mesh file (the deck's or gmsh's node number, the hot spot's `node_label`; generated meshes: the 1-based position)"),
            key!("node_at", VEC3, "m", OPT, kinds ["stress"], "or the mesh node at this position in part axes"),
            key!("set", "string", "", OPT, kinds ["stress"], "or a node set of the part's mesh"),
            key!("axes", "string", "", def(r#"`"global"`"#), kinds ["acceleration", "angular-acceleration"], range r#"`"global"`, `"body"`"#, r#"`"global"`: inertial axes; `"body"`: the axes of the point, turning with it (what an accelerometer fixed there reads)"#),
        ],
    },
    Table {
        path: "initial",
        header: "[[initial]]",
        kinds_from: "which of `joint`, `at`, `body`, `start` is given",
        kinds: &["joint", "point", "body", "start"],
        keys: &[
            key!("joint", "string", "", OPT, kinds ["joint"], "a joint whose coordinate gets an initial value and/or rate"),
            key!("coordinate", "integer", "", def("0"), kinds ["joint"], "which scalar coordinate of the joint"),
            key!("value", "number", "", OPT, kinds ["joint"], "the coordinate's initial value, in the coordinate's units: [rad] for an angle (revolute θ, cylindrical θ, universal θ1 and θ2, planar θ) or [m] for a length (prismatic s, cylindrical s, planar s1 and s2); its `rate` in [rad/s] or [m/s]"),
            key!("value_deg", "number", "°", OPT, kinds ["joint"], "or the value of an angle in degrees"),
            key!("rate", "number", "", OPT, kinds ["joint"], "the coordinate's initial rate [rad/s] or [m/s]"),
            key!("at", "string", "", OPT, kinds ["point"], "a point whose motion no joint gives: at a supported point only the free components can move (a component that is not zero along a direction the support holds is refused)"),
            key!("body", "string", "", OPT, kinds ["body"], "a body: its rigid velocity, v(x) = velocity + angular_velocity × (x − point) in global axes"),
            key!("velocity", VEC3, "m/s", def("`[0, 0, 0]`"), kinds ["point", "body"], "the velocity in global axes (of the point, or of the body at `point`)"),
            key!("angular_velocity", VEC3, "rad/s", def("`[0, 0, 0]`"), kinds ["point", "body"], "the spatial angular velocity (global axes)"),
            key!("point", VEC3, "m", def("the body's centre of mass at t = 0"), kinds ["body"], "the point about which a body's velocity is given"),
            key!("start", "string", "", def(r#"`"consistent"`"#), kinds ["start"], range r#"`"consistent"`, `"at-rest"`"#, r#"how the mechanism starts (an entry of its own): `"consistent"`, the closed loops assembled at the drivers' and initial values and every rate solved from the drivers' and initial rates; `"at-rest"`, the same configuration with every coordinate's rate zero (a driver with a rate at t = 0 then starts with an impact)"#),
        ],
    },
    Table::plain(
        "joint_springs",
        "[[joint_springs]]",
        &[
            key!("name", "string", "", REQ, "unique among the joint springs"),
            key!("joint", "string", "", REQ, "the joint"),
            key!("coordinate", "integer", "", def("0"), "which scalar coordinate of the joint"),
            key!("stiffness", "number", "", def("0"), range ">= 0", "[N/m or N m/rad]: the generalised force on the coordinate x is −(preload + stiffness (x − rest) + damping ẋ), a linear spring on a length and a torsional one on an angle"),
            key!("damping", "number", "", def("0"), range ">= 0", "[N s/m or N m s/rad]"),
            key!("rest", "number", "", def("0"), "[m or rad]"),
            key!("preload", "number", "", def("0"), "[N or N m]"),
        ],
    ),
    Table::plain(
        "joint_limits",
        "[[joint_limits]]",
        &[
            key!("name", "string", "", REQ, "unique among the joint limits"),
            key!("joint", "string", "", REQ, "the joint"),
            key!("coordinate", "integer", "", def("0"), "which scalar coordinate of the joint"),
            key!("lower", "number", "", OPT, "[m or rad]: the lower bound; give `lower` and/or `upper`"),
            key!("upper", "number", "", OPT, "[m or rad]: the upper bound"),
            key!("stiffness", "number", "", REQ, range "> 0", "[N/m or N m/rad]: a stop as a stiff one-sided spring-damper, acting only beyond a bound and only pushing back (it does not stick)"),
            key!("damping", "number", "", def("0"), range ">= 0", "[N s/m or N m s/rad]"),
        ],
    ),
    Table::plain(
        "actuators",
        "[[actuators]]",
        &[
            key!("name", "string", "", REQ, "unique among the actuators"),
            key!("joint", "string", "", REQ, "the joint"),
            key!("coordinate", "integer", "", def("0"), "which scalar coordinate of the joint (one no driver drives)"),
            key!("function", "table", "", OPT, "the effort [N or N m] as a function of time (the functions of `[[drivers]]`); give `function` or `pid`, one of them"),
            key!("pid", "table", "", OPT, "or a PID law `{ kp, ki, kd, setpoint, sensor, max_effort }` (below)"),
        ],
    ),
    Table::plain(
        "actuators.pid",
        "pid = { ... }",
        &[
            key!("kp", "number", "", def("0"), range ">= 0", "proportional gain [N/m on a length, N m/rad on an angle]"),
            key!("ki", "number", "", def("0"), range ">= 0", "integral gain [N/(m s), N m/(rad s)]"),
            key!("kd", "number", "", def("0"), range ">= 0", "derivative gain [N s/m, N m s/rad]"),
            key!("setpoint", "table", "", REQ, "r(t), a function of time in the measured coordinate's unit"),
            key!("sensor", "string", "", def("the actuated coordinate"), "a `joint` sensor whose coordinate y is measured"),
            key!("max_effort", "number", "", OPT, range "> 0", "[N or N m]: saturates |u|"),
        ],
    ),
    Table::plain(
        "output",
        "[output]",
        &[
            key!("every", "integer", "", def("1"), range ">= 1", "write the sensors every n-th step"),
            key!("vtu_every", "integer", "", def("never"), range ">= 1", "write the deformed meshes every n-th step (for dynamic analyses)"),
            key!("plots", "bool", "", def("`true`"), "a PNG per sensor"),
        ],
    ),
];
