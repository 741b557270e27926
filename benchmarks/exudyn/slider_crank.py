"""Exudyn side of the slider-crank comparison (validation problem C2).

Builds the planar flexible slider-crank with Exudyn's ObjectFFRFreducedOrder: the rod's
Hurty-Craig-Bampton modes (RBE2 interfaces on the two end faces, `--modes` fixed-interface
modes) are computed by Exudyn's FEMinterface from the SAME mesh and assembled K, M that
flexmbs uses (written by `cargo run --release -p flexmbs-benchmarks --bin export_rod -- --out
DIR`); the crank is a rigid body driven at 150 rad/s, the slider a rigid body on the x axis,
pins are generic joints free about z; no gravity. Integrated with Exudyn's generalized-alpha
(index 3, spectral radius `--rho-inf`) at the fixed step `--h` to `--t-end`.

Prints the wall time per step, the steps per second and the midpoint deflection relative to
the chord: the mid-length axis node of the mesh against the line through the end-face centre
nodes, the same mesh nodes flexmbs measures. `--csv` writes `t,w,slider_x`; `--reference`
compares with a CSV written by the flexmbs `slider_crank` binary.

Usage (run.sh makes the virtual environment):
    .venv/bin/python slider_crank.py --mesh DIR [--h H] [--t-end T] [--modes 4] [--rho-inf 0.9]
        [--csv out.csv] [--reference ref.csv] [--modified-newton]
"""

import argparse
import math
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse

import exudyn as exu
from exudyn.FEM import FEMinterface, HCBstaticModeSelection, ObjectFFRFreducedOrderInterface
from exudyn.itemInterface import (
    GenericJoint,
    CoordinateConstraint,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    MarkerSuperElementRigid,
    NodePointGround,
    NodeRigidBodyRxyz,
    ObjectGround,
    ObjectRigidBody,
    SensorNode,
    SensorSuperElement,
)


def read_mesh(folder):
    """Nodes, K and M permuted to Exudyn's ordering (3 * node + direction), node sets, params."""
    nodes = np.loadtxt(f"{folder}/nodes.txt").reshape(-1, 3)
    dofs = np.loadtxt(f"{folder}/dofs.txt", dtype=int).reshape(-1, 2)
    if np.any(dofs[:, 1] > 2) or len(dofs) != 3 * len(nodes):
        sys.exit(f"{folder}/dofs.txt: expected 3 translational dofs per node, got {len(dofs)} for {len(nodes)} nodes")
    index = 3 * dofs[:, 0] + dofs[:, 1]  # our free dof -> Exudyn coordinate

    def permuted(name):
        A = scipy.sparse.coo_matrix(scipy.io.mmread(f"{folder}/{name}"))
        return scipy.sparse.csr_matrix((A.data, (index[A.row], index[A.col])), shape=A.shape)

    sets = {}
    for line in open(f"{folder}/sets.txt"):
        words = line.split()
        sets[words[0]] = [int(w) for w in words[1:]]
    params = {}
    for line in open(f"{folder}/params.txt"):
        k, v = line.split()
        params[k] = float(v)
    return nodes, permuted("K.mtx"), permuted("M.mtx"), sets, params


def chord_distance(p, a, b):
    """Signed distance of p from the line a-b, positive along e_z x (b - a) (as flexmbs)."""
    t = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    return np.cross(t, p - a)[:, 2]


def report_run(args, t, w, slider, peak, wall, cpu, steps, it):
    """The lines both Exudyn runs print after their time loop (Newton counts, time per step,
    the midpoint deflection and the RESULT lines the comparison scripts parse), the history
    written to --csv and the error against --reference."""
    print(f"Newton iterations per step {it.newtonStepsCount / steps:.2f}, Jacobians per step {it.newtonJacobiCount / steps:.2f}")
    print(f"wall {wall:.4f} s; per step {wall / steps * 1e6:.3f} us; {steps / wall:.0f} steps/s; CPU {cpu:.2f} s = {cpu / steps * 1e6:.3f} us/step")
    print(f"midpoint deflection: peak |w| = {peak:.6e} m, w(t_end) = {w[-1]:.6e} m")
    print(f"RESULT s_per_step={wall / steps:.6e} cpu_per_step={cpu / steps:.6e} peak_w={peak:.9e}")
    if args.csv:
        np.savetxt(args.csv, np.column_stack([t, w, slider[:, 1]]), delimiter=",", header="t,w,slider_x", comments="", fmt="%.9e")
    if args.reference:
        ref = np.loadtxt(args.reference, delimiter=",", skiprows=1)
        ref_w = np.interp(t, ref[:, 0], ref[:, 1])
        ref_peak = np.max(np.abs(ref[:, 1]))
        err = np.max(np.abs(w - ref_w)) / ref_peak
        print(f"against {args.reference}: max |w - w_ref| / max |w_ref| = {err:.3e}, peak error {(peak - ref_peak) / ref_peak:.3e}")
        print(f"RESULT history_error={err:.6e} peak_error={(peak - ref_peak) / ref_peak:.6e}")


