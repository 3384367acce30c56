"""The configuration of ``fe-beam dynamic`` and ``fe-beam modes``: the [time], [initial],
[damping] and [modes] tables, time functions of the loads and of the tendons, and the parsers
`parse_dynamic` and `parse_modes`. Pure Python and numpy: `fe_beam.analyses.transient` runs them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from fe_beam.config.contact import check_motions
from fe_beam.config.finger import (
    TENDON_KEYS,
    check_tendon_inside,
    check_tendons_planar,
    parse_tendon,
)
from fe_beam.config.schema import (
    NUMBER,
    ConfigError,
    Key,
    StaticConfig,
    _wrap,
    given_max_increment,
    parse_static,
    table,
)
from fe_beam.model.settings import Damping, TimeSettings
from fe_beam.timefunctions import TimeFunctionError, parse_formula, time_function

__all__ = [
    "DAMPING_KEYS",
    "INITIAL_KEYS",
    "MODES_KEYS",
    "TIME_KEYS",
    "DynamicConfig",
    "parse_dynamic",
    "parse_modes",
]

TIME_KEYS = {
    "t_end": Key(NUMBER, None, "end time [s]"),
    "dt": Key(NUMBER, None, "time step [s] (initial step if adaptive)"),
    "rho_inf": Key(NUMBER, 0.9, "spectral radius at infinity in [0, 1]"),
    "adaptive": Key((bool,), False, "local error control"),
    "tol": Key(NUMBER, 1e-4, "local error tolerance, relative to L"),
    "min_dt": Key(NUMBER, None, "smallest step [s]"),
    "max_dt": Key(NUMBER, None, "largest step [s]"),
    "output_every": Key((int,), None, "write every n-th step (default: ~200 outputs)"),
    "scheme": Key((str,), "generalized-alpha",
                  "generalized-alpha | energy-conserving | fd-rk45 | fd-dop853"),
}
INITIAL_KEYS = {
    "from_static": Key((bool,), False, "start from the static solution under [loads]"),
    "velocity": Key((list,), None, "[u_t, v_t, theta_t] as numbers or formulas in x (spatial "
                    "rods: [u_t, v_t, w_t, omega_x, omega_y, omega_z], omega the sections' "
                    "angular velocity in world axes)"),
    "angular_velocity": Key(NUMBER + (list,), None, "rigid spin about x = 0 [rad/s] (spatial "
                            "rods: a vector [omega_x, omega_y, omega_z] about the origin, or "
                            "a number: about z)"),
}
DAMPING_KEYS = {
    "c": Key(NUMBER, 0.0, "viscous damping per unit length [N s/m^2]"),
    "kelvin_voigt": Key(NUMBER, 0.0, "Kelvin-Voigt retardation time [s]"),
}
MODES_KEYS = {
    "count": Key((int,), 6, "number of modes"),
    "prestress": Key((bool,), False, "linearise about the static state under [loads]"),
}
TIME_LOAD_KEYS = ("time_function", "time_table", "motion_function")


@dataclass(frozen=True)
class DynamicConfig:
    static: StaticConfig
    time: TimeSettings
    damping: Damping = field(default_factory=Damping)
    from_static: bool = False
    velocity: tuple | None = None
    load_function: object = None
    motion_function: object = None
    tendon_functions: tuple = ()  # f_i(t) scaling tendon i's tension (static.tendons)
    notes: tuple = ()  # what the configuration gives that the run does not use (said once)


def _split_time_loads(config: dict) -> tuple[dict, dict]:
    """Separate the time-function keys of [loads] (the statics schema does not know them)."""
    config = dict(config)
    loads = dict(config.get("loads", {}))
    timing = {key: loads.pop(key) for key in TIME_LOAD_KEYS if key in loads}
    config["loads"] = loads
    return config, timing


def _functions(timing: dict):
    try:
        formula = timing.get("time_function")
        if formula is not None and not isinstance(formula, str):
            raise TimeFunctionError(f"time_function must be a string formula in t, got {formula!r}")
        load = time_function(formula, timing.get("time_table"))
        motion = timing.get("motion_function")
        return load, (parse_formula(motion) if motion is not None else load)
    except TimeFunctionError as error:
        raise ConfigError(f"[loads] {error}") from None


def _velocity(initial: dict, spatial: bool = False):
    spin = initial["angular_velocity"]
    given = initial["velocity"]
    if spin is not None and given is not None:
        raise ConfigError("[initial] give velocity or angular_velocity, not both")
    if isinstance(spin, list):
        ok = (spatial and len(spin) == 3 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) for c in spin))
        if not ok:
            what = ("a number or a vector [omega_x, omega_y, omega_z] of numbers" if spatial
                    else "a number (a vector needs [model] kinematics = \"spatial\")")
            raise ConfigError(f"[initial] angular_velocity must be {what}, got {spin!r}")
    if spin is not None and spatial:
        # a rigid spin about the origin of the reference rod: r_t = omega x (x, 0, 0)
        wx, wy, wz = (float(c) for c in spin) if isinstance(spin, list) else (0.0, 0.0,
                                                                              float(spin))
        return lambda x: (0.0 * x[0], wz * x[0], -wy * x[0], wx + 0.0 * x[0],
                          wy + 0.0 * x[0], wz + 0.0 * x[0])
    if spin is not None:
        return lambda x: (0.0 * x[0], spin * x[0], spin + 0.0 * x[0])
    if given is None:
        return None
    names = ("[u_t, v_t, w_t, omega_x, omega_y, omega_z]" if spatial
             else "[u_t, v_t, theta_t]")
    if len(given) != (6 if spatial else 3):
        raise ConfigError(f"[initial] velocity must list {names}, got {given!r}")
    parts = []
    for value in given:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            parts.append(lambda x, c=float(value): c + 0.0 * x)
        elif isinstance(value, str):
            try:
                function = parse_formula(value, variable="x")
            except TimeFunctionError as error:
                raise ConfigError(f"[initial] velocity: {error}") from None
            parts.append(np.vectorize(function, otypes=[float]))
        else:
            raise ConfigError(
                f"[initial] velocity entries must be numbers or formulas, got {value!r}")
    return lambda x: tuple(part(x[0]) for part in parts)


def parse_dynamic(config: dict) -> DynamicConfig:
    config, timing = _split_time_loads(config)
    time_table = table(config, "time", TIME_KEYS)
    for key in ("t_end", "dt"):
        if time_table[key] is None:
            raise ConfigError(f"[time] {key} is required ({TIME_KEYS[key].doc})")
    initial = table(config, "initial", INITIAL_KEYS)
    damping = _wrap(Damping, **table(config, "damping", DAMPING_KEYS))
    settings = _wrap(TimeSettings, **time_table)
    static = parse_static(config, rigid_motion_allowed=not initial["from_static"],
                          motion_variable="t")
    if static.model.material.rho <= 0:
        raise ConfigError("[material] rho must be > 0 for dynamics")
    if static.obstacles:
        _check_contact_dynamics(static, settings, initial)
    spatial = getattr(static.model, "kinematics", "planar") == "spatial"
    if spatial:
        _check_spatial_dynamics(settings, damping, static, config)
    load, motion = _functions(timing)
    static, tendon_functions = _parse_tendons(config, static, "dynamic", load)
    if static.tendons and settings.scheme.startswith("fd-"):
        raise ConfigError(f"[time] scheme = {settings.scheme}: no [[tendons]] (use "
                          "scheme = \"generalized-alpha\" or \"energy-conserving\")")
    pulled = [t.name for t in static.tendons if t.controlled_by_pull_in]
    if pulled and settings.scheme == "energy-conserving":
        raise ConfigError(f"[[tendons]] {pulled[0]!r}: pull_in (displacement control) is not "
                          "supported with [time] scheme = \"energy-conserving\"; give its "
                          "tension, or use scheme = \"generalized-alpha\"")
    _check_tendons_pull(static.tendons, tendon_functions, settings)
    constraint = static.model.options.constraint
    if (static.tendons and settings.scheme == "generalized-alpha" and constraint != "none"
            and settings.rho_inf > 0):
        # measured: tip errors and balance residuals that fall only like dt (15% of the work
        # at dt = T1/400), because the multipliers act at t_{n+1} while the tendon's axial pull
        # acts at t_{n+1-alpha_f}
        raise ConfigError(
            f"[[tendons]] with [model] constraint = \"{constraint}\" are not supported by "
            "fe-beam dynamic with scheme = \"generalized-alpha\" (its constraints hold at "
            "t_{n+1} but the tendon pulls at t_{n+1-alpha_f}: first-order errors); use "
            "constraint = \"none\", or rho_inf = 0 (alpha_f = 0: both at t_{n+1})")
    return DynamicConfig(static, settings, damping, initial["from_static"],
                         _velocity(initial, spatial),
                         load, motion, tendon_functions, _unused_time_keys(config, settings))


def _check_contact_dynamics(static: StaticConfig, settings: TimeSettings,
                            initial: dict) -> None:
    """What fe-beam dynamic does not do with [[obstacles]]: ConfigError; and the moving
    obstacles' positions over [0, t_end]."""
    if settings.scheme != "generalized-alpha":
        raise ConfigError(f"[time] scheme = \"{settings.scheme}\" does not take [[obstacles]] "
                          "(contact in dynamics is solved with scheme = \"generalized-alpha\"); "
                          "use it, or remove [[obstacles]]")
    if initial["from_static"]:
        raise ConfigError("[initial] from_static = true does not take [[obstacles]] yet (the "
                          "static pre-state is solved without contact); start from the "
                          "undeformed rod (from_static = false), or remove [[obstacles]]")
    rough = [o.name for o in static.obstacles if o.friction > 0]
    if rough and getattr(static.model, "kinematics", "planar") == "spatial":
        raise ConfigError(f"[[obstacles]] {rough[0]!r}: friction of a spatial rod is available "
                          "in statics only (fe-beam static, finger); leave friction out for "
                          "fe-beam dynamic")
    check_motions(static.obstacles, settings.t_end, static.model)


