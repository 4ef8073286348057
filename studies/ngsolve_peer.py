"""NGSolve as a peer of the P2/P1 mixed tissue solve: the same problem on the same mesh.

:func:`solve_mixed` builds, from a scene, what :class:`reference_fem.mixed.MixedProblem`
discretises and lets NGSolve's own Newton (:class:`ngsolve.solvers.NewtonSolver`) solve it:

- the scene's tets and points as a netgen mesh (one volume region; every boundary triangle
  labelled by the first scene region holding it: the pressure's and the boundaries');
- Taylor–Hood ``VectorH1`` order 2 × ``H1`` order 1, the P2 DOFs fixed as ours are (every
  vertex of a boundary region and every edge with both vertices in it);
- the Guccione energy of the full Green strain in each element's frame (``scene.frames`` as
  an L2 piecewise-constant coefficient), ``W = C/2 (e^Q - 1)``,
  ``Q = sum_ab B_ab E'_ab^2``, ``E' = R E R^T``, and the constraint as in
  :mod:`reference_fem.mixed`: ``Pi = int W - p (J - 1) - p^2 / (2 kappa) dX`` (``kappa``
  infinite when incompressible), through ``Variation``;
- the follower pressure as a nonlinear form on the reference surface, Nanson's
  ``J F^-T N = cof(F_s) N`` with the surface gradient ``F_s = I + grad_s u`` (the cofactor
  of ``F`` on a normal needs only the tangential derivatives, which both sides of a face
  share), ``+ lambda p (cof(F_s) N) . v`` in the residual;
- the same quadrature: scikit-fem's points and weights of the degree ``intorder`` tet rule
  and the degree-4 triangle rule (:mod:`reference_fem.loads`) passed to NGSolve as
  ``IntegrationRule`` (both rules are symmetric, so NGSolve's vertex order maps them to the
  same physical points);
- load stepping as our solver's nominal schedule: ``[fem] load_steps`` equal increments of
  the load factor, a Newton solve each, the previous state as the start.

NGSolve is an optional extra (``pip install springfem[ngsolve]``); nothing here imports it
at module level.

Examples
--------
>>> from springfem.scene import load_scene
>>> labels = facet_labels(load_scene("land-beam"))  # 30 x 3 x 3 boxes, 2 triangles a square
>>> labels.names, np.bincount(labels.index).tolist()  # z = 0: 30 x 3 squares; x = 0: 3 x 3
(['z_min', 'x_min', 'rest'], [180, 18, 558])
"""

from __future__ import annotations

import contextlib
import io
import time
from dataclasses import dataclass

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.scene import Scene

#: Degree of the triangle rule of the follower pressure on P2 (:mod:`reference_fem.loads`).
FACET_INTORDER = 4
#: NGSolve's Newton stops when ``sqrt(|du . R|)`` falls below this times its first value
#: in the first load step: a relative energy-norm test, like our ``|R| <= tol |f|``.
NEWTON_RELATIVE = 1e-10


def available() -> str | None:
    """``None`` when NGSolve imports, else why not (one line)."""
    try:
        import ngsolve  # noqa: F401
    except ImportError as exc:
        return f"NGSolve is not installed ({exc}; pip install ngsolve): peer skipped"
    return None


@dataclass
class FacetLabels:
    """Boundary triangles of a mesh with a region label each.

    Attributes
    ----------
    facets
        ``(f, 3)`` outward-oriented boundary triangles.
    index
        ``(f,)`` label number of each (into ``names``).
    names
        Label names: scene regions in order of first use, ``rest`` for the others.
    """

    facets: np.ndarray
    index: np.ndarray
    names: list[str]


def facet_labels(scene: Scene) -> FacetLabels:
    """Label every boundary triangle with the first scene region (loads, then boundaries)
    that holds it, ``rest`` otherwise."""
    mesh = scene.mesh
    bf = np.asarray(mesh.boundary_facets(), dtype=np.int64)
    n = mesh.n_points

    def keys(f: np.ndarray) -> np.ndarray:
        s = np.sort(f, axis=1)
        return (s[:, 0] * n + s[:, 1]) * n + s[:, 2]

    kb = keys(bf)
    index = np.full(len(bf), -1, dtype=np.int64)
    names: list[str] = []
    regions = [ld.region for ld in scene.loads if ld.region is not None]
    regions += [b.region for b in scene.boundaries]
    for region in regions:
        if region.facets.size == 0:
            continue
        hit = np.isin(kb, keys(region.facets)) & (index < 0)
        if not hit.any():
            continue
        if region.name not in names:
            names.append(region.name)
        index[hit] = names.index(region.name)
    if (index < 0).any():
        names.append("rest")
        index[index < 0] = len(names) - 1
    return FacetLabels(bf, index, names)