def simulation_settings(steps, h, args):
    """Exudyn's generalized-alpha (index 3, spectral radius --rho-inf, full Newton unless
    --modified-newton) for `steps` steps of `h`, silent, sensors stored at every step and no
    solution file: the settings both Exudyn runs share."""
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = steps
    ss.timeIntegration.endTime = steps * h
    ss.timeIntegration.generalizedAlpha.spectralRadius = args.rho_inf
    ss.timeIntegration.generalizedAlpha.useIndex2Constraints = False
    ss.timeIntegration.generalizedAlpha.useNewmark = False
    ss.timeIntegration.newton.useModifiedNewton = args.modified_newton
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    return ss


def solve_timed(mbs, ss):
    """SolveDynamic with the generalized-alpha solver: whether it succeeded, its wall and CPU time."""
    start, cpu_start = time.perf_counter(), time.process_time()
    ok = mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    wall = time.perf_counter() - start
    cpu = time.process_time() - cpu_start
    return ok, wall, cpu


def add_crank(mbs, ground, m_ground_coordinate, p):
    """The spatial crank: a rigid body of length p["crank"] pinned at O by a GenericJoint and
    driven at p["speed"]. Returns its rigid marker at A (for the rod's pin)."""
    crank, speed = p["crank"], p["speed"]
    # Crank: rigid, node at O, centre of mass at r/2; inertia about the node (Exudyn's convention).
    m_c = p["crank_mass"]
    arm = crank / 2
    n_crank = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[0] * 6, initialVelocities=[0, 0, 0, 0, 0, speed]))
    o_crank = mbs.AddObject(
        ObjectRigidBody(
            nodeNumber=n_crank,
            mass=m_c,
            inertia=[p["crank_Ixx"], p["crank_Iyy"] + m_c * arm**2, p["crank_Izz"] + m_c * arm**2, 0, 0, 0],
            centerOfMass=[arm, 0, 0],
        )
    )
    m_o = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    m_crank_o = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_crank, localPosition=[0, 0, 0]))
    m_crank_a = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_crank, localPosition=[crank, 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[m_o, m_crank_o], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    # Constant crank speed: the z rotation (Tait-Bryan xyz, x and y held at zero) has rate Omega.
    m_crank_angle = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_crank, coordinate=5))
    mbs.AddObject(
        CoordinateConstraint(markerNumbers=[m_ground_coordinate, m_crank_angle], offset=speed, velocityLevel=True)
    )
    return m_crank_a


