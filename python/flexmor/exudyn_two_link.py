"""The two-link benchmark of ``input/two_link.nml`` built in Exudyn (an independent flexible
multibody code, PyPI ``exudyn``), for side-by-side benchmarks (scripts/bench_scaling.py).

Exudyn is optional: importing this module works without it; :func:`available` says whether it
can be used and :func:`run` raises ImportError when it cannot.

The model: each link is a chain of Exudyn's planar geometrically exact beam elements
(``ObjectBeamGeometricallyExact2D``: axial, shear and bending deformation) between rigid-body
nodes (x, y, phi), with the data of ``input/two_link.nml`` (E = 7.3e10 Pa, rho = 2700 kg/m^3,
link 1: 0.545 m, A = 9e-4 m^2, I = 1.69e-8 m^4; link 2: 0.675 m, A = 4e-4 m^2, I = 3.33e-9
m^4), point masses of 1 kg at the elbow and 3 kg at the tip, no gravity. The base node is
pinned and its rotation prescribed, phi = phi1(t); at the elbow the two links' end nodes share
their position and phi2_start - phi1_end = phi2(t). Both laws are the cubic rest-to-rest quarter
turn in 0.5 s. flexmor keeps the elongation rigid and has no shear; here axial and shear
stiffness are finite (EA and kappa G A with G = E/2.6, kappa = 5/6), which moves the tip by
less than 1e-7 m on this motion (checked against flexmor with elongation dynamic).
Time integration: Exudyn's generalized-alpha with a fixed step h and spectral radius rho_inf.
"""
from __future__ import annotations

import math
import time

E = 7.3e10
RHO = 2700.0
LINKS = ((0.545, 9.0e-4, 1.69e-8), (0.675, 4.0e-4, 3.33e-9))   # length, A, I
MASSES = (1.0, 3.0)   # elbow, tip
DURATION = 0.5
VERBOSE = 0
QUARTER = 0.5 * math.pi


def available() -> bool:
    try:
        import exudyn  # noqa: F401
    except ImportError:
        return False
    return True


def version() -> str:
    import exudyn
    return exudyn.config.Version() if hasattr(exudyn, "config") else exudyn.__version__


def cubic(t: float) -> float:
    """The joint angle of both joints: a quarter turn, 3 s^2 - 2 s^3, held after 0.5 s."""
    s = min(max(t / DURATION, 0.0), 1.0)
    return QUARTER * (3 * s * s - 2 * s ** 3)


def run(n_per_link: int, h: float, t_end: float, rho_inf: float = 0.8,
        output_dt: float = 1.0e-3, sparse: bool = True, newton_rtol: float = 1.0e-6):
    """Simulate; returns dict(time, tip (n, 2), cpu_s, n_steps). cpu_s is the process time of
    the solve alone (model building excluded). sparse: Exudyn's sparse linear solver (Eigen)
    instead of its dense default. newton_rtol: Newton's relative tolerance; Exudyn's default
    1e-8 lies at the round-off of the stiff axial and shear modes from 12 elements per link on
    (Newton then stalls and the step is cut again and again)."""
    import numpy as np
    import exudyn as exu
    from exudyn.itemInterface import (NodeRigidBody2D, ObjectBeamGeometricallyExact2D,
                                      ObjectGround, MarkerNodeCoordinate,
                                      ObjectConnectorCoordinate, ObjectRigidBody2D,
                                      SensorNode)

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    ground_node = mbs.AddNode(exu.itemInterface.NodePointGround())
    ground_marker = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))

    def angle_offset(mbs_, t, item, l_offset):
        return cubic(t)

    x0 = 0.0
    link_nodes = []
    for length, area, inertia in LINKS:
        le = length / n_per_link
        nodes = [mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x0 + i * le, 0, 0]))
                 for i in range(n_per_link + 1)]
        for i in range(n_per_link):
            mbs.AddObject(ObjectBeamGeometricallyExact2D(
                nodeNumbers=[nodes[i], nodes[i + 1]], physicsLength=le,
                physicsMassPerLength=RHO * area, physicsCrossSectionInertia=RHO * inertia,
                physicsBendingStiffness=E * inertia, physicsAxialStiffness=E * area,
                physicsShearStiffness=5.0 / 6.0 * E / 2.6 * area))
        link_nodes.append(nodes)
        x0 += length

    def coord(node, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=k))

    base = link_nodes[0][0]
    for k in (0, 1):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground_marker, coord(base, k)]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground_marker, coord(base, 2)],
                                            offsetUserFunction=angle_offset))
    end1, start2 = link_nodes[0][-1], link_nodes[1][0]
    for k in (0, 1):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[coord(end1, k),
                                                               coord(start2, k)]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[coord(end1, 2), coord(start2, 2)],
                                            offsetUserFunction=angle_offset))
    for node, mass in zip((end1, link_nodes[1][-1]), MASSES):
        mbs.AddObject(ObjectRigidBody2D(physicsMass=mass, physicsInertia=0.0, nodeNumber=node))
    tip_sensor = mbs.AddSensor(SensorNode(nodeNumber=link_nodes[1][-1], storeInternal=True,
                                          writeToFile=False,
                                          outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()

    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.numberOfSteps = int(round(t_end / h))
    settings.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    settings.timeIntegration.newton.relativeTolerance = newton_rtol
    settings.timeIntegration.verboseMode = VERBOSE
    settings.solutionSettings.writeSolutionToFile = False
    settings.solutionSettings.sensorsWritePeriod = min(output_dt, h)
    settings.displayStatistics = False
    if sparse:
        settings.linearSolverType = exu.LinearSolverType.EigenSparse
    settings.displayComputationTime = False
    start = time.process_time()
    mbs.SolveDynamic(settings)
    cpu = time.process_time() - start
    data = np.array(mbs.GetSensorStoredData(tip_sensor))
    return {"time": data[:, 0], "tip": data[:, 1:3], "cpu_s": cpu,
            "n_steps": settings.timeIntegration.numberOfSteps}