def ngsolve_mesh(scene: Scene):
    """The scene's mesh as an :class:`ngsolve.Mesh` (same points, same tets, same order).

    Returns
    -------
    mesh, labels
        The NGSolve mesh and the :class:`FacetLabels` of its boundary triangles.
    """
    import ngsolve
    from netgen.meshing import Element2D, Element3D, FaceDescriptor, MeshPoint, Pnt
    from netgen.meshing import Mesh as NetgenMesh

    points = np.asarray(scene.mesh.points, dtype=float)
    tets = np.asarray(scene.mesh.tets, dtype=np.int64)
    labels = facet_labels(scene)
    m = NetgenMesh(dim=3)
    pids = [m.Add(MeshPoint(Pnt(*map(float, x)))) for x in points]
    for k, name in enumerate(labels.names):
        m.Add(FaceDescriptor(surfnr=k + 1, domin=1, domout=0, bc=k + 1))
        m.SetBCName(k, name)
    # netgen's reference tet is (1,0,0), (0,1,0), (0,0,1), (0,0,0): vertex 3 is the origin,
    # so a positively oriented tet (a b c d) is passed as (b c d a)
    for t in tets:
        m.Add(Element3D(1, [pids[t[1]], pids[t[2]], pids[t[3]], pids[t[0]]]))
    # our boundary triangles are outward oriented; netgen's normal is then outward too
    for f, k in zip(labels.facets, labels.index, strict=True):
        m.Add(Element2D(int(k) + 1, [pids[f[0]], pids[f[1]], pids[f[2]]]))
    m.SetMaterial(1, "tissue")
    return ngsolve.Mesh(m), labels


def _rules(intorder: int, facet_intorder: int):
    """scikit-fem's tet and triangle rules as NGSolve ``IntegrationRule`` objects."""
    import ngsolve
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTet, RefTri

    out = {}
    for et, ref, order in ((ngsolve.TET, RefTet, intorder), (ngsolve.TRIG, RefTri, facet_intorder)):
        X, W = get_quadrature(ref, order)
        pts = [tuple(float(c) for c in x) for x in X.T]
        out[et] = ngsolve.IntegrationRule(points=pts, weights=[float(w) for w in W])
    return out


def _fixed_dofs(scene: Scene, mesh, V) -> np.ndarray:
    """DOF numbers of ``V`` (a ``VectorH1``: component ``c`` of scalar DOF ``d`` is
    ``c n + d``) that the scene's boundaries fix, as
    :func:`reference_fem.constraints.dirichlet` fixes P2 nodes."""
    import ngsolve

    nv = scene.mesh.n_points
    edges = np.array([[v.nr for v in e.vertices] for e in mesh.edges], dtype=np.int64)
    scalar = V.components[0]
    n = scalar.ndof
    out = []
    for b in scene.boundaries:
        if np.any(np.asarray(b.value) != 0.0):
            raise InputError("the NGSolve peer supports fixed (zero) displacements only")
        mask = np.zeros(nv, dtype=bool)
        mask[b.region.nodes] = True
        dofs = [int(d) for d in b.region.nodes]  # H1 vertex DOFs are the vertex numbers
        for e in np.flatnonzero(mask[edges].all(axis=1)):
            dofs.extend(int(d) for d in scalar.GetDofNrs(ngsolve.NodeId(ngsolve.EDGE, int(e))))
        for c in b.components:
            out.extend(c * n + d for d in dofs)
    return np.unique(np.array(out, dtype=np.int64))


def _compiled(cf, how: str):
    """``cf`` compiled as asked (``real``, ``tree`` or ``none``, see :func:`solve_mixed`)."""
    if how == "real":
        return cf.Compile(realcompile=True, wait=True)
    if how == "tree":
        return cf.Compile()
    if how == "none":
        return cf
    raise InputError(f"unknown compile mode {how!r}; valid: real, tree, none")


@dataclass
class PeerSolution:
    """An NGSolve solve: probe displacements and what it cost.

    Attributes
    ----------
    probes
        Probe name -> displacement ``[ux, uy, uz]``.
    seconds, setup_seconds
        Wall time of the whole solve (mesh, spaces, forms, Newton) and of the part before
        the first Newton iteration.
    iterations
        Newton iterations over all load steps.
    info
        Quadrature rules, solver, DOFs.
    """

    probes: dict[str, list[float]]
    seconds: float
    setup_seconds: float
    iterations: int
    info: dict


def _guccione(scene: Scene):
    from reference_fem.law_names import parse_law
    from springfem.materials.laws import Guccione

    _, law = parse_law(scene, None)
    if not isinstance(law, Guccione):
        raise InputError(f"the NGSolve peer solves the Guccione law, not {scene.material.law}")
    if law.active_tension:
        raise InputError("the NGSolve peer has no active tension")
    return law


