"""Solver, load-stepping and time-stepping settings as plain validated dataclasses.

No PETSc here: `SolverSettings` checks the form of its options; PETSc judges their values where
a solver is built (`fe_beam.solvers.newton`). Creating or `dataclasses.replace`-ing a setting is
cheap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from numbers import Integral

__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "LINEAR_SOLVERS",
    "SOLID_LINEAR_SOLVERS",
    "LINE_SEARCHES",
    "SADDLE_POINT_WORKSPACE",
    "SCHEMES",
    "Damping",
    "LoadStepping",
    "SolverSettings",
    "TimeSettings",
    "check_option_names",
]

LINEAR_SOLVERS = ("auto", "mumps", "lu", "gamg", "gmres-ilu")
#: [solid] solver: "fieldsplit" (the scalable solver of the 3D solid, see `resolve_solid_solver`)
#: is set up by `fe_beam.solvers.solid`, which gives PETSc the fields
SOLID_LINEAR_SOLVERS = ("auto", "mumps", "gamg", "fieldsplit")
#: "auto" for the 3D solid: MUMPS up to this many unknowns, the iterative solver above
#: (measured with benchmarks/bench_solid.py --crossover: see `resolve_solid_solver`)
AUTO_DIRECT_MAX_DOFS = 10_000
LINE_SEARCHES = ("bt", "basic", "l2", "cp")


@dataclass
class SolverSettings:
    """Newton (SNES) and linear-solver settings; ``petsc_options`` are merged over the defaults.

    Only the form of ``petsc_options`` is checked here (names without '-', string or number
    values); PETSc itself judges the values where a solver is built
    (`fe_beam.solvers.newton.check_petsc_options`, called by
    `fe_beam.solvers.newton.SNESSolver`)."""

    rtol: float = 1e-9
    # Residuals carry the problem's units (N, N m): any fixed absolute tolerance is wrong for
    # someone (a 1e-15 N load on a hair-thin beam). Convergence is relative (rtol, stol).
    atol: float = 1e-300
    stol: float = 1e-11
    max_it: int = 25
    # Plain Newton: ||F||-based line searches reject good steps of saddle-point (multiplier)
    # problems; globalisation comes from load-step cut-back instead.
    line_search: str = "basic"
    # "auto": PETSc's LU for a serial problem without multipliers (2.5-3x faster than MUMPS on
    # the small 1D systems), MUMPS otherwise (pivoting for saddle points; parallel); resolved
    # by `for_problem`, MUMPS where nothing resolved it
    linear_solver: str = "auto"
    petsc_options: dict = field(default_factory=dict)

    def __post_init__(self):
        for name in ("rtol", "atol", "stol"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not (0 <= value < 1):
                raise ValueError(f"solver.{name} must be a number in [0, 1), got {value!r}")
        if not isinstance(self.max_it, int) or self.max_it < 1:
            raise ValueError(f"solver.max_it must be an integer >= 1, got {self.max_it!r}")
        if self.line_search not in LINE_SEARCHES:
            raise ValueError(
                f"solver.line_search must be one of {', '.join(LINE_SEARCHES)}; "
                f"got {self.line_search!r}"
            )
        if self.linear_solver not in LINEAR_SOLVERS + ("fieldsplit",):
            raise ValueError(
                f"solver.linear_solver must be one of {', '.join(LINEAR_SOLVERS)}; "
                f"got {self.linear_solver!r}"
            )
        if not isinstance(self.petsc_options, dict):
            raise ValueError("solver.petsc_options must be a table of PETSc option = value")
        check_option_names(self.petsc_options)

    def for_problem(self, saddle_point: bool, comm) -> SolverSettings:
        """These settings with "auto" resolved for a problem: PETSc's LU (no pivoting) only
        for a serial system without multiplier rows (zero diagonal), MUMPS otherwise."""
        settings = self
        if self.linear_solver == "auto":
            serial_spd_like = comm.size == 1 and not saddle_point
            settings = replace(self, linear_solver="lu" if serial_spd_like else "mumps")
        if saddle_point and settings.linear_solver in ("auto", "mumps"):
            # the pivoting that the zero diagonal of the multiplier rows needs overruns MUMPS's
            # default workspace estimate (+20%) on fine meshes (degree 1, inextensible-
            # unshearable, from ~1000 elements: INFOG(1) = -9, "DIVERGED_LINEAR_SOLVE")
            options = {SADDLE_POINT_WORKSPACE[0]: SADDLE_POINT_WORKSPACE[1]}
            settings = replace(settings, petsc_options=options | dict(settings.petsc_options))
        return settings

    def options(self) -> dict:
        """PETSc options (without prefix): defaults first, the user's options over them."""
        opts = {
            "snes_type": "newtonls",
            "snes_linesearch_type": self.line_search,
            "snes_rtol": self.rtol,
            "snes_atol": self.atol,
            "snes_stol": self.stol,
            "snes_max_it": self.max_it,
            "snes_divergence_tolerance": 1e12,
        }
        if self.linear_solver in ("auto", "mumps", "lu"):
            opts |= {"ksp_type": "preonly", "pc_type": "lu"}
            if self.linear_solver in ("auto", "mumps"):
                opts["pc_factor_mat_solver_type"] = "mumps"
        elif self.linear_solver == "gamg":
            opts |= {"ksp_type": "cg", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_max_it": 1000}
        elif self.linear_solver == "fieldsplit":
            opts |= FIELDSPLIT_OPTIONS | INEXACT_NEWTON
        else:
            # block Jacobi: ILU on each rank's block (plain ILU in serial; PETSc's ILU
            # would refuse a parallel matrix); ILU(0) breaks down on beam matrices, ILU(2) holds
            opts |= {"ksp_type": "gmres", "pc_type": "bjacobi", "sub_pc_type": "ilu",
                     "sub_pc_factor_levels": 2, "ksp_gmres_restart": 100, "ksp_max_it": 2000,
                     "ksp_rtol": 1e-12}
        opts |= {str(k): v for k, v in self.petsc_options.items()}
        return opts


# Inexact Newton (Eisenstat-Walker, PETSc's version 2): the Krylov tolerance of each Newton
# iteration follows the nonlinear convergence; capped at 0.1 so that every Newton step still
# reduces the linearised residual tenfold (the convergence test of
# `fe_beam.solvers.newton.SNESSolver`
# is on the nonlinear residual, as tight as with a direct solver).
INEXACT_NEWTON = {"snes_ksp_ew": "true", "snes_ksp_ew_rtolmax": 0.1}
# ... whose loose early linear solves cost a step about 2 Newton iterations more than exact ones
# (u-p finger at 0.05 load steps: 5-6 with fieldsplit, 3-4 with MUMPS): a load step counts as
# easy (`LoadStepping.easy_iterations`, grow the next one) with that many more iterations
INEXACT_NEWTON_EXTRA_ITERATIONS = 2

# u-p (Taylor-Hood) saddle point: FGMRES, block lower-triangular Schur preconditioner
# [[A, 0], [B, S]]^-1 with A^-1 ~ one GAMG V-cycle (rigid-body near-nullspace) and
# S = -B A^-1 B^T - M/kappa ~ -(1/mu + 1/kappa) M_p (pressure mass matrix, given by
# `fe_beam.solvers.solid` as the user Schur preconditioner), applied by Jacobi.
# The preconditioner (GAMG hierarchy, extracted blocks) is rebuilt every 3rd Newton iteration
# of a load step: FGMRES still runs on the current Jacobian, so the Newton steps and the
# equilibrium are unchanged, and the Krylov count barely moves (measured, benchmarks/README.md).
FIELDSPLIT_OPTIONS = {
    "snes_lag_preconditioner": 3,
    "ksp_type": "fgmres",
    "ksp_gmres_restart": 200,
    "ksp_max_it": 1000,
    "ksp_rtol": 1e-10,
    "pc_type": "fieldsplit",
    "pc_fieldsplit_type": "schur",
    "pc_fieldsplit_schur_fact_type": "lower",
    "fieldsplit_u_ksp_type": "preonly",
    "fieldsplit_u_pc_type": "gamg",
    "fieldsplit_p_ksp_type": "preonly",
    "fieldsplit_p_pc_type": "jacobi",
}


def resolve_solid_solver(requested: str, mixed: bool, dofs: int,
                         threshold: int = AUTO_DIRECT_MAX_DOFS) -> str:
    """The linear solver of the 3D solid: "mumps", "gamg" (CG + GAMG, displacement
    formulation) or "fieldsplit" (FGMRES + Schur fieldsplit, u-p formulation).

    "auto": MUMPS up to ``threshold`` unknowns (a sparse LU is then fastest and exact), the
    iterative solver of the formulation above. "fieldsplit" on the displacement formulation
    (one field, nothing to split) is the GAMG path. "gamg" (CG) cannot solve the u-p saddle
    point: ValueError. Other `LINEAR_SOLVERS` ("lu", "gmres-ilu") are returned as given."""
    if requested not in SOLID_LINEAR_SOLVERS:
        return requested
    if requested == "gamg" and mixed:
        raise ValueError("solver.linear_solver = 'gamg' is for the displacement formulation "
                         "(use 'fieldsplit' for mixed u-p)")
    if requested == "auto":
        requested = "mumps" if dofs <= threshold else "iterative"
    if requested == "mumps":
        return "mumps"
    return "fieldsplit" if mixed else "gamg"


# MUMPS ICNTL(14): percentage by which the factorisation workspace may exceed its estimate
SADDLE_POINT_WORKSPACE = ("mat_mumps_icntl_14", 100)

@dataclass
class LoadStepping:
    """Load-factor ramp 0 -> 1: ``steps`` equal increments to start with, adapted on the way.

    A step that diverges, or whose solution is rejected by the branch check, is retried with
    the increment multiplied by ``cut_factor``; after ``easy_iterations`` or fewer Newton
    iterations the increment grows by ``grow_factor`` (never beyond ``max_increment``).
    """

    steps: int = 10
    min_increment: float = 1e-5
    max_increment: float | None = None
    cut_factor: float = 0.5
    grow_factor: float = 1.5
    easy_iterations: int = 4
    adaptive: bool = True

    def __post_init__(self):
        if not isinstance(self.steps, int) or self.steps < 1:
            raise ValueError(f"loads.steps must be an integer >= 1, got {self.steps!r}")
        if not (0 < self.min_increment <= 1.0 / self.steps):
            raise ValueError(f"min_increment must be in (0, 1/steps], got {self.min_increment!r}")
        if not (0 < self.cut_factor < 1):
            raise ValueError(f"cut_factor must be in (0, 1), got {self.cut_factor!r}")
        if self.grow_factor < 1:
            raise ValueError(f"grow_factor must be >= 1, got {self.grow_factor!r}")
        if self.max_increment is None:
            self.max_increment = 1.0 / self.steps
        if not (0 < self.max_increment <= 1):
            raise ValueError(f"max_increment must be in (0, 1], got {self.max_increment!r}")


def check_option_names(options: dict, where: str = "solver.petsc_options") -> None:
    """ValueError unless ``options`` maps names without a leading '-' to strings or numbers."""
    for key, value in options.items():
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise ValueError(f"{where}.{key} must be a string or a number, got {value!r}")
        if not isinstance(key, str) or key.startswith("-"):
            raise ValueError(f"{where}: give option names without the leading '-', got {key!r}")


SCHEMES = ("generalized-alpha", "energy-conserving", "fd-rk45", "fd-dop853")


@dataclass(frozen=True)
class TimeSettings:
    """Time stepping: end time, (initial) step, rho_inf, optional adaptive error control."""

    t_end: float
    dt: float
    rho_inf: float = 0.9
    adaptive: bool = False
    tol: float = 1e-4
    min_dt: float | None = None
    max_dt: float | None = None
    output_every: int | None = None
    scheme: str = "generalized-alpha"

    def __post_init__(self):
        for name in ("t_end", "dt"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise ValueError(f"time.{name} must be a number > 0, got {value!r}")
        if self.dt > self.t_end:
            raise ValueError(f"time.dt ({self.dt:g}) must not exceed time.t_end ({self.t_end:g})")
        if not (isinstance(self.rho_inf, (int, float)) and 0 <= self.rho_inf <= 1):
            raise ValueError(f"time.rho_inf must be in [0, 1], got {self.rho_inf!r}")
        if not (isinstance(self.tol, (int, float)) and self.tol > 0):
            raise ValueError(f"time.tol must be > 0, got {self.tol!r}")
        every = self.output_every
        if every is not None and (isinstance(every, bool) or not isinstance(every, Integral)
                                  or every < 1):
            raise ValueError(f"time.output_every must be an integer >= 1, got {every!r}")
        if self.scheme not in SCHEMES:
            allowed = ", ".join(SCHEMES)
            raise ValueError(f"time.scheme must be one of {allowed}; got {self.scheme!r}")
        for name in ("min_dt", "max_dt"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and value > 0):
                raise ValueError(f"time.{name} must be > 0, got {value!r}")

    @property
    def output_interval(self) -> int:
        """Steps between outputs: as given, else about 200 outputs over the run."""
        if self.output_every is not None:
            return int(self.output_every)
        return max(1, math.ceil(self.t_end / self.dt / 200))

    @property
    def smallest_step(self) -> float:
        return self.min_dt if self.min_dt is not None else self.dt * 1e-4

    @property
    def largest_step(self) -> float:
        if self.max_dt is not None:
            return self.max_dt
        return self.dt * 10 if self.adaptive else self.dt


@dataclass(frozen=True)
class Damping:
    """Viscous damping c (per unit length, on u_t and v_t as in the paper's eqs. 4-5) and a
    Kelvin-Voigt retardation time eta [s]: stresses eta (EA eps_t, GA g_t, EI kappa_t)."""

    c: float = 0.0
    kelvin_voigt: float = 0.0

    def __post_init__(self):
        for name in ("c", "kelvin_voigt"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0:
                raise ValueError(f"damping.{name} must be a number >= 0, got {value!r}")