def _check_spatial_dynamics(settings: TimeSettings, damping: Damping,
                            static: StaticConfig | None = None, config: dict | None = None) -> None:
    """What fe-beam dynamic does not do for spatial rods yet: ConfigError."""
    if settings.scheme not in ("generalized-alpha", "energy-conserving"):
        raise ConfigError(f"[time] scheme = \"{settings.scheme}\" is not available for spatial "
                          "rods ([model] kinematics = \"spatial\") yet; use scheme = "
                          "\"generalized-alpha\" or \"energy-conserving\"")
    if settings.scheme == "energy-conserving" and static is not None:
        scheme = "[time] scheme = \"energy-conserving\" for spatial rods"
        model = static.model
        if getattr(model, "structure", None) is not None:
            raise ConfigError(f"{scheme} does not take chains of rods yet; use scheme = "
                              "\"generalized-alpha\"")
        if config is not None and config.get("tendons"):
            raise ConfigError(f"{scheme} takes no [[tendons]]; use scheme = "
                              "\"generalized-alpha\"")
        for end in ("x0", "xL"):
            if any(getattr(model.supports, f"prescribed_{end}").values()):
                raise ConfigError(f"{scheme} takes no prescribed end motions ([loads] "
                                  f"prescribed_{end}, end_displacement, end_rotation); use "
                                  "scheme = \"generalized-alpha\"")
    if damping.kelvin_voigt:
        raise ConfigError("[damping] kelvin_voigt is not available for spatial rods ([model] "
                          "kinematics = \"spatial\") yet; use the viscous [damping] c")