def solve_mixed(
    scene: Scene,
    intorder: int = 2,
    facet_intorder: int = FACET_INTORDER,
    inverse: str = "pardiso",
    load_steps: int | None = None,
    max_iter: int = 25,
    compile: str = "tree",
) -> PeerSolution:
    """Solve the scene's P2/P1 mixed Guccione problem with NGSolve (module docstring).

    Parameters
    ----------
    scene
        A Guccione scene (incompressible, or with a ``kappa``) with pressure loads and
        fixed boundaries.
    intorder, facet_intorder
        Degrees of the tet and triangle rules (ours: 2 and 4).
    inverse
        NGSolve's sparse direct solver of the Newton systems.
    load_steps
        Equal load increments (default: the scene's ``[fem] load_steps``).
    max_iter
        Newton iterations per load step.
    compile
        How NGSolve evaluates the forms: ``real`` (compiled to C++ at run time, needs a C++
        compiler), ``tree`` (its expression tree, ``Compile()`` without a compiler) or
        ``none``.

    Returns
    -------
    PeerSolution

    Raises
    ------
    SolverError
        A load step's Newton did not converge.
    """
    import ngsolve as ng
    from ngsolve.nonlinearsolvers import NewtonSolver

    from reference_fem.options import FemOptions
    from reference_fem.volumetric_split import volumetric_split

    t0 = time.perf_counter()
    law = _guccione(scene)
    kappa = volumetric_split(law).kappa
    steps = int(FemOptions.of(scene).load_steps if load_steps is None else load_steps)
    mesh, labels = ngsolve_mesh(scene)
    rules = _rules(intorder, facet_intorder)
    V = ng.VectorH1(mesh, order=2)
    Q = ng.H1(mesh, order=1)
    X = V * Q
    (u, p), (v, q) = X.TnT()
    frames = ng.L2(mesh, order=0) ** 9
    R_gf = ng.GridFunction(frames)
    R_gf.vec.FV().NumPy()[:] = np.asarray(scene.frames, dtype=float).reshape(-1, 9).T.ravel()
    R = ng.CF(tuple(R_gf.components), dims=(3, 3))
    B = law.B
    F = ng.Id(3) + ng.Grad(u)
    E = 0.5 * (F.trans * F - ng.Id(3))
    Ep = R * E * R.trans
    Qe = sum(float(B[a, b]) * Ep[a, b] ** 2 for a in range(3) for b in range(3))
    W = 0.5 * law.C * (ng.exp(Qe) - 1.0)
    J = ng.Det(F)
    energy = W - p * (J - 1.0)
    if kappa > 0:
        energy = energy - p * p / (2.0 * kappa)
    a = ng.BilinearForm(X, symmetric=False)
    a += ng.Variation(_compiled(energy, compile) * ng.dx(intrules={ng.TET: rules[ng.TET]}))
    lam = ng.Parameter(0.0)
    N = ng.specialcf.normal(3)
    Fs = ng.Id(3) + ng.Grad(u).Trace()  # the surface gradient on boundary triangles
    for load in scene.loads:
        if load.type != "pressure":
            raise InputError(f"the NGSolve peer supports pressure loads only, not {load.type}")
        assert load.region is not None
        value = float(load.value[0])
        ds = ng.ds(load.region.name, intrules={ng.TRIG: rules[ng.TRIG]})
        traction = _compiled(ng.InnerProduct(ng.Cof(Fs) * N, v), compile)
        a += lam * value * traction * ds
    free = X.FreeDofs()
    for d in _fixed_dofs(scene, mesh, V):
        free.Clear(int(d))
    gfu = ng.GridFunction(X)
    gfu.vec[:] = 0.0
    newton = NewtonSolver(a=a, u=gfu, freedofs=free, inverse=inverse)
    setup = time.perf_counter() - t0
    iterations, err0 = 0, None
    first: list[float] = []

    def record(it: int, err: float) -> None:
        first.append(err)

    for k in range(1, steps + 1):
        lam.Set(k / steps)
        if err0 is None:  # the first load step's first error sets the scale of the test
            first.clear()
            with contextlib.redirect_stdout(io.StringIO()):  # its "might not converge"
                status, its = newton.Solve(maxit=1, maxerr=0.0, callback=record)
            err0 = max(first[0], 1e-300)
            iterations += its
        status, its = newton.Solve(maxit=max_iter, maxerr=NEWTON_RELATIVE * err0)
        iterations += its
        if status != 0:
            raise SolverError(
                f"NGSolve Newton did not converge in load step {k}/{steps} "
                f"(load factor {k / steps:g})"
            )
    probes = {
        pr.name: [float(c) for c in gfu.components[0](mesh(*map(float, pr.point)))]
        for pr in scene.probes
    }
    return PeerSolution(
        probes=probes,
        seconds=time.perf_counter() - t0,
        setup_seconds=setup,
        iterations=iterations,
        info={
            "dofs": int(X.ndof),
            "intorder": intorder,
            "facet_intorder": facet_intorder,
            "inverse": inverse,
            "compile": compile,
            "load_steps": steps,
            "regions": labels.names,
            "threads": "1 (no TaskManager)",
        },
    )
