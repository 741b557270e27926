"""Exudyn's finite-element rods for the slider-crank (validation problem C2).

The C2 connecting rod (round steel rod, d = 6 mm, l = 0.30 m, E = 200 GPa, rho = 7870 kg/m^3,
Euler-Bernoulli) as Exudyn's own beam elements instead of a reduced body:

* `--model ancf`: `ObjectANCFCable2D`, the planar ANCF cable (Euler-Bernoulli with axial
  strain; nodes `NodePoint2DSlope1`), crank `ObjectRigidBody2D`, slider `ObjectMassPoint2D`,
  pins `RevoluteJoint2D`: the planar model a user of Exudyn builds for this rod.
* `--model beam3d`: `ObjectBeamGeometricallyExact`, the 3D geometrically exact (shear
  deformable) beam on `NodeRigidBodyRxyz` nodes, crank and slider 3D rigid bodies and
  `GenericJoint`s as in slider_crank.py. Its section: EA, GJ, EI of the rod and rotary
  inertia rho (2I, I, I); the shear stiffness is `--shear-factor` times k G A (Cowper's k = 0.89;
  default 1, the physical rod: shear adds about 0.07 % to its bending flexibility, which the
  Euler-Bernoulli C2 rod lacks; a stiffer shear would remove that, but at 100 k G A Exudyn's
  Newton iteration does not converge at any step tried).

`--section square` replaces the round section by the square one of the solid rod of
run_comparison.sh (side `side` of params.txt, the round rod's I, 2 % less area and mass): the
converged ANCF run with it is that comparison's reference.

Mechanism (as slider_crank.py): rigid crank r = 0.15 m driven at 150 rad/s (velocity-level
coordinate constraint), slider of half the rod's mass on the x axis, start at the dead centre
with the rigid mechanism's velocities, no gravity; the values are read from `params.txt`
written by `export_rod --out DIR`. Integrated with Exudyn's generalized-alpha (index 3,
spectral radius `--rho-inf`) at the fixed step `--h` to `--t-end`, full Newton unless
`--modified-newton` (Exudyn's own default for time integration is modified Newton:
`timeIntegration.newton.useModifiedNewton` is on, the Jacobian kept across steps and rebuilt
when the contraction is worse than `modifiedNewtonContractivity` = 0.5).

Output as slider_crank.py: the midpoint deflection w from the chord (the middle node against
the line through the end nodes, positive along e_z x (B - A); `--elements` must be even), the
wall and CPU time of `SolveDynamic` per step, `RESULT` lines, `--csv` (t, w, slider_x) and
`--reference` (a CSV of the same columns).

Usage (run.sh makes the virtual environment):
    run.sh slider_crank_beam.py --params DIR/params.txt --model ancf|beam3d [--elements 4]
        [--section round|square] [--h H] [--t-end T] [--rho-inf 0.9] [--modified-newton] [--sparse] [--csv out.csv]
        [--reference ref.csv]
"""

import argparse
import math
import sys

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (
    CoordinateConstraint,
    GenericJoint,
    MarkerBodyPosition,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    MarkerNodeRigid,
    NodePoint2D,
    NodePoint2DSlope1,
    NodePointGround,
    NodeRigidBody2D,
    NodeRigidBodyRxyz,
    ObjectANCFCable2D,
    ObjectBeamGeometricallyExact,
    ObjectGround,
    ObjectJointRevolute2D,
    ObjectMassPoint2D,
    ObjectRigidBody2D,
    SensorNode,
)

from slider_crank import add_crank, add_slider, chord_distance, report_run, simulation_settings, solve_timed


def read_params(path):
    params = {}
    for line in open(path):
        k, v = line.split()
        params[k] = float(v)
    for k in ["crank", "rod", "speed", "diameter", "E", "nu", "rho", "crank_mass", "crank_Izz"]:
        if k not in params:
            sys.exit(f"{path}: no '{k}' (written by export_rod)")
    return params