def _unused_time_keys(config: dict, settings: TimeSettings) -> tuple:
    """Notes on [time] keys given but not used by the chosen scheme: rho_inf parametrises
    generalized-alpha only (the energy-momentum rule has no numerical dissipation; the fd-*
    schemes are scipy's Runge-Kutta integrators)."""
    given = config.get("time")
    if not isinstance(given, dict) or "rho_inf" not in given \
            or settings.scheme == "generalized-alpha":
        return ()
    why = ("the energy-momentum rule has no numerical dissipation to set"
           if settings.scheme == "energy-conserving"
           else "scipy's Runge-Kutta integrator has none")
    return (f"[time] rho_inf = {given['rho_inf']!r} is not used by scheme = "
            f"\"{settings.scheme}\" and ignored ({why}); it parametrises scheme = "
            "\"generalized-alpha\" only",)


TENDON_TIME_KEYS = ("time_function", "time_table")
TENDON_SAMPLES = 20001  # times in [0, t_end] at which a tendon's time function is checked


def _check_tendons_pull(tendons, functions, settings) -> None:
    """A cable cannot push: refuse a tendon whose tension (or pull-in) times its time function
    is negative somewhere in [0, t_end] (sampled finely and at the steps of a fixed dt), as
    fe-beam finger refuses a negative tension or pull_in."""
    t_end, dt = float(settings.t_end), float(settings.dt)
    times = np.linspace(0.0, t_end, TENDON_SAMPLES)
    if dt > 0 and t_end / dt < 1e6:
        times = np.union1d(times, np.arange(0.0, t_end + dt / 2, dt))
    for tendon, function in zip(tendons, functions, strict=True):
        value = tendon.pull_in if tendon.controlled_by_pull_in else tendon.tension
        if not value:
            continue
        for t in times:
            if float(function(t)) < 0:
                key = "pull_in" if tendon.controlled_by_pull_in else "tension"
                raise ConfigError(
                    f"[[tendons]] {tendon.name!r}: {key} x time_function/time_table is negative "
                    f"at t = {t:.4g} s (a tendon can only pull: keep the time function >= 0 on "
                    f"[0, t_end])")


