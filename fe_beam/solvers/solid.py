"""The 3D hyperelastic finger: set-up, load-stepped solve and post-processing.

Total potential (load factor lambda in [0, 1]):

    Pi(u) = int_Omega W(F) dX + sum_i tau_i l_i(u) - lambda int_tip t0 . u dA,   F = I + grad u,

with the clamp u = 0 on x = 0, the dead tip traction t0 = tip_force / |tip face| and cable
energies tau_i l_i (`fe_beam.fem.solid.cable`): tau_i = lambda T_i under tension control, or the
unknown multiplier of l_i^0 - l_i = lambda * pull_in_i under pull-in control. The mixed u-p
formulation (Taylor-Hood P2-P1) replaces U(J) by p (J - 1) - p^2 / (2 kappa).

Post-processing (all collective, MPI-reduced, identical on every rank):

- tip displacement: area average of u over the tip face, (1/A) int_tip u dA;
- tip rotation: the best-fit (Kabsch) rotation R of the tip face, from the SVD of
  H = int_tip (X - Xc) (x - xc)^T dA = U S V^T, R = V diag(1, 1, det(V U^T)) U^T; the in-plane
  angle is atan2(R_yx, R_xx). The area-averaged deformed normal (Nanson, int_tip J F^-T N dA,
  normalised) is reported alongside;
- backbone: deformed area centroids of the cross-sections X = x_i, by Gauss-Legendre quadrature
  (n x n points) of X + u(X) over each reference section;
- largest principal stretch: max over cells of sqrt(max eig C) at the P2 nodes of each cell;
  the "bulk" value leaves out the clamp edges and one section height around each loaded tendon
  end (the tip face's slab for an end on it), where the idealised model's strains are
  singular (`bulk_mask`).

Nothing here writes files (see `fe_beam.exports.solid`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar, global_max, global_sum
from fe_beam.fem.solid.cable import TendonCable
from fe_beam.fem.solid.contact import SolidContact
from fe_beam.fem.solid.geometry import CLAMP_TAG, TIP_TAG, FingerMesh
from fe_beam.model.hyperelastic import HyperelasticLaw
from fe_beam.model.settings import (
    INEXACT_NEWTON,
    INEXACT_NEWTON_EXTRA_ITERATIONS,
    resolve_solid_solver,
)
from fe_beam.model.solid import (  # noqa: F401  (their home; re-exported)
    ANCHORS,
    FORMULATIONS,
    Discretization,
    TendonLoad,
)
from fe_beam.solvers.contact import ContactSolver
from fe_beam.solvers.continuation import (
    BorderedConstraintSolver,
    Continuation,
    NonlinearParameterProblem,
)
from fe_beam.solvers.newton import (
    LoadStepping,
    NonlinearProblem,
    SNESSolver,
    SolverSettings,
)

__all__ = [
    "FORMULATIONS",
    "Discretization",
    "SolidFingerProblem",
    "TendonLoad",
    "UPFieldSplit",
    "evaluate_at_points",
    "rigid_body_modes",
]

class SolidFingerProblem:
    """Clamped hyperelastic finger with tendons and a dead tip force.

    Parameters
    ----------
    finger : the meshed finger (`fe_beam.fem.solid.geometry.create_finger_mesh`).
    material : a law from `fe_beam.model.hyperelastic`.
    tendons : one `TendonLoad` per tendon of ``finger.geometry`` (default: all slack).
    tip_force : total dead force (N) on the tip face, spread as a uniform traction.
    discretization, solver : see `Discretization`, `fe_beam.solvers.newton.SolverSettings`.
    obstacles, contact : rigid obstacles (3D `fe_beam.model.obstacles` shapes) the exterior
        boundary may touch, and their `ContactSettings` (`fe_beam.fem.solid.contact`;
        augmented-Lagrangian Uzawa updates around Newton, `fe_beam.solvers.contact`).
    """

    def __init__(
        self,
        finger: FingerMesh,
        material: HyperelasticLaw,
        tendons: Sequence[TendonLoad] = (),
        tip_force: Sequence[float] = (0.0, 0.0, 0.0),
        discretization: Discretization | None = None,
        solver: SolverSettings | None = None,
        prefix: str = "fe_beam_solid_",
        anchor: str = "face",
        obstacles: Sequence = (),
        contact=None,
    ):
        if anchor not in ANCHORS:
            raise ValueError(f"anchor must be one of {', '.join(ANCHORS)}, got {anchor!r}")
        self.anchor = anchor
        self.finger = finger
        self.mesh = finger.mesh
        self.comm: MPI.Comm = self.mesh.comm
        self.material = material
        self.discretization = discretization or Discretization()
        self.settings = solver or SolverSettings(linear_solver="mumps")
        self.tendon_loads = self._check_tendons(tendons)
        tip_force = np.asarray(tip_force, dtype=float)
        if tip_force.shape != (3,) or not np.all(np.isfinite(tip_force)):
            raise ValueError(f"tip_force must be 3 finite numbers (N), got {tip_force!r}")
        self.tip_force = tip_force
        mixed = self.discretization.formulation == "mixed"
        if mixed and not material.supports_mixed:
            raise ValueError(f"material {material.name!r} does not support the mixed formulation")
        if not mixed and math.isinf(material.kappa):
            raise ValueError("material.kappa = inf needs discretization.formulation = 'mixed'")
        self.load_factor = 0.0
        self.obstacles = tuple(obstacles)
        if any(o.dim != 3 for o in self.obstacles):
            raise ValueError("the solid's obstacles take 3D coordinates (dim = 3)")
        self.contact_settings = contact
        self.contact: SolidContact | None = None

        self._spaces()
        self._measures()
        self._forms()
        self._boundary_conditions()
        self._cables()
        self._nonlinear_solver(prefix)
        self._postprocessing_forms()

    # --- set-up pipeline --------------------------------------------------------------------

    def _check_tendons(self, tendons) -> list[TendonLoad]:
        n = len(self.finger.geometry.tendons)
        tendons = list(tendons) if tendons else [TendonLoad() for _ in range(n)]
        if len(tendons) != n:
            raise ValueError(f"tendons: need one TendonLoad per tendon ({n}), got {len(tendons)}")
        for i, t in enumerate(tendons):
            if not isinstance(t, TendonLoad):
                raise ValueError(f"tendons[{i}] must be a TendonLoad, got {t!r}")
        return tendons

    def _spaces(self) -> None:
        d = self.discretization
        vector = compat.vector_element(self.mesh, "Lagrange", d.degree)
        if d.formulation == "mixed":
            pressure = compat.element(self.mesh, "Lagrange", 1)
            self.W = compat.function_space(self.mesh, compat.mixed_element([vector, pressure]))
            self.V = self.W.sub(0)
            self.w = fem.Function(self.W, name="state")
            self.u, self.p = ufl.split(self.w)
        else:
            self.W = compat.function_space(self.mesh, vector)
            self.V = self.W
            self.w = fem.Function(self.W, name="displacement")
            self.u, self.p = self.w, None

    def _measures(self) -> None:
        q = self.discretization.quadrature_degree
        self.dx = ufl.Measure("dx", domain=self.mesh, metadata={"quadrature_degree": q})
        self.ds = ufl.Measure(
            "ds", domain=self.mesh, subdomain_data=self.finger.facet_tags,
            metadata={"quadrature_degree": q},
        )
        one = fem.Constant(self.mesh, PETSc.ScalarType(1.0))
        self.tip_area = assemble_scalar(fem.form(one * self.ds(TIP_TAG)))
        if not self.tip_area > 0:
            raise RuntimeError("the tip face (facet tag TIP_TAG) is empty")
        X = ufl.SpatialCoordinate(self.mesh)
        self.tip_centroid = np.array(
            [assemble_scalar(fem.form(X[i] * self.ds(TIP_TAG))) for i in range(3)]
        ) / self.tip_area

    def _forms(self) -> None:
        msh, law = self.mesh, self.material
        self.coefficients = {
            k: fem.Constant(msh, PETSc.ScalarType(v))
            for k, v in law.coefficients().items() if k != "kappa"
        }
        F = ufl.Identity(3) + ufl.grad(self.u)
        if self.p is None:
            self.coefficients["kappa"] = fem.Constant(msh, PETSc.ScalarType(law.kappa))
            energy_density = law.strain_energy(F, self.coefficients)
        else:  # p = kappa (J - 1) at equilibrium: the mean stress, positive in tension
            compliance = 0.0 if math.isinf(law.kappa) else 1.0 / law.kappa
            self.coefficients["compliance"] = fem.Constant(msh, PETSc.ScalarType(compliance))
            J = ufl.det(F)
            energy_density = (
                law.isochoric_energy(F, self.coefficients)
                + self.p * (J - 1) - 0.5 * self.coefficients["compliance"] * self.p**2
            )
        self.traction = fem.Constant(msh, np.zeros(3, dtype=PETSc.ScalarType))
        external = ufl.dot(self.traction, self.u) * self.ds(TIP_TAG)
        self.potential = energy_density * self.dx - external
        if self.obstacles:
            geometry = self.finger.geometry
            settings = self.contact_settings
            tolerance = (settings.penetration_tolerance
                         if settings is not None and settings.penetration_tolerance else
                         1e-3 * min(geometry.height(0.0), geometry.height(geometry.length),
                                    geometry.width))
            self.contact = SolidContact(self.obstacles, settings, msh, self.u,
                                        self.discretization.degree, law.shear_modulus,
                                        self.finger.sizes.size, tolerance)
            self.potential = self.potential + self.contact.energy
        self.residual = ufl.derivative(self.potential, self.w, ufl.TestFunction(self.W))

    def _boundary_conditions(self) -> None:
        fdim = self.mesh.topology.dim - 1
        facets = self.finger.facet_tags.find(CLAMP_TAG)
        if self.p is None:
            dofs = fem.locate_dofs_topological(self.W, fdim, facets)
            zero = np.zeros(3, dtype=PETSc.ScalarType)
            self.bcs = [fem.dirichletbc(zero, dofs, self.W)]
        else:
            V0, _ = compat.sub_space_collapsed(self.W, 0)
            zero = fem.Function(V0)
            dofs = fem.locate_dofs_topological((self.W.sub(0), V0), fdim, facets)
            self.bcs = [fem.dirichletbc(zero, dofs, self.W.sub(0))]
        if global_sum(self.comm, len(facets)) == 0:
            raise RuntimeError("the clamp face (facet tag CLAMP_TAG) is empty")

    def _cables(self) -> None:
        length = self.finger.geometry.length
        face = self._tip_face_nodes() if self.anchor == "face" else None
        self.cables = []
        for chain, tendon in zip(self.finger.tendon_chains, self.finger.geometry.tendons,
                                 strict=True):
            patch = None
            if face is not None and abs(chain[-1][0] - length) <= 1e-9 * length:
                patch = (face[0], consistent_plate_weights(face[0], face[1], chain[-1]))
            self.cables.append(TendonCable(self.V, chain, 0.0, name=tendon.name,
                                           anchor_patch=patch))

    def _tip_face_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """(the displacement space's nodes on the tip face (m, 3), their load moments (m, 3):
        int_tip phi_j (1, Y, Z) dA, phi_j the node's scalar shape function), on every rank:
        the consistent nodal loads of a traction linear in (Y, Z) (`consistent_plate_weights`).
        """
        S = compat.function_space(self.mesh, compat.element(self.mesh, "Lagrange",
                                                             self.discretization.degree))
        v = ufl.TestFunction(S)
        X = ufl.SpatialCoordinate(self.mesh)
        one = fem.Constant(self.mesh, PETSc.ScalarType(1.0))
        fdim = self.mesh.topology.dim - 1
        dofs = fem.locate_dofs_topological(S, fdim, self.finger.facet_tags.find(TIP_TAG))
        dofs = dofs[dofs < S.dofmap.index_map.size_local]
        columns = []
        for density in (one, X[1], X[2]):
            vector = compat.assemble_vector(fem.form(density * v * self.ds(TIP_TAG)))
            vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            columns.append(vector.getArray(readonly=True)[dofs].copy())
            vector.destroy()
        points = S.tabulate_dof_coordinates()[dofs][:, :3]
        moments = np.column_stack(columns)
        return (np.concatenate(self.comm.allgather(points)),
                np.concatenate(self.comm.allgather(moments)))

    def _tip_face_vertices(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (m, 3), lumped areas (m,)) of the whole tip face, on every rank."""
        fdim = self.mesh.topology.dim - 1
        facets = self.finger.facet_tags.find(TIP_TAG)
        facets = facets[facets < self.mesh.topology.index_map(fdim).size_local]
        triangles = compat.facet_vertex_coordinates(self.mesh, facets)
        triangles = np.concatenate(self.comm.allgather(triangles))
        areas = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                              triangles[:, 2] - triangles[:, 0]), axis=1)
        vertices, index = np.unique(triangles.reshape(-1, 3).round(12), axis=0,
                                    return_inverse=True)
        lumped = np.bincount(index.reshape(-1), weights=np.repeat(areas / 3, 3),
                             minlength=len(vertices))
        return vertices, lumped

    def _nonlinear_solver(self, prefix: str) -> None:
        self.problem = NonlinearProblem(self.residual, self.w, self.bcs, contributions=self.cables)
        if any(c.patch_dofs is not None for c in self.cables):
            # an anchor plate couples the whole tip face: preallocated by NonlinearProblem
            # (`TendonCable.jacobian_couplings`); a missed entry would cost time, not fail
            self.problem.A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        dofs = self.W.dofmap.index_map.size_global * self.W.dofmap.index_map_bs
        #: the linear solver actually used ("mumps", "gamg" or "fieldsplit"; "auto" resolved)
        pull_in = any(t.controlled_by_pull_in for t in self.tendon_loads)
        # pull-in control solves bordered systems with the Newton's KSP (tension updates from
        # extra solves): an inexact Krylov solve there stalls it (hundreds of tiny steps,
        # measured), so "auto" keeps MUMPS and an iterative solver runs without inexact Newton
        self.linear_solver = resolve_solid_solver(
            self.settings.linear_solver, self.p is not None,
            dofs if not pull_in or self.settings.linear_solver != "auto" else 0)
        settings = replace(self.settings, linear_solver=self.linear_solver)
        #: Newton iterations a load step may take beyond `LoadStepping.easy_iterations` and
        #: still count as easy (inexact Newton takes ~2 more than exact linear solves)
        self.extra_easy_iterations = 0
        if self.linear_solver != "mumps" and not pull_in:  # inexact Newton unless told otherwise
            settings = replace(settings,
                               petsc_options=INEXACT_NEWTON | dict(settings.petsc_options))
            self.extra_easy_iterations = INEXACT_NEWTON_EXTRA_ITERATIONS
        nullspace = None
        if self.linear_solver == "gamg":
            nullspace = rigid_body_modes(self.W)
        self.snes_solver = SNESSolver(self.problem, settings, prefix, near_nullspace=nullspace,
                                      state_scale=self.finger.geometry.length)
        if self.linear_solver == "fieldsplit":
            self._fieldsplit = UPFieldSplit(self.W, self.material, self.dx)
            self._fieldsplit.attach(self.snes_solver.snes.getKSP().getPC())
        controlled = [i for i, t in enumerate(self.tendon_loads) if t.controlled_by_pull_in]
        if controlled:
            self.solver = _PullInSolver(
                self.snes_solver, [self.cables[i] for i in controlled], self._unloaded
            )
        else:
            self.solver = self.snes_solver
        if self.contact is not None:
            self.solver = ContactSolver(self.solver, self.contact)

    def _postprocessing_forms(self) -> None:
        ds_tip = self.ds(TIP_TAG)
        u, X = self.u, ufl.SpatialCoordinate(self.mesh)
        Xc = fem.Constant(self.mesh, self.tip_centroid.astype(PETSc.ScalarType))
        self._tip_u = [fem.form(u[i] * ds_tip) for i in range(3)]
        self._tip_cov = [
            [fem.form((X[i] - Xc[i]) * (X[j] + u[j]) * ds_tip) for j in range(3)]
            for i in range(3)
        ]
        N = ufl.FacetNormal(self.mesh)
        F = ufl.Identity(3) + ufl.grad(u)
        nanson = ufl.det(F) * ufl.inv(F).T * N
        self._tip_normal = [fem.form(nanson[i] * ds_tip) for i in range(3)]
        nodes = np.array(
            [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0, 0], [0, 0.5, 0],
             [0, 0, 0.5], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]], dtype=float
        )
        self._F_nodes = compat.expression(F, nodes)
        cells = np.arange(self.mesh.topology.index_map(self.mesh.topology.dim).size_local,
                          dtype=np.int32)
        reference = compat.evaluate_expression(compat.expression(X, nodes), self.mesh, cells)
        self._bulk_nodes = bulk_mask(reference, self.finger.tendon_chains, self.finger.geometry)

    def _unloaded(self) -> bool:
        """True when every load is zero (the equilibrium is then u = 0, p = 0)."""
        return not np.any(self.traction.value) and all(c.tension == 0 for c in self.cables)

    # --- loading and solving ----------------------------------------------------------------

    def set_load_factor(self, lam: float) -> None:
        """Traction lambda t0, tensions lambda T_i, pull-in targets lambda d_i."""
        self.load_factor = float(lam)
        self.traction.value[:] = lam * self.tip_force / self.tip_area
        for cable, load in zip(self.cables, self.tendon_loads, strict=True):
            if load.controlled_by_pull_in:
                cable.target_pull_in = lam * load.pull_in
            else:
                cable.tension = lam * load.tension

    def solve(
        self,
        stepping: LoadStepping | None = None,
        progress: bool = False,
        record_steps: bool = True,
    ) -> dict:
        """Ramp the load factor 0 -> 1 (load control of `engine`) from the current
        state; returns ``{"steps": [...], **self.summary()}`` (plain Python data).

        Raises `fe_beam.solvers.newton.LoadSteppingFailed` when the ramp stalls.
        """
        steps = []

        def on_converged(step):
            self.accept_step()
            if not record_steps:
                return
            rot = self.tip_rotation()
            steps.append(
                {
                    "load_factor": step.load_factor,
                    "iterations": step.iterations,
                    "linear_iterations": step.linear_iterations,
                    "tensions": self.tensions(),
                    "tip_displacement": self.tip_displacement().tolist(),
                    "tip_rotation": rot["angle"],
                    **({"contact": self.contact.summary()} if self.contact else {}),
                }
            )

        engine = self.engine()
        engine.parameter = 0.0  # a ramp 0 -> 1 from the current state, as always
        engine.load_control(1.0, stepping or LoadStepping(steps=5), on_converged=on_converged,
                            progress=progress, label="solid")
        return {"steps": steps, **self.summary()}

    def accept_step(self) -> None:
        """A load step was accepted: the contact multipliers become the committed ones."""
        if self.contact is not None:
            self.contact.commit()

    def parameter_problem(self):
        """This problem as a `fe_beam.solvers.continuation.ParameterProblem` of the load factor
        (`set_load_factor`): its residual is affine in it (tip traction, cable tensions), the
        arc metric weighs the displacement by 1/L^2 and the pressure by 0. Under pull-in
        control: load control only."""

        metric = compat.vector_of(self.w).duplicate()
        weights = np.zeros(metric.getLocalSize())
        owned = self.W.dofmap.index_map.size_local * self.W.dofmap.index_map_bs
        if self.p is None:
            weights[:] = 1.0
        else:
            dofs = np.asarray(compat.sub_space_collapsed(self.W, 0)[1])
            weights[dofs[dofs < owned]] = 1.0
        metric.getArray()[:] = weights / self.finger.geometry.length**2
        adapter = NonlinearParameterProblem(self.solver, self.set_load_factor, metric=metric,
                                            parameter=self.load_factor)
        adapter.arc_length_ready = self.solver is self.snes_solver
        return adapter

    def engine(self):
        """The continuation engine of the load factor (`fe_beam.solvers.continuation.Continuation`,
        built once); its parameter follows ``load_factor``."""

        if getattr(self, "_engine", None) is None:
            self._engine = Continuation(self.parameter_problem(), self.load_factor)
        self._engine.parameter = self.load_factor
        return self._engine

    # --- post-processing --------------------------------------------------------------------

    def displacement(self) -> fem.Function:
        """The displacement as a Function of its own (collapsed) space."""
        if self.p is None:
            return self.w
        return self.w.sub(0).collapse()

    def tensions(self) -> list[float]:
        return [float(c.tension) for c in self.cables]

    def tendon_lengths(self) -> list[float]:
        x = compat.vector_of(self.w)
        return [c.length(x) for c in self.cables]

    def tip_displacement(self) -> np.ndarray:
        """(1/A_tip) int_tip u dA."""
        return np.array([assemble_scalar(f) for f in self._tip_u]) / self.tip_area

    def tip_rotation(self) -> dict:
        """Best-fit rotation of the tip face (Kabsch) and its area-averaged deformed normal.

        Returns {"angle": atan2(R_yx, R_xx), "matrix": R (3x3 list), "normal": n (list),
        "normal_angle": atan2(n_y, n_x)}.
        """
        H = np.array([[assemble_scalar(f) for f in row] for row in self._tip_cov])
        U, _, Vt = np.linalg.svd(H)
        d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
        R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
        n = np.array([assemble_scalar(f) for f in self._tip_normal])
        n /= np.linalg.norm(n)
        return {
            "angle": float(math.atan2(R[1, 0], R[0, 0])),
            "matrix": R.tolist(),
            "normal": n.tolist(),
            "normal_angle": float(math.atan2(n[1], n[0])),
        }

    def _displacement_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned displacement nodes (n, 3) local dof indices of W, their reference
        coordinates (n, 3)), built once."""
        if getattr(self, "_u_nodes", None) is None:
            owned = self.W.dofmap.index_map.size_local * self.W.dofmap.index_map_bs
            if self.p is None:
                n = self.W.dofmap.index_map.size_local
                nodes = np.arange(3 * n).reshape(-1, 3)
                coordinates = self.W.tabulate_dof_coordinates()[:n]
            else:  # V0's dofs come in nodes of 3 components (`UPFieldSplit`)
                V0, u_map = compat.sub_space_collapsed(self.W, 0)
                nodes = np.asarray(u_map, dtype=np.int64).reshape(-1, 3)
                coordinates = V0.tabulate_dof_coordinates()[: len(nodes)]
                keep = np.all(nodes < owned, axis=1)
                nodes, coordinates = nodes[keep], coordinates[keep]
            self._u_nodes, self._u_X = nodes, np.asarray(coordinates, dtype=float)[:, :3]
        return self._u_nodes, self._u_X

    def equilibrium(self) -> dict:
        """Global equilibrium of the current state (collective): the support reaction at the
        clamped face, read off the rows of the assembled residual (no boundary conditions, the
        cables' contributions included) that the clamp fixes, against the external loads
        computed apart: the dead tip force lambda * tip_force with its moment (Xc + u_tip) x F
        (a uniform traction), and each obstacle's contact force and moment (its traction
        integrated over the surface, `SolidContact.summary`, `SolidContact.moments`). The
        tendons are internal (a cable's energy tau l is invariant under rigid motions: its
        forces on the body sum to zero, force and moment), so the reaction balances the
        external loads only.

        Returns {"reaction_force", "reaction_moment" (about the origin, deformed positions),
        "force_imbalance", "moment_imbalance" (|sum|), "scale" (the largest load: the tip
        force, a contact force, a tendon tension, the reaction [N]; with nothing loaded the
        force of a unit strain on the tip face, mu A), "value" (max(|force sum|, |moment sum|
        / L) / scale)}."""
        x = compat.vector_of(self.w)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        b = compat.create_vector(self.problem.residual_form)
        with b.localForm() as local:
            local.set(0.0)
        compat.assemble_vector(b, self.problem.residual_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        for term in self.problem.contributions:
            term.add_to_residual(x, b)
        b.assemble()
        residual = b.getArray(readonly=True).copy()
        state = x.getArray(readonly=True)
        b.destroy()
        nodes, X = self._displacement_nodes()
        clamped = np.zeros(len(residual), dtype=bool)
        clamped[compat.owned_bc_dofs(self.bcs)] = True
        on_clamp = clamped[nodes[:, 0]]
        reaction = residual[nodes[on_clamp]]  # R = f_int - f_ext: the support's force there
        positions = X[on_clamp] + state[nodes[on_clamp]]
        force = global_sum(self.comm, reaction.sum(axis=0))
        moment = global_sum(self.comm, np.cross(positions, reaction).sum(axis=0))
        applied = self.load_factor * self.tip_force
        centre = self.tip_centroid + self.tip_displacement()
        total_force = force + applied
        total_moment = moment + np.cross(centre, applied)
        loads = [float(np.linalg.norm(applied)), *(abs(t) for t in self.tensions())]
        if self.contact is not None:
            forces = [np.asarray(e["force"]) for e in self.contact.summary()]
            for f, m in zip(forces, self.contact.moments(), strict=True):
                total_force = total_force + f
                total_moment = total_moment + m
                loads.append(float(np.linalg.norm(f)))
        # the largest load (the reaction too: a spurious one must not set a small scale);
        # nothing loaded: the force of a unit strain on the tip face, mu A
        scale = (max(*loads, float(np.linalg.norm(force))) if max(loads) > 0
                 else self.material.shear_modulus * self.tip_area)
        length = self.finger.geometry.length
        imbalance = (float(np.linalg.norm(total_force)), float(np.linalg.norm(total_moment)))
        value = max(imbalance[0], imbalance[1] / length) / scale
        return {"reaction_force": force.tolist(), "reaction_moment": moment.tolist(),
                "force_imbalance": imbalance[0], "moment_imbalance": imbalance[1],
                "scale": scale, "value": value}

    def backbone(self, xs: Sequence[float] | None = None, n_gauss: int = 4) -> dict:
        """Deformed area centroids of the reference sections X = xs (default 21 stations).

        Returns {"x": xs, "centroid": (n, 3) list, "displacement": (n, 3) list}.
        """
        geometry = self.finger.geometry
        L, r = geometry.length, geometry.tip_radius
        xs = np.linspace(0.0, L - r, 21) if xs is None else np.asarray(xs, dtype=float)
        if np.any(xs < 0) or np.any(xs > L - r + 1e-12 * L):
            raise ValueError(f"backbone stations must lie in [0, L - tip_radius], got {xs!r}")
        g, wg = np.polynomial.legendre.leggauss(n_gauss)
        points, weights = [], []
        for x in xs:
            h = float(geometry.height(x))
            yy, zz = np.meshgrid(0.5 * h * g, 0.5 * geometry.width * g, indexing="ij")
            points.append(np.column_stack([np.full(yy.size, x), yy.ravel(), zz.ravel()]))
            weights.append(np.outer(wg, wg).ravel())
        points = np.concatenate(points)
        values = evaluate_at_points(self.displacement(), points)
        m = n_gauss * n_gauss
        w = np.concatenate(weights).reshape(len(xs), m, 1) / 4.0
        u_mean = (w * values.reshape(len(xs), m, 3)).sum(axis=1)
        X_mean = (w * points.reshape(len(xs), m, 3)).sum(axis=1)
        return {
            "x": xs.tolist(),
            "centroid": (X_mean + u_mean).tolist(),
            "displacement": u_mean.tolist(),
        }

    def max_principal_stretches(self) -> dict:
        """{"anywhere", "bulk"}: max over cells and P2 nodes of sqrt(largest eigenvalue of
        C = F^T F), over all nodes and over the nodes of the bulk (`bulk_mask`); F is evaluated
        once for both."""
        tdim = self.mesh.topology.dim
        cells = np.arange(self.mesh.topology.index_map(tdim).size_local, dtype=np.int32)
        anywhere = bulk = 1.0
        if len(cells):
            F = compat.evaluate_expression(self._F_nodes, self.mesh, cells).reshape(-1, 3, 3)
            stretch = np.sqrt(np.linalg.eigvalsh(np.einsum("nki,nkj->nij", F, F))[:, -1])
            anywhere = float(stretch.max())
            if self._bulk_nodes.any():
                bulk = float(stretch[self._bulk_nodes].max())
        return {"anywhere": global_max(self.comm, anywhere), "bulk": global_max(self.comm, bulk)}

    def max_principal_stretch(self, bulk: bool = False) -> float:
        """One of `max_principal_stretches`."""
        return self.max_principal_stretches()["bulk" if bulk else "anywhere"]

    def summary(self) -> dict:
        """Plain-data results of the current state."""
        rotation = self.tip_rotation()
        return {
            "load_factor": self.load_factor,
            "tip_displacement": self.tip_displacement().tolist(),
            "tip_rotation": rotation["angle"],
            "tip_rotation_matrix": rotation["matrix"],
            "tip_normal": rotation["normal"],
            "tensions": self.tensions(),
            "tendon_lengths": self.tendon_lengths(),
            "tendon_reference_lengths": [c.reference_length for c in self.cables],
            "backbone": self.backbone(),
            **stretch_keys(self.max_principal_stretches()),
            **({"contact": self.contact.summary()} if self.contact else {}),
        }


def stretch_keys(stretches: dict) -> dict:
    """The summary keys of `SolidFingerProblem.max_principal_stretches`."""
    return {"max_principal_stretch": stretches["anywhere"],
            "max_principal_stretch_bulk": stretches["bulk"]}


def plate_weights(vertices: np.ndarray, lumped: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """Weights w_j of the face vertices for an anchor plate at ``anchor``: closest (in the
    lumped-area metric) to a uniform traction, with sum w_j = 1 and sum w_j (y_j, z_j) = the
    anchor's (y, z), so that the spread force has the point force's resultant and moment. The
    result is a linearly varying traction (Navier's distribution of an eccentric force)."""
    base = lumped / lumped.sum()
    moments = np.vstack([np.ones(len(vertices)), vertices[:, 1], vertices[:, 2]])
    target = np.array([1.0, anchor[1], anchor[2]])
    system = moments @ (base[:, None] * moments.T)
    multipliers = np.linalg.solve(system, target - moments @ base)
    return base * (1.0 + moments.T @ multipliers)


def consistent_plate_weights(points: np.ndarray, moments: np.ndarray,
                             anchor: np.ndarray) -> np.ndarray:
    """Weights w_j of the face nodes ``points`` (m, 3) for an anchor plate at ``anchor``: the
    consistent nodal loads w_j = int_tip phi_j t dA of the traction t = a + b Y + c Z (per
    unit force) with resultant 1 and moment arm the anchor's (y, z), i.e. sum w_j = 1 and
    sum w_j (y_j, z_j) = (y_a, z_a) (exact: Y and Z lie in the nodal space). ``moments`` holds
    int_tip phi_j (1, Y, Z) dA (`SolidFingerProblem._tip_face_nodes`).

    Unlike `plate_weights` (the same traction lumped to the P1 vertices, which for P2 elements
    is a set of point forces at the vertices: local singularities of the discrete solution
    right on the tip face, so that the face's best-fit rotation converged erratically under
    refinement), this is the traction itself as the finite element sees it."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    moments = np.asarray(moments, dtype=float).reshape(-1, 3)
    arms = np.vstack([np.ones(len(points)), points[:, 1], points[:, 2]])  # (3, m)
    coefficients = np.linalg.solve(arms @ moments, np.array([1.0, anchor[1], anchor[2]]))
    return moments @ coefficients


TENDON_TUBE = 0.1  # radius of the tube around a tendon left out of the bulk, / section height


def bulk_mask(points: np.ndarray, chains: Sequence[np.ndarray], geometry) -> np.ndarray:
    """Boolean mask of the reference (n, 3) ``points`` of the bulk: farther than half the base
    height H(0) / 2 from the clamped face, and farther than the section height H(x) from every
    tendon end not on the clamp (for an end on the tip face: from the whole tip face, where a
    face anchor spreads the force).

    Also left out: a tube of radius TENDON_TUBE H(x) around each tendon, which, once the
    finger bends, presses on the solid as a line load (a 1/r strain singularity).

    These zones hold singular strains of the idealised model that grow without bound under mesh
    refinement: the edges of the fully clamped face, the cable's end force acting on one vertex
    (point anchor), the edges of the loaded tip face (face anchor), the cable's line load. The
    maximum over the rest, at a fixed distance from them, converges.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    length = geometry.length
    inside = points[:, 0] >= 0.5 * float(geometry.height(0.0))
    for chain in chains:
        chain = np.asarray(chain, dtype=float)
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            segment = b - a
            t = np.clip((points - a) @ segment / (segment @ segment), 0.0, 1.0)
            distance = np.linalg.norm(points - (a + t[:, None] * segment), axis=1)
            inside &= distance >= TENDON_TUBE * geometry.height(points[:, 0])
        for end in (np.asarray(chain[0], float), np.asarray(chain[-1], float)):
            radius = float(geometry.height(end[0]))
            if end[0] >= length * (1 - 1e-12):
                inside &= points[:, 0] <= length - radius
            elif end[0] > 1e-12 * length:
                inside &= np.linalg.norm(points - end, axis=1) >= radius
    return inside


class _PullInSolver:
    """Pull-in control of cables: their tensions are global unknowns of the Newton system with
    the constraints l_i^0 - l_i(u) = target_i
    (`fe_beam.solvers.continuation.BorderedConstraintSolver`:
    [[K, dR/dtau], [g^T, 0]], g_i = dl_i/du with Dirichlet rows zeroed, one bordered solve per
    iteration; tensions clipped at 0). When nothing is loaded and no pull-in is asked (the
    first step) the state is set to the known equilibrium u = 0 instead of asking Newton to
    reduce a round-off residual.
    """

    def __init__(self, inner: SNESSolver, cables: list[TendonCable], unloaded,
                 rtol: float = 1e-10, max_it: int = 30):

        self.inner = inner
        self.solver = inner
        self.unloaded = unloaded
        self.problem = inner.problem
        self.cables = cables
        self.rtol, self.max_it = rtol, max_it
        for c in cables:
            c.target_pull_in = 0.0
        start = self.problem.b.getOwnershipRange()[0]
        self._bc_rows = (compat.owned_bc_dofs(self.problem.bcs) + start).astype(PETSc.IntType)
        scale = max(c.reference_length for c in cables)
        self._bordered = BorderedConstraintSolver(
            inner, lambda: [c.tension for c in self.cables], self._set_tensions,
            lambda x: np.array([c.length(x) for c in self.cables]), self._gradient_vectors,
            lambda: np.array([c.reference_length - c.target_pull_in for c in self.cables]),
            rtol * scale, max_it, nonnegative=True,
            unloaded=lambda: self.unloaded() and all(c.target_pull_in == 0 for c in self.cables),
        )

    @property
    def linear_iterations(self) -> int:
        return self._bordered.linear_iterations

    def _set_tensions(self, values) -> None:
        for c, value in zip(self.cables, values, strict=True):
            c.tension = float(value)

    def residual_norm(self) -> float:
        return self.inner.residual_norm()

    def set_reference_residual(self, value) -> None:
        self._bordered.set_reference_residual(value)

    def destroy(self) -> None:
        self.inner.destroy()

    def _gradient_vectors(self, x: PETSc.Vec) -> list[PETSc.Vec]:
        vectors = []
        bc_rows = self._bc_rows
        for c in self.cables:
            g = x.duplicate()
            g.set(0.0)
            saved, c.tension = c.tension, 1.0
            c.add_to_residual(x, g)
            c.tension = saved
            g.assemble()
            g.setValues(bc_rows, np.zeros(len(bc_rows)), addv=PETSc.InsertMode.INSERT_VALUES)
            g.assemble()
            vectors.append(g)
        return vectors

    def solve(self) -> int:
        return self._bordered.solve()


def evaluate_at_points(function: fem.Function, points: np.ndarray) -> np.ndarray:
    """Values (n, value_size) of ``function`` at ``points`` (n, 3), identical on every rank.

    Each point is evaluated by the lowest rank that holds a cell containing it; raises
    ValueError when a point lies outside the mesh.
    """
    msh = function.function_space.mesh
    comm = msh.comm
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    tree = compat.bounding_box_tree(msh, msh.topology.dim)
    cells = compat.first_colliding_cells(msh, tree, points)
    found = cells >= 0
    owner = np.empty(len(points), dtype=np.int64)
    comm.Allreduce(np.where(found, comm.rank, comm.size).astype(np.int64), owner, op=MPI.MIN)
    if np.any(owner == comm.size):
        bad = points[owner == comm.size][0]
        raise ValueError(f"point {bad.tolist()} is outside the mesh")
    mine = owner == comm.rank
    size = int(np.prod(function.ufl_shape)) if function.ufl_shape else 1
    values = np.zeros((len(points), size))
    if np.any(mine):
        values[mine] = function.eval(points[mine], cells[mine]).reshape(-1, size)
    return global_sum(comm, values)


def rigid_body_modes(space) -> PETSc.NullSpace:
    """Near-nullspace of 3D elasticity (3 translations, 3 rotations), orthonormalised (GAMG)."""
    coords = space.tabulate_dof_coordinates()
    n_owned = space.dofmap.index_map.size_local
    x = coords[:n_owned]
    modes = []
    for k in range(6):
        f = fem.Function(space)
        a = compat.local_array(f).reshape(-1, 3)
        a[:] = 0.0
        if k < 3:
            a[:n_owned, k] = 1.0
        else:
            i, j = [(0, 1), (1, 2), (2, 0)][k - 3]
            a[:n_owned, i] = -x[:, j]
            a[:n_owned, j] = x[:, i]
        modes.append(compat.vector_of(f).copy())
    for i, v in enumerate(modes):
        for u in modes[:i]:
            v.axpy(-v.dot(u), u)
        v.normalize()
    return PETSc.NullSpace().create(vectors=modes, comm=space.mesh.comm)


class UPFieldSplit:
    """The fields of the Taylor-Hood space W = (u, p) for PETSc's PCFIELDSPLIT: index sets of
    the owned displacement and pressure dofs (global numbering of W), the rigid-body
    near-nullspace of the displacement block (for GAMG) and the Schur-complement
    preconditioner -(1/mu + 1/kappa) M_p (M_p the P1 pressure mass matrix, assembled once).

    At small strain the Schur complement S = -B A^-1 B^T - M_p / kappa is spectrally equivalent
    to -(1/mu + 1/kappa) M_p, uniformly in the mesh size and in kappa / mu (inf-sup stability
    of P2-P1), so the Krylov iterations stay bounded under refinement and as nu -> 1/2.
    """

    def __init__(self, W, material: HyperelasticLaw, dx):
        comm = W.mesh.comm
        imap = W.dofmap.index_map
        n_owned = imap.size_local * W.dofmap.index_map_bs
        start = imap.local_range[0] * W.dofmap.index_map_bs
        V0, u_map = compat.sub_space_collapsed(W, 0)
        _, p_map = compat.sub_space_collapsed(W, 1)
        u_map, p_map = np.asarray(u_map, dtype=np.int64), np.asarray(p_map, dtype=np.int64)
        # V0's dofs come in nodes of 3 components: u_map[3 i + c] = W dof of node i, component c
        bs = V0.dofmap.index_map_bs
        nodes = u_map.reshape(-1, bs)
        owned = nodes[:, 0] < n_owned
        coordinates = V0.tabulate_dof_coordinates()[: len(nodes)][owned]
        nodes = nodes[owned]
        if np.any(nodes >= n_owned):
            raise RuntimeError("fieldsplit: a displacement node's components on two ranks")
        order = np.argsort(nodes[:, 0])
        nodes, coordinates = nodes[order], coordinates[order]
        u_dofs = nodes.reshape(-1)
        blocked = bool(np.all(np.diff(nodes, axis=1) == 1))
        p_dofs = np.sort(p_map[p_map < n_owned])
        self.is_u = PETSc.IS().createGeneral((u_dofs + start).astype(PETSc.IntType), comm=comm)
        self.is_p = PETSc.IS().createGeneral((p_dofs + start).astype(PETSc.IntType), comm=comm)
        if blocked:
            self.is_u.setBlockSize(bs)
        self.near_nullspace = _rigid_body_modes_of(coordinates, comm)
        self.is_u.compose("nearnullspace", self.near_nullspace)
        # -(1/mu + 1/kappa) M_p on W (zero outside the p-p block), then its p-p block
        scale = 1.0 / material.shear_modulus + (
            0.0 if math.isinf(material.kappa) else 1.0 / material.kappa)
        _, q = ufl.split(ufl.TestFunction(W))
        _, p = ufl.split(ufl.TrialFunction(W))
        full = compat.assemble_matrix(fem.form(-scale * p * q * dx))
        full.assemble()
        self.schur_preconditioner = full.createSubMatrix(self.is_p, self.is_p)
        full.destroy()

    def attach(self, pc: PETSc.PC) -> None:
        """Give ``pc`` (of type fieldsplit, options from the solver settings) its fields and
        the Schur preconditioner."""
        pc.setFieldSplitIS(("u", self.is_u), ("p", self.is_p))
        pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER,
                                     self.schur_preconditioner)


def _rigid_body_modes_of(x: np.ndarray, comm) -> PETSc.NullSpace:
    """Rigid-body modes of the nodes ``x`` (n, 3), vectors of (n * 3) interleaved components,
    orthonormalised."""
    n = len(x)
    modes = []
    for k in range(6):
        a = np.zeros((n, 3))
        if k < 3:
            a[:, k] = 1.0
        else:
            i, j = [(0, 1), (1, 2), (2, 0)][k - 3]
            a[:, i] = -x[:, j]
            a[:, j] = x[:, i]
        v = PETSc.Vec().createMPI((3 * n, PETSc.DETERMINE), comm=comm)
        v.array[:] = a.reshape(-1)
        modes.append(v)
    for i, v in enumerate(modes):
        for u in modes[:i]:
            v.axpy(-v.dot(u), u)
        v.normalize()
    return PETSc.NullSpace().create(vectors=modes, comm=comm)