def section_properties(p):
    """Area, second moment of area, torsion constant and Cowper's shear factor of the rod's
    section: `p["section"]` is "round" (diameter `diameter`, validation problem C2) or "square"
    (side `side`: the solid rod of run_comparison.sh, a hex20 bar with the round rod's I)."""
    nu = p["nu"]
    if p["section"] == "round":
        d = p["diameter"]
        return math.pi * d**2 / 4, math.pi * d**4 / 64, math.pi * d**4 / 32, 6 * (1 + nu) / (7 + 6 * nu)
    a = p["side"]
    # Square: J = 0.1406 a^4 (Saint-Venant, Roark's table 10.1), Cowper's 10 (1 + nu) / (12 + 11 nu).
    return a**2, a**4 / 12, 0.1406 * a**4, 10 * (1 + nu) / (12 + 11 * nu)


def ancf_model(mbs, p, n):
    """Planar model: crank, ANCF cable rod of n elements, slider. Returns the rod nodes and the slider node."""
    r, l, speed = p["crank"], p["rod"], p["speed"]
    A, I, _, _ = section_properties(p)
    rod_mass = p["rho"] * A * l
    w_rod = -speed * r / l  # rigid mechanism at the dead centre: the rod turns about B
    ground = mbs.AddObject(ObjectGround())
    m_ground_coord = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))

    # Crank: node at O, centre of mass at r/2, inertia about O; driven at constant speed.
    m_c = p["crank_mass"]
    n_crank = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0, 0, 0], initialVelocities=[0, 0, speed]))
    o_crank = mbs.AddObject(
        ObjectRigidBody2D(nodeNumber=n_crank, mass=m_c, inertia=p["crank_Izz"] + m_c * (r / 2) ** 2, centerOfMass=[r / 2, 0])
    )
    m_o = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m_o, mbs.AddMarker(MarkerBodyPosition(bodyNumber=o_crank, localPosition=[0, 0, 0]))]))
    m_angle = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_crank, coordinate=2))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground_coord, m_angle], offset=speed, velocityLevel=True))
    m_crank_a = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o_crank, localPosition=[r, 0, 0]))

    # Rod: n cable elements from A = (r, 0) to B = (r + l, 0), rigid velocities about B.
    nodes = []
    for i in range(n + 1):
        x = r + l * i / n
        nodes.append(
            mbs.AddNode(
                NodePoint2DSlope1(
                    referenceCoordinates=[x, 0, 1, 0], initialVelocities=[0, w_rod * (x - r - l), 0, w_rod]
                )
            )
        )
    for i in range(n):
        mbs.AddObject(
            ObjectANCFCable2D(
                nodeNumbers=[nodes[i], nodes[i + 1]],
                length=l / n,
                massPerLength=p["rho"] * A,
                bendingStiffness=p["E"] * I,
                axialStiffness=p["E"] * A,
            )
        )

    # Slider: a mass point of half the rod's mass on the x axis.
    n_slider = mbs.AddNode(NodePoint2D(referenceCoordinates=[r + l, 0]))
    mbs.AddObject(ObjectMassPoint2D(nodeNumber=n_slider, mass=rod_mass / 2))
    m_slider_y = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_slider, coordinate=1))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground_coord, m_slider_y]))
    m_slider = mbs.AddMarker(MarkerNodePosition(nodeNumber=n_slider))

    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m_crank_a, mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m_slider, mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))]))
    return nodes, n_slider, rod_mass


