"""The 3D hyperelastic law of a configuration table (``[solid]`` for the 3D solid, ``[model]``
for the rod's ``law = "hyperelastic"``): the same keys, defaults, presets and checks for both.

Constants default to the small-strain match of ``[material]`` E, nu, or come from a silicone
``preset``; explicit constants override either (see `hyperelastic_law`).
"""

from __future__ import annotations

from fe_beam.config.keys import NUMBER, SCHEMA, Key, table
from fe_beam.errors import ConfigError
from fe_beam.model.hyperelastic import LAWS, SILICONE_PRESETS, VOLUMETRIC_LAWS, HyperelasticLaw

__all__ = ["LAW_CONSTANTS", "MATERIALS", "MATERIAL_KEYS", "hyperelastic_law"]

#: config name -> key of `fe_beam.model.hyperelastic.LAWS`
MATERIALS = {
    "neo-hookean": "neo_hookean",
    "mooney-rivlin": "mooney_rivlin",
    "yeoh": "yeoh",
    "svk": "saint_venant_kirchhoff",
}
#: the constants of each law that the table may set explicitly (besides ``kappa``)
LAW_CONSTANTS = {
    "neo-hookean": ("mu",),
    "mooney-rivlin": ("c10", "c01"),
    "yeoh": ("c10", "c20", "c30"),
    "svk": ("mu",),
}
MATERIAL_KEYS = SCHEMA["material"] | {
    "E": Key(NUMBER, None, "Young's modulus [Pa] (not with a preset)")
}


def _positive(where: str, value, minimum: float = 0.0, strict: bool = True) -> float:
    ok = value > minimum if strict else value >= minimum
    if not ok:
        relation = ">" if strict else ">="
        raise ConfigError(f"{where} must be {relation} {minimum:g}; got {value!r}")
    return float(value)


def hyperelastic_law(raw: dict, values: dict, table_name: str = "solid",
                     purpose: str = "the 3D solid") -> HyperelasticLaw:
    """The 3D law of ``[<table_name>]`` (its validated ``values``).

    Constants default to the small-strain match of ``[material]`` E, nu (mu = E / (2 (1 + nu));
    Mooney-Rivlin C10 = C01 = mu / 4; Yeoh C10 = mu / 2), or come from a silicone ``preset``;
    explicit constants override either; the bulk modulus is kappa = 2 mu0 (1 + nu) /
    (3 (1 - 2 nu)) of the law's small-strain shear modulus mu0 unless ``kappa`` is given.
    Messages name ``[<table_name>]``; ``purpose`` says what needs nu (e.g. "the 3D solid").
    """
    solid = values
    where = f"[{table_name}]"
    name = solid["material"]
    if name not in MATERIALS:
        raise ConfigError(
            f"{where} material must be one of {', '.join(MATERIALS)}; got {name!r}"
        )
    if solid["volumetric"] not in VOLUMETRIC_LAWS:
        raise ConfigError(
            f"{where} volumetric must be one of {', '.join(VOLUMETRIC_LAWS)}; "
            f"got {solid['volumetric']!r}"
        )
    allowed = LAW_CONSTANTS[name]
    for key in ("mu", "c10", "c01", "c20", "c30"):
        if solid[key] is not None and key not in allowed:
            raise ConfigError(
                f"{where} {key} is not a constant of {name} (its constants: "
                f"{', '.join(allowed)}, kappa)"
            )
    for key in ("mu", "kappa") + (("c10",) if name == "yeoh" else ()):
        if solid[key] is not None:
            _positive(f"{where} {key}", solid[key])
    material = table(raw, "material", MATERIAL_KEYS)
    E, nu, G = material["E"], material["nu"], material["G"]
    if nu is not None and G is not None:
        raise ConfigError("[material] give nu or G, not both")
    if E is not None:
        _positive("[material] E", E)
    if G is not None:
        _positive("[material] G", G)
        if E is None:
            raise ConfigError("[material] G needs E (or give nu)")
        nu = E / (2 * G) - 1
    if nu is not None and not (-1 < nu < 0.5):
        raise ConfigError(f"[material] nu must be in (-1, 0.5); got {nu!r}")
    law_key = MATERIALS[name]
    preset = solid["preset"]
    if preset is not None:
        if preset not in SILICONE_PRESETS:
            raise ConfigError(
                f"{where} preset must be one of {', '.join(sorted(SILICONE_PRESETS))}; "
                f"got {preset!r}"
            )
        laws = SILICONE_PRESETS[preset].laws
        if law_key not in laws:
            names = [n for n, k in MATERIALS.items() if k in laws]
            raise ConfigError(
                f"{where} preset {preset!r} has constants for material = {', '.join(names)}; "
                f"got material = {name!r}"
            )
        if E is not None:
            raise ConfigError(
                f"[material] E = {E!r} conflicts with {where} preset = {preset!r} (which sets the "
                "stiffness); remove one of them"
            )
        coefficients = dict(laws[law_key])
        if name == "neo-hookean":
            coefficients = {"mu": 2 * coefficients["c10"]}
        if nu is None and solid["kappa"] is None:
            raise ConfigError(
                f"{where} preset = {preset!r} needs the compressibility: [material] nu or "
                f"{where} kappa"
            )
    else:
        if E is None:
            raise ConfigError("[material] E is required (Young's modulus [Pa]) unless "
                              f"{where} preset is given")
        if nu is None:
            raise ConfigError(f"[material] nu (or G) is required for {purpose}")
        mu = E / (2 * (1 + nu))
        coefficients = {
            "neo-hookean": {"mu": mu},
            "mooney-rivlin": {"c10": mu / 4, "c01": mu / 4},
            "yeoh": {"c10": mu / 2, "c20": 0.0, "c30": 0.0},
            "svk": {"mu": mu},
        }[name]
    coefficients |= {k: float(solid[k]) for k in allowed if solid[k] is not None}
    mu0 = {
        "neo-hookean": lambda c: c["mu"],
        "mooney-rivlin": lambda c: 2 * (c["c10"] + c["c01"]),
        "yeoh": lambda c: 2 * c["c10"],
        "svk": lambda c: c["mu"],
    }[name](coefficients)
    if not mu0 > 0:
        raise ConfigError(
            f"{where} the small-strain shear modulus of {name} must be > 0; got {mu0!r} "
            f"from {coefficients}"
        )
    if solid["kappa"] is not None:
        kappa = float(solid["kappa"])
    else:
        kappa = 2 * mu0 * (1 + nu) / (3 * (1 - 2 * nu))
    try:
        return LAWS[law_key](kappa=kappa, volumetric=solid["volumetric"], **coefficients)
    except ValueError as error:
        raise ConfigError(f"{where} {error}") from None