def add_slider(mbs, ground, p, slider_mass):
    """The spatial slider: a rigid body of `slider_mass` on the x axis at crank + rod, rotation
    held, by a GenericJoint. Returns its node and its rigid marker (for the rod's pin)."""
    crank, rod = p["crank"], p["rod"]
    # Slider: mass m_rod / 2 on the x axis, rotation held.
    n_slider = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[crank + rod, 0, 0, 0, 0, 0]))
    o_slider = mbs.AddObject(
        ObjectRigidBody(nodeNumber=n_slider, mass=slider_mass, inertia=[1e-8, 1e-8, 1e-8, 0, 0, 0])
    )
    m_guide = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[crank + rod, 0, 0]))
    m_slider = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_slider, localPosition=[0, 0, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[m_guide, m_slider], constrainedAxes=[0, 1, 1, 1, 1, 1]))
    return n_slider, m_slider


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", required=True, help="folder written by export_rod")
    ap.add_argument("--h", type=float, default=None, help="time step (default T/400)")
    ap.add_argument("--t-end", type=float, default=None, help="end time (default 2T)")
    ap.add_argument("--modes", type=int, default=4)
    ap.add_argument("--rho-inf", type=float, default=0.9)
    ap.add_argument("--csv")
    ap.add_argument("--reference")
    # Exudyn's time integration defaults to modified Newton; this script runs full Newton unless asked.
    ap.add_argument("--modified-newton", action="store_true", help="Exudyn's modified Newton (Jacobian kept; Exudyn's own default)")
    args = ap.parse_args()

    nodes, K, M, sets, p = read_mesh(args.mesh)
    crank, rod, speed = p["crank"], p["rod"], p["speed"]
    period = 2 * math.pi / speed
    h = args.h if args.h is not None else period / 400
    t_end = args.t_end if args.t_end is not None else 2 * period
    steps = int(round(t_end / h))

    t0 = time.perf_counter()
    fem = FEMinterface()
    fem.nodes = {"Position": nodes}
    fem.stiffnessMatrix = K
    fem.massMatrix = M
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=[sets["x0"], sets["x1"]],
        nEigenModes=args.modes,
        useSparseSolver=True,
        computationMode=HCBstaticModeSelection.RBE2,
    )
    cms = ObjectFFRFreducedOrderInterface(fem)
    t_reduce = time.perf_counter() - t0
    rod_mass = cms.totalMass

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    w_rod = -speed * crank / rod  # rigid mechanism at the dead centre
    # The reference frame sits at the mesh origin, the centre of face x0 (pin A); Exudyn's
    # RBE2 HCB basis drops that face's six static modes, so the frame is fixed to face A.
    ffrf = cms.AddObjectFFRFreducedOrder(
        mbs,
        positionRef=[crank, 0, 0],
        initialVelocity=[0, crank * speed, 0],
        initialAngularVelocity=[0, 0, w_rod],
    )
    o_rod = ffrf["oFFRFreducedOrder"]

    ground = mbs.AddObject(ObjectGround())
    ground_node = mbs.AddNode(NodePointGround())
    m_ground_coordinate = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))

    m_crank_a = add_crank(mbs, ground, m_ground_coordinate, p)
    n_slider, m_slider = add_slider(mbs, ground, p, rod_mass / 2)

    # Pins at the end faces: rigid markers on the face nodes (the faces are rigid in the RBE2 basis).
    def face_marker(face):
        ids = sets[face]
        return mbs.AddMarker(
            MarkerSuperElementRigid(bodyNumber=o_rod, meshNodeNumbers=ids, weightingFactors=[1 / len(ids)] * len(ids))
        )

    m_rod_a, m_rod_b = face_marker("x0"), face_marker("x1")
    mbs.AddObject(GenericJoint(markerNumbers=[m_crank_a, m_rod_a], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    mbs.AddObject(GenericJoint(markerNumbers=[m_slider, m_rod_b], constrainedAxes=[1, 1, 1, 1, 1, 0]))

    sensors = [
        mbs.AddSensor(
            SensorSuperElement(
                bodyNumber=o_rod,
                meshNodeNumber=k,
                outputVariableType=exu.OutputVariableType.Position,
                storeInternal=True,
                writeToFile=False,
            )
        )
        for k in sets["axis"]
    ]
    s_slider = mbs.AddSensor(
        SensorNode(nodeNumber=n_slider, outputVariableType=exu.OutputVariableType.Position, storeInternal=True, writeToFile=False)
    )
    mbs.Assemble()

    ss = simulation_settings(steps, h, args)
    ss.show.statistics = False
    ss.show.computationTime = False

    ok, wall, cpu = solve_timed(mbs, ss)
    if not ok:
        sys.exit("Exudyn: the dynamic solve failed")

    a, mid, b = (mbs.GetSensorStoredData(s) for s in sensors)
    slider = mbs.GetSensorStoredData(s_slider)
    t = a[:, 0]
    w = chord_distance(mid[:, 1:4], a[:, 1:4], b[:, 1:4])
    peak = np.max(np.abs(w))
    print(
        f"Exudyn {exu.config.Version()} slider-crank: rod {len(nodes)} nodes, {K.shape[0]} dofs, "
        f"{cms.nModes} HCB coordinates ({args.modes} eigenmodes), mass {rod_mass:.6e} kg, reduction {t_reduce:.2f} s"
    )
    print(
        f"h = {h:.6e} s, {steps} steps to t = {steps * h:.6f} s, rho_inf = {args.rho_inf}, "
        f"modified Newton {args.modified_newton}"
    )
    it = mbs.sys["dynamicSolver"].it
    report_run(args, t, w, slider, peak, wall, cpu, steps, it)

if __name__ == "__main__":
    main()