def beam3d_model(mbs, p, n, shear_factor):
    """Spatial model: crank, geometrically exact beam rod of n elements, slider. Returns as ancf_model."""
    r, l, speed = p["crank"], p["rod"], p["speed"]
    E, nu, rho = p["E"], p["nu"], p["rho"]
    A, I, J, k_shear = section_properties(p)
    G = E / (2 * (1 + nu))
    rod_mass = rho * A * l
    w_rod = -speed * r / l
    section = exu.BeamSection()
    GA = shear_factor * k_shear * G * A
    section.stiffnessMatrix = np.diag([E * A, GA, GA, G * J, E * I, E * I])
    section.inertia = rho * np.diag([2 * I, I, I])
    section.massPerLength = rho * A

    ground = mbs.AddObject(ObjectGround())
    m_ground_coord = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    m_crank_a = add_crank(mbs, ground, m_ground_coord, p)

    nodes = []
    for i in range(n + 1):
        x = r + l * i / n
        nodes.append(
            mbs.AddNode(
                NodeRigidBodyRxyz(
                    referenceCoordinates=[x, 0, 0, 0, 0, 0], initialVelocities=[0, w_rod * (x - r - l), 0, 0, 0, w_rod]
                )
            )
        )
    for i in range(n):
        mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=l / n, sectionData=section))

    n_slider, m_slider = add_slider(mbs, ground, p, rod_mass / 2)

    pin = [1, 1, 1, 1, 1, 0]
    mbs.AddObject(GenericJoint(markerNumbers=[m_crank_a, mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))], constrainedAxes=pin))
    mbs.AddObject(GenericJoint(markerNumbers=[m_slider, mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))], constrainedAxes=pin))
    return nodes, n_slider, rod_mass


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--params", required=True, help="params.txt written by export_rod")
    ap.add_argument("--model", choices=["ancf", "beam3d"], required=True)
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--section", choices=["round", "square"], default="round",
                    help="the round rod of C2 (default) or the solid rod's square section (side from params.txt)")
    ap.add_argument("--h", type=float, default=None, help="time step (default T/400)")
    ap.add_argument("--t-end", type=float, default=None, help="end time (default 2T)")
    ap.add_argument("--rho-inf", type=float, default=0.9)
    ap.add_argument("--shear-factor", type=float, default=1.0, help="beam3d: shear stiffness over k G A")
    ap.add_argument("--modified-newton", action="store_true", help="Exudyn's modified Newton (Jacobian kept)")
    ap.add_argument("--sparse", action="store_true", help="Exudyn's sparse linear solver (EigenSparse) instead of its dense default")
    ap.add_argument("--csv")
    ap.add_argument("--reference")
    args = ap.parse_args()
    if args.elements < 2 or args.elements % 2:
        sys.exit(f"--elements {args.elements}: an even number of at least 2 (the midpoint must be a node)")

    p = read_params(args.params)
    if args.section == "square" and "side" not in p:
        sys.exit(f"{args.params}: no 'side' (written by export_rod), needed by --section square")
    p["section"] = args.section
    period = 2 * math.pi / p["speed"]
    h = args.h if args.h is not None else period / 400
    t_end = args.t_end if args.t_end is not None else 2 * period
    steps = int(round(t_end / h))

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    if args.model == "ancf":
        nodes, n_slider, rod_mass = ancf_model(mbs, p, args.elements)
    else:
        nodes, n_slider, rod_mass = beam3d_model(mbs, p, args.elements, args.shear_factor)
    probe = [nodes[0], nodes[len(nodes) // 2], nodes[-1]]
    sensors = [
        mbs.AddSensor(SensorNode(nodeNumber=k, outputVariableType=exu.OutputVariableType.Position, storeInternal=True, writeToFile=False))
        for k in probe + [n_slider]
    ]
    mbs.Assemble()

    ss = simulation_settings(steps, h, args)
    if args.sparse:
        ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse

    ok, wall, cpu = solve_timed(mbs, ss)
    if not ok:
        sys.exit(f"Exudyn: the dynamic solve of the {args.model} rod with {args.elements} elements, h = {h:.4e} s failed")

    a, mid, b, slider = (mbs.GetSensorStoredData(s) for s in sensors)
    t = a[:, 0]
    w = chord_distance(mid[:, 1:4], a[:, 1:4], b[:, 1:4])
    peak = np.max(np.abs(w))
    name = {"ancf": "ObjectANCFCable2D", "beam3d": "ObjectBeamGeometricallyExact"}[args.model]
    it = mbs.sys["dynamicSolver"].it
    print(
        f"Exudyn {exu.config.Version()} slider-crank: rod as {args.elements} x {name}, "
        f"{len(mbs.systemData.GetODE2Coordinates())} ODE2 coordinates, {len(mbs.systemData.GetAECoordinates())} constraint equations, rod mass {rod_mass:.6e} kg"
    )
    print(
        f"h = {h:.6e} s, {steps} steps to t = {steps * h:.6f} s, rho_inf = {args.rho_inf}, modified Newton {args.modified_newton}, "
        f"{'sparse' if args.sparse else 'dense'} linear solver"
    )
    report_run(args, t, w, slider, peak, wall, cpu, steps, it)

if __name__ == "__main__":
    main()