def _parse_tendons(config: dict, static: StaticConfig, command: str, load_function=None):
    """[[tendons]] as fe-beam finger reads them (pull_in only for ``command`` "dynamic"), each
    with an optional time_function / time_table (default ``load_function``): (static config
    with the tendons and the pre-state's load steps, tuple of time functions)."""
    given = config.get("tendons")
    if given is None:
        return static, ()
    if not isinstance(given, list) or not given:
        raise ConfigError("[[tendons]] must list at least one tendon (write each as [[tendons]])")
    length = static.model.length
    tendons, functions, steps = [], [], [static.stepping.steps]
    for index, entry in enumerate(given):
        if not isinstance(entry, dict):
            raise ConfigError(f"[[tendons]] #{index + 1} must be a table")
        entry = dict(entry)
        allowed = list(TENDON_KEYS) + list(TENDON_TIME_KEYS)
        unknown = [key for key in entry if key not in allowed]
        if unknown:
            label = entry.get("name") if isinstance(entry.get("name"), str) else f"#{index + 1}"
            raise ConfigError(f"[[tendons]] {label!r}: unknown key {unknown[0]!r}; allowed: "
                              f"{', '.join(allowed)}")
        timing = {key: entry.pop(key) for key in TENDON_TIME_KEYS if key in entry}
        tendon, tendon_steps = parse_tendon(index, entry, length)
        check_tendon_inside(tendon, static.model.section, length, index)
        check_tendons_planar(config, [tendon], index)
        where = f"[[tendons]] {tendon.name!r}"
        if tendon.controlled_by_pull_in and command != "dynamic":
            raise ConfigError(
                f"{where}: pull_in (displacement control) is not supported by fe-beam {command}; "
                "give its tension (fe-beam finger solves pull-in control in statics)")
        if tendon_steps is not None:
            steps.append(tendon_steps)
        formula = timing.get("time_function")
        try:
            if formula is not None and not isinstance(formula, str):
                raise TimeFunctionError(
                    f"time_function must be a string formula in t, got {formula!r}")
            if timing:
                functions.append(time_function(formula, timing.get("time_table")))
            else:
                functions.append(load_function or time_function())
        except TimeFunctionError as error:
            key = "time_function" if formula is not None else "time_table"
            text = str(error)
            raise ConfigError(f"{where} {text}" if text.startswith(key) else
                              f"{where} {key}: {text}") from None
        tendons.append(tendon)
    count = max(steps)
    if count < 1:
        raise ConfigError(f"[[tendons]] steps must be >= 1, got {count}")
    stepping = replace(static.stepping, steps=count,
                       max_increment=given_max_increment(config, count),
                       min_increment=min(static.stepping.min_increment, 1.0 / count))
    return replace(static, tendons=tuple(tendons), stepping=stepping), tuple(functions)


def parse_modes(config: dict) -> tuple[StaticConfig, dict]:
    config, _ = _split_time_loads(config)
    modes = table(config, "modes", MODES_KEYS)
    if modes["count"] < 1:
        raise ConfigError(f"[modes] count must be >= 1, got {modes['count']}")
    static = parse_static(config, rigid_motion_allowed=not modes["prestress"])
    # tendons pull on the pre-state (prestress = true) at their full tension; a tendon's time
    # function is irrelevant here (checked all the same)
    static, _ = _parse_tendons(config, static, "modes")
    if static.model.material.rho <= 0:
        raise ConfigError("[material] rho must be > 0 for a modal analysis")
    return static, modes
