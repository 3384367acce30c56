"""A structure of rods, joints and rigid bodies (MODEL.md section 9), as validated data.

This slice supports planar serial chains of rods joined rigidly end to end (a frame such as
Lee's), with fixed bodies clamping a chain end. The chain is one interval mesh whose coordinate
s is the arc length along the chain (the rods laid end to end in chain order); each rod has a
reference angle theta0 (its direction), constant along it. A rod whose joints make the chain
run from its end to its start is traversed reversed (theta0 = its direction + pi, its point
loads mapped to s). `Structure.chain` holds the resolved order.

Pure Python: no numpy, no finite-element code. Mistakes are ValueError with one sentence naming
the table and key (the config layer turns them into `fe_beam.errors.ConfigError`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from fe_beam.model.beam import SUPPORT_KINDS

__all__ = ["Body", "ChainSegment", "Joint", "JOINT_KINDS", "Rod", "Structure", "Tie",
           "SUPPORTED_JOINT_KINDS"]

#: the joint kinds of the interface (issue 29) and those this slice solves
JOINT_KINDS = ("rigid", "pin", "ball", "hinge")
SUPPORTED_JOINT_KINDS = ("rigid", "pin", "ball")
#: the components a joint kind ties (planar, spatial): the others stay free on each side
TIED = {"rigid": (("u", "v", "theta"), ("u", "v", "w", "theta_x", "theta_y", "theta_z")),
        "pin": (("u", "v"), None), "ball": (None, ("u", "v", "w"))}
PLANAR_SUPPORTS = {"clamped": ("u", "v", "theta"), "pinned": ("u", "v"), "roller": ("v",),
                   "free": ()}
#: joined ends must coincide to this fraction of the longest rod (round-off of the inputs)
COINCIDENCE = 1e-9
ENDS = ("start", "end")


@dataclass(frozen=True)
class Rod:
    """One rod's reference placement: the straight axis from ``start`` along the unit
    ``direction`` over ``length``; its mesh, end supports ({"start" | "end": kind}) and point
    loads (rows [x, Px, Py] / [x, M], x the arc length from the rod's start)."""

    name: str
    start: tuple[float, float]
    direction: tuple[float, float]
    length: float
    elements: int
    degree: int
    supports: dict = field(default_factory=dict)
    point_forces: tuple = ()
    point_moments: tuple = ()
    #: the rod's section dimensions ((name, value), ...) and material ((E, G)) when a rod of
    #: the structure has its own (every rod then carries its values); () : the top level's
    section: tuple = ()
    material: tuple = ()
    #: spatial: the section's d2 at the start (None: the default, `frame`)
    normal: tuple | None = None
    #: planar: the reference axis's constant curvature [1/m] (an arc turning left; 0 straight)
    curvature: float = 0.0

    def __post_init__(self):
        where = f"[[rods]] '{self.name}'"
        ok = (isinstance(self.curvature, (int, float)) and not isinstance(self.curvature, bool)
              and math.isfinite(self.curvature))
        if not ok:
            raise ValueError(f"{where} curvature must be a number [1/m]; got {self.curvature!r}")
        object.__setattr__(self, "curvature", float(self.curvature))
        if not isinstance(self.name, str) or not self.name or ":" in self.name:
            raise ValueError(f"[[rods]] name must be a non-empty string without ':'; got "
                             f"{self.name!r}")
        size = len(self.start) if isinstance(self.start, (list, tuple)) \
            and len(self.start) in (2, 3) else 2
        for key in ("start", "direction"):
            value = getattr(self, key)
            ok = (isinstance(value, (list, tuple)) and len(value) == size
                  and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                          and math.isfinite(c) for c in value))
            if not ok:
                form = "a pair of numbers [x, y]" if size == 2 else "three numbers [x, y, z]"
                raise ValueError(f"{where} {key} must be {form} (as start); got {value!r}")
            object.__setattr__(self, key, tuple(float(c) for c in value))
        norm = math.sqrt(sum(c * c for c in self.direction))
        if not abs(norm - 1.0) <= 1e-9:
            raise ValueError(f"{where} direction must be a unit vector; got {list(self.direction)}"
                             f" of length {norm:.12g}")
        if self.normal is not None:
            value = self.normal
            ok = (size == 3 and isinstance(value, (list, tuple)) and len(value) == 3
                  and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                          and math.isfinite(c) for c in value))
            if not ok:
                raise ValueError(f"{where} normal must be three numbers [x, y, z] (a spatial "
                                 f"rod's d2); got {value!r}")
            object.__setattr__(self, "normal", tuple(float(c) for c in value))
            length = math.sqrt(sum(c * c for c in self.normal))
            dot = sum(a * b for a, b in zip(self.normal, self.direction, strict=True))
            if not (abs(length - 1.0) <= 1e-9 and abs(dot) <= 1e-9):
                raise ValueError(f"{where} normal must be a unit vector orthogonal to direction;"
                                 f" got {list(self.normal)} of length {length:.6g}, "
                                 f"normal . direction = {dot:.3g}")
        ok = (isinstance(self.length, (int, float)) and not isinstance(self.length, bool)
              and math.isfinite(self.length) and self.length > 0)
        if not ok:
            raise ValueError(f"{where} length must be a number > 0; got {self.length!r}")
        for end, kind in self.supports.items():
            if self.dim == 3 and isinstance(kind, tuple):
                continue  # spatial components, checked with the chain's end
            if kind not in SUPPORT_KINDS:
                key = {"start": "x0", "end": "xL"}.get(end, end)  # as the user wrote it
                raise ValueError(f"{where} supports.{key} must be one of "
                                 f"{', '.join(SUPPORT_KINDS)}; got {kind!r}")
        for name, rows in (("point_forces", self.point_forces),
                           ("point_moments", self.point_moments)):
            for index, row in enumerate(rows):
                if not 0 <= row[0] <= self.length:
                    raise ValueError(f"{where} loads.{name}[{index}]: x = {row[0]!r} is outside "
                                     f"the rod (0 <= x <= length = {self.length!r})")

    @property
    def dim(self) -> int:
        """2 (planar) or 3 (spatial)."""
        return len(self.start)

    @property
    def frame(self) -> tuple:
        """Spatial: the reference directors (d1, d2, d3) (world 3-vectors, the columns of R0):
        d1 = direction, d2 = normal or by default e3 x d1 normalised (the planar convention:
        d1 turned by +90 degrees about z; d1 x e1 normalised when d1 is along z), d3 = d1 x d2."""
        d1 = self.direction
        if self.normal is not None:
            d2 = self.normal
        else:
            d2 = _cross((0.0, 0.0, 1.0), d1)
            if math.sqrt(sum(c * c for c in d2)) < 1e-6:
                d2 = _cross(d1, (1.0, 0.0, 0.0))
            n = math.sqrt(sum(c * c for c in d2))
            d2 = tuple(c / n for c in d2)
        return (tuple(d1), tuple(d2), _cross(d1, d2))

    @property
    def angle(self) -> float:
        """The direction's angle to the x axis [rad]."""
        return math.atan2(self.direction[1], self.direction[0])

    def point(self, end: str) -> tuple:
        """The reference position of the rod's "start" or "end"."""
        if end == "start":
            return self.start
        if self.curvature:
            return arc_point(self.start, self.angle, self.curvature, self.length)
        return tuple(x + self.length * d for x, d in zip(self.start, self.direction,
                                                         strict=True))


def arc_point(origin, angle: float, curvature: float, t: float) -> tuple:
    """The point at arc length t along a planar axis from ``origin`` leaving at ``angle`` with
    constant ``curvature`` (a straight line for 0)."""
    if abs(curvature * t) < 1e-8:
        along, across = t, 0.5 * curvature * t * t
    else:
        along = math.sin(curvature * t) / curvature
        across = (1.0 - math.cos(curvature * t)) / curvature
    c, s = math.cos(angle), math.sin(angle)
    return (origin[0] + c * along - s * across, origin[1] + s * along + c * across)


def _cross(a, b) -> tuple:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@dataclass(frozen=True)
class Joint:
    """A joint of ``kind`` between the ends named in ``at`` ("rod:start", "rod:end",
    "body:NAME")."""

    name: str
    kind: str
    at: tuple[str, ...]

    def __post_init__(self):
        where = f"[[joints]] '{self.name}'"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"[[joints]] name must be a non-empty string; got {self.name!r}")
        if self.kind not in JOINT_KINDS:
            raise ValueError(f"{where} kind must be one of {', '.join(JOINT_KINDS)}; got "
                             f"{self.kind!r}")
        if self.kind not in SUPPORTED_JOINT_KINDS:
            raise ValueError(f"{where} kind = {self.kind!r} is not supported yet (this version "
                             "joins rods with kind = \"rigid\", \"pin\" (planar) or \"ball\" "
                             "(spatial))")
        if not (isinstance(self.at, (list, tuple)) and all(isinstance(a, str) for a in self.at)):
            raise ValueError(f"{where} at must be a list of \"rod:start\", \"rod:end\" or "
                             f"\"body:NAME\"; got {self.at!r}")
        object.__setattr__(self, "at", tuple(self.at))
        if len(self.at) < 2:
            raise ValueError(f"{where} at must name two or more ends (\"rod:start\", "
                             f"\"rod:end\", \"body:NAME\"); got {list(self.at)}")
        for entry in self.at:
            head, _, tail = entry.partition(":")
            if not head or not tail:
                raise ValueError(f"{where} at entry {entry!r} must be \"rod:start\", "
                                 "\"rod:end\" or \"body:NAME\"")


@dataclass(frozen=True)
class Body:
    """A rigid body at ``position``: ``fixed`` = true (it clamps the rod end joined to it) or
    false (planar: a free body, its pose (x, y, theta) unknowns of the solve, the rod ends
    joined rigidly to it at its reference point; dead ``force`` [Fx, Fy] and ``moment`` M on
    it)."""

    name: str
    position: tuple[float, float]
    fixed: object = True
    force: tuple = ()
    moment: float = 0.0

    def __post_init__(self):
        where = f"[[bodies]] '{self.name}'"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"[[bodies]] name must be a non-empty string; got {self.name!r}")
        value = self.position
        ok = (isinstance(value, (list, tuple)) and len(value) in (2, 3)
              and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value))
        if not ok:
            raise ValueError(f"{where} position must be [x, y] (planar) or [x, y, z] (spatial); "
                             f"got {value!r}")
        object.__setattr__(self, "position", tuple(float(c) for c in value))
        if self.fixed is not True and self.fixed is not False:
            raise ValueError(f"{where} fixed = {self.fixed!r}: partly fixed bodies are not "
                             "supported yet (give fixed = true or false)")
        force = tuple(self.force or ())
        ok = (len(force) in (0, len(self.position))
              and all(isinstance(c, (int, float)) and not isinstance(c, bool)
                      and math.isfinite(c) for c in force))
        if not ok:
            raise ValueError(f"{where} force must be [Fx, Fy] (numbers, world axes); got "
                             f"{self.force!r}")
        object.__setattr__(self, "force", tuple(float(c) for c in force))
        ok = (isinstance(self.moment, (int, float)) and not isinstance(self.moment, bool)
              and math.isfinite(self.moment))
        if not ok:
            raise ValueError(f"{where} moment must be a number M (planar); got {self.moment!r}")
        object.__setattr__(self, "moment", float(self.moment))
        if self.fixed and (any(self.force) or self.moment):
            raise ValueError(f"{where} force, moment: a fixed body takes no loads (they would "
                             "be the support's); give fixed = false or load a rod")
        if not self.fixed and len(self.position) == 3:
            raise ValueError(f"{where} fixed = false: free bodies are planar in this version "
                             "(a spatial body must be fixed = true)")


@dataclass(frozen=True)
class ChainSegment:
    """Rod ``rod`` (index in `Structure.rods`) on the chain's [s0, s0 + length], traversed
    from its start (``reversed`` False) or from its end; ``theta0`` the reference angle of the
    chain's tangent at s0, ``origin`` the reference point at s0."""

    rod: int
    reversed: bool
    s0: float
    length: float
    theta0: float
    origin: tuple
    #: spatial: the reference directors (d1, d2, d3) of the chain on it (d1 the chain's
    #: tangent; a reversed rod's frame turned by pi about its d3); None: planar
    frame: tuple | None = None
    #: planar: the curvature of the chain's reference axis on it (a reversed arc's turned sign)
    curvature: float = 0.0

    @property
    def tangent(self) -> tuple:
        """The chain's reference tangent at s0 (world)."""
        if self.frame is not None:
            return self.frame[0]
        return (math.cos(self.theta0), math.sin(self.theta0))

    def angle_at(self, s: float) -> float:
        """Planar: the reference angle of the chain's tangent at s."""
        return self.theta0 + self.curvature * (s - self.s0)

    def s_of(self, x: float) -> float:
        """The chain coordinate of the rod's own arc length x (from its start)."""
        return self.s0 + (self.length - x if self.reversed else x)


@dataclass(frozen=True)
class ChainJoint:
    """A rigid joint between two rods at chain coordinate ``s`` (a shared mesh vertex);
    ``first_before``: the first end of ``at`` lies on the chain before s (the reported force
    is on that end)."""

    name: str
    s: float
    first_before: bool
    segment: int  # the chain segment that ends at s


@dataclass(frozen=True)
class Tie:
    """A joint whose ends lie on separate mesh vertices (a pin, a ball, a T junction, the
    closure of a loop): ``ends`` ((chain coordinate, "rod:end"), ...) in the order of ``at``,
    ``components`` the tied unknowns (equal at every end; those a support holds are held at
    every end instead)."""

    name: str
    kind: str
    ends: tuple
    components: tuple


@dataclass(frozen=True)
class Structure:
    """Rods, joints and bodies, validated into pieces: serial chains of rods joined rigidly
    (shared mesh vertices) laid one after the other on the mesh coordinate with a gap between
    them (`chain`, `joints_on_chain`, `pieces`), and the other joints as ties between the
    pieces' end vertices (`ties`). A serial chain is one piece and no tie."""

    rods: tuple[Rod, ...]
    joints: tuple[Joint, ...] = ()
    bodies: tuple[Body, ...] = ()
    chain: tuple[ChainSegment, ...] = field(init=False, default=())
    joints_on_chain: tuple[ChainJoint, ...] = field(init=False, default=())
    #: {"x0" | "xL": support kind or held components} of the mesh's two ends
    end_supports: dict = field(init=False, default_factory=dict)
    #: ((joint name, chain end "x0" | "xL", the rod end is named first), ...): rod ends
    #: joined to a fixed body
    body_joints: tuple = field(init=False, default=())
    #: the joints that are not shared vertices (`Tie`)
    ties: tuple = field(init=False, default=())
    #: ((s, held components, "rod:end"), ...): supported piece ends inside the mesh
    extra_supports: tuple = field(init=False, default=())
    #: ((s_start, s_end), ...): the pieces on the mesh coordinate
    pieces: tuple = field(init=False, default=())
    #: ((joint name, s, the rod end is named first), ...): fixed bodies at ends inside the mesh
    inner_body_joints: tuple = field(init=False, default=())
    #: free bodies: (Tie(name = the body's, kind "body", its rod ends), ...)
    body_ties: tuple = field(init=False, default=())
    #: ((joint name, s of its rod end, the rod end is named first, body name), ...): joints of
    #: rod ends to free bodies
    free_body_joints: tuple = field(init=False, default=())

    def __post_init__(self):
        object.__setattr__(self, "rods", tuple(self.rods))
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "bodies", tuple(self.bodies))
        if not self.rods:
            raise ValueError("[[rods]] needs at least one rod")
        for table, items in (("rods", self.rods), ("joints", self.joints),
                             ("bodies", self.bodies)):
            names = [item.name for item in items]
            duplicate = next((n for n in names if names.count(n) > 1), None)
            if duplicate is not None:
                raise ValueError(f"[[{table}]] name {duplicate!r} is given twice; names must be "
                                 "unique")
        dims = {rod.dim for rod in self.rods} | {len(body.position) for body in self.bodies}
        if len(dims) > 1:
            raise ValueError("[[rods]] start, direction and [[bodies]] position must all be "
                             "planar [x, y] or all spatial [x, y, z]")
        degrees = {rod.degree for rod in self.rods}
        if len(degrees) > 1:
            raise ValueError("[[rods]] mesh.degree differs between rods; this version needs "
                             "one degree for every rod")
        for rod in self.rods:
            if rod.curvature and rod.dim == 3:
                raise ValueError(f"[[rods]] '{rod.name}' curvature is planar (a spatial rod's "
                                 "reference axis is straight in this version)")
        self._resolve()

    # --- the pieces ---------------------------------------------------------------------------
    @property
    def length(self) -> float:
        """The extent of the mesh coordinate: the rods' lengths and the gaps between pieces."""
        if self.pieces:
            return self.pieces[-1][1]
        return sum(rod.length for rod in self.rods)

    @property
    def dim(self) -> int:
        """2 (planar) or 3 (spatial)."""
        return self.rods[0].dim

    @property
    def tied(self) -> bool:
        """Some joint is a tie (the mesh has several pieces, a loop or a free body)."""
        return bool(self.ties) or bool(self.body_ties) or len(self.pieces) > 1

    def body(self, name: str) -> Body:
        return next(b for b in self.bodies if b.name == name)

    def rod_index(self, name: str) -> int:
        return next(i for i, rod in enumerate(self.rods) if rod.name == name)

    def _end(self, joint: Joint, entry: str):
        """(kind, name, end) of one ``at`` entry, checked."""
        head, _, tail = entry.partition(":")
        where = f"[[joints]] '{joint.name}' at"
        if head == "body":
            if tail not in {b.name for b in self.bodies}:
                raise ValueError(f"{where}: unknown body {tail!r} (bodies: "
                                 f"{', '.join(b.name for b in self.bodies) or 'none'})")
            return "body", tail, None
        if head not in {r.name for r in self.rods}:
            raise ValueError(f"{where}: unknown rod {head!r} in {entry!r} (rods: "
                             f"{', '.join(r.name for r in self.rods)})")
        if tail not in ENDS:
            raise ValueError(f"{where}: {entry!r} names no end of rod {head!r}; use "
                             f"\"{head}:start\" or \"{head}:end\"")
        return "rod", head, tail

    def _resolve(self) -> None:
        scale = max(rod.length for rod in self.rods)
        planar = self.dim == 2
        used: dict[tuple[str, str], str] = {}  # rod end -> joint
        links = []  # candidate shared vertices: (joint, (rod, end), (rod, end))
        ties = []  # (joint, [(rod, end), ...])
        clamped: dict[tuple[str, str], tuple] = {}  # rod end -> (body, joint, rod first)
        carried: dict[str, list] = {}  # free body -> [(rod end, joint, rod first), ...]
        for joint in self.joints:
            where = f"[[joints]] '{joint.name}'"
            if joint.kind == "pin" and not planar:
                raise ValueError(f"{where} kind = \"pin\" is the planar hinge; a spatial model "
                                 "takes \"ball\" (equal positions) or \"rigid\"")
            if joint.kind == "ball" and planar:
                raise ValueError(f"{where} kind = \"ball\" is spatial; a planar model takes "
                                 "\"pin\" (equal positions, free rotations) or \"rigid\"")
            ends = [self._end(joint, entry) for entry in joint.at]
            rods = [(name, end) for kind, name, end in ends if kind == "rod"]
            bodies = [name for kind, name, _ in ends if kind == "body"]
            for key in rods:
                if key in used or len(set(rods)) != len(rods):
                    raise ValueError(
                        f"{where} at: {key[0]}:{key[1]} is already joined (by "
                        f"'{used.get(key, joint.name)}'); name every end meeting at a point in "
                        "one joint")
                used[key] = joint.name
            if bodies and (len(rods) != 1 or len(bodies) > 1 or joint.kind != "rigid"):
                raise ValueError(f"{where} at: {len(rods)} rod ends and {len(bodies)} bodies "
                                 f"of kind {joint.kind!r}; this version joins one rod end "
                                 "rigidly to one fixed body (a pinned end: supports)")
            if not rods:
                raise ValueError(f"{where} at names no rod end")
            points = [self.rods[self.rod_index(n)].point(e) for n, e in rods]
            points += [next(b for b in self.bodies if b.name == n).position for n in bodies]
            distance = max(math.dist(points[0], p) for p in points[1:])
            if distance > COINCIDENCE * scale:
                raise ValueError(f"[[joints]] '{joint.name}' at: the ends do not coincide in "
                                 f"the reference geometry: {', '.join(joint.at)} are "
                                 f"{distance:.6g} m apart")
            if bodies and not self.body(bodies[0]).fixed:  # a free body: a tie of its ends
                carried.setdefault(bodies[0], []).append(
                    (rods[0], joint.name, joint.at[0].partition(":")[0] != "body"))
            elif bodies:
                clamped[rods[0]] = (bodies[0], joint.name,
                                    joint.at[0].partition(":")[0] != "body")
            elif joint.kind == "rigid" and len(rods) == 2 and rods[0][0] != rods[1][0]:
                links.append((joint, rods[0], rods[1]))
            else:
                ties.append((joint, rods))
        joined_bodies = {body for body, _, _ in clamped.values()} | set(carried)
        for body in self.bodies:
            if body.name not in joined_bodies:
                raise ValueError(f"[[bodies]] '{body.name}' is joined to no rod end; name it in "
                                 "a [[joints]] at (e.g. at = [\"rod:start\", "
                                 f"\"body:{body.name}\"]) or remove it")
        for (name, end), (body, _, _) in clamped.items():
            rod = self.rods[self.rod_index(name)]
            if end in rod.supports:
                raise ValueError(f"[[rods]] '{name}' supports.{'x0' if end == 'start' else 'xL'}"
                                 f" and the fixed body '{body}' both hold its {end}; give one")
        # shared vertices: the rigid links that close no loop (the others are ties)
        root = {rod.name: rod.name for rod in self.rods}

        def find(n):
            while root[n] != n:
                n = root[n]
            return n

        accepted = []
        for joint, a, b in links:
            ra, rb = find(a[0]), find(b[0])
            if ra == rb:
                ties.append((joint, [a, b]))
                continue
            root[ra] = rb
            accepted.append((joint, a, b))
        self._order(accepted, clamped, ties, carried)

    def _held(self, key, clamped) -> tuple:
        """The components a rod end's own support (or fixed body) holds."""
        name, end = key
        rod = self.rods[self.rod_index(name)]
        kind = "clamped" if key in clamped else rod.supports.get(end, "free")
        if isinstance(kind, tuple):
            return kind
        if self.dim == 2:
            return PLANAR_SUPPORTS[kind]
        if kind == "clamped":
            return TIED["rigid"][1]
        if kind == "free":
            return ()
        if kind == "pinned":
            axis = [i for i, c in enumerate(rod.direction) if abs(abs(c) - 1.0) <= 1e-12]
            if not axis:
                raise ValueError(f"[[rods]] '{name}' supports.{'x0' if end == 'start' else 'xL'}"
                                 " = \"pinned\" holds the twist about the rod's direction, which "
                                 "is not a coordinate axis here; give the held components as a "
                                 "list (e.g. [\"u\", \"v\", \"w\", \"theta_x\"])")
            return ("u", "v", "w", ("theta_x", "theta_y", "theta_z")[axis[0]])
        raise ValueError(f"[[rods]] '{name}' supports.{'x0' if end == 'start' else 'xL'} = "
                         f"\"{kind}\" is planar; a spatial chain takes clamped, pinned, free "
                         "or a list of components from u, v, w, theta_x, theta_y, theta_z")

    def _order(self, links, clamped, ties, carried) -> None:
        names = [rod.name for rod in self.rods]
        neighbours: dict[str, list] = {n: [] for n in names}
        for joint, a, b in links:
            neighbours[a[0]].append((joint, a, b))
            neighbours[b[0]].append((joint, b, a))

        def held(start):
            rod = self.rods[self.rod_index(start[0])]
            return start in clamped or rod.supports.get(start[1], "free") != "free"

        # the pieces, each from one of its two free ends (a held one if there is: the single
        # rod's convention, x0 supported), in the order of their first rod in [[rods]]
        order_all, visited = [], set()
        for n in names:
            if n in visited:
                continue
            members, stack = set(), [n]
            while stack:
                m = stack.pop()
                if m in members:
                    continue
                members.add(m)
                stack += [other[0] for _, _, other in neighbours[m]]
            starts = []
            for m in names:
                if m not in members:
                    continue
                if not neighbours[m]:
                    starts += [(m, "start"), (m, "end")]
                elif len(neighbours[m]) == 1:
                    joined = neighbours[m][0][1][1]
                    starts.append((m, "end" if joined == "start" else "start"))
            first, first_end = next((c for c in starts if held(c)), starts[0])
            current, entered = first, None
            while current is not None:
                visited.add(current)
                if entered is None:
                    start_end = first_end
                else:
                    start_end = next(link for link in neighbours[current]
                                     if link[0].name == entered.name)[1][1]
                order_all.append((current, start_end == "end"))
                nxt = None
                for joint, _mine, other in neighbours[current]:
                    if other[0] not in visited:
                        nxt, entered = other[0], joint
                current = nxt
        # piece numbers: a new piece where the walk restarted
        piece_of, count, previous = [], -1, None
        for name, _flipped in order_all:
            linked = previous is not None and any(o[0] == previous for _, _, o in
                                                  neighbours[name])
            count += 0 if linked else 1
            piece_of.append(count)
            previous = name
        gap = max(rod.length for rod in self.rods)
        segments, s, pieces, piece_start = [], 0.0, [], 0.0
        for k, (name, flipped) in enumerate(order_all):
            if k > 0 and piece_of[k] != piece_of[k - 1]:
                pieces.append((piece_start, s))
                s += gap
                piece_start = s
            rod = self.rods[self.rod_index(name)]
            angle = rod.angle + (math.pi if flipped else 0.0)
            curvature = -rod.curvature if flipped else rod.curvature
            if flipped:
                angle += rod.curvature * rod.length
            origin = rod.point("end" if flipped else "start")
            frame = None
            if rod.dim == 3:
                d1, d2, d3 = rod.frame
                frame = ((tuple(-c for c in d1), tuple(-c for c in d2), d3) if flipped
                         else (d1, d2, d3))
                angle = 0.0
            segments.append(ChainSegment(self.rod_index(name), flipped, s, rod.length, angle,
                                         origin, frame, curvature))
            s += rod.length
        pieces.append((piece_start, s))
        object.__setattr__(self, "chain", tuple(segments))
        object.__setattr__(self, "pieces", tuple(pieces))
        joints = []
        for k in range(len(segments) - 1):
            if piece_of[k] != piece_of[k + 1]:
                continue
            a, b = self.rods[segments[k].rod].name, self.rods[segments[k + 1].rod].name
            joint, mine, other = next(link for link in neighbours[a] if link[2][0] == b)
            first_before = joint.at[0].partition(":")[0] == a
            joints.append(ChainJoint(joint.name, segments[k + 1].s0, first_before, k))
        object.__setattr__(self, "joints_on_chain", tuple(joints))
        self._supports_and_ties(clamped, ties, carried)

    def end_s(self, name: str, end: str) -> float:
        """The mesh coordinate of a rod's "start" or "end"."""
        index = self.rod_index(name)
        segment = next(seg for seg in self.chain if seg.rod == index)
        at_s0 = (end == "start") != segment.reversed
        return segment.s0 if at_s0 else segment.s0 + segment.length

    def _supports_and_ties(self, clamped, ties, carried) -> None:
        ends = [(rod.name, e) for rod in self.rods for e in ENDS]
        held = {key: set(self._held(key, clamped)) for key in ends}
        dim_index = 0 if self.dim == 2 else 1
        resolved = []
        for joint, rods in ties:
            tied = TIED[joint.kind][dim_index]
            common = set().union(*(held[key] for key in rods)) & set(tied)
            for key in rods:
                held[key] |= common
            components = tuple(c for c in tied if c not in common)
            resolved.append(Tie(joint.name, joint.kind,
                                tuple((self.end_s(*key), f"{key[0]}:{key[1]}") for key in rods),
                                components))
        object.__setattr__(self, "ties", tuple(resolved))
        body_ties, free_joints = [], []
        for body, entries in carried.items():
            for key, _, _ in entries:
                if held[key]:
                    raise ValueError(f"[[rods]] '{key[0]}' supports."
                                     f"{'x0' if key[1] == 'start' else 'xL'}: the end is joined "
                                     f"to the free body '{body}'; hold the body or free the end")
            body_ties.append(Tie(body, "body", tuple((self.end_s(*key), f"{key[0]}:{key[1]}")
                                                     for key, _, _ in entries),
                                 TIED["rigid"][0]))
            free_joints += [(name, self.end_s(*key), first, body) for key, name, first in entries]
        object.__setattr__(self, "body_ties", tuple(body_ties))
        object.__setattr__(self, "free_body_joints", tuple(free_joints))
        span = self.pieces[-1][1]
        order_names = self.rods[0].dim == 2 and ("u", "v", "theta") or TIED["rigid"][1]
        supports, extra, body_joints, inner = {}, [], [], []
        for key in ends:
            s = self.end_s(*key)
            components = tuple(c for c in order_names if c in held[key])
            if abs(s) <= 1e-12 * span or abs(s - span) <= 1e-12 * span:
                chain_end = "x0" if abs(s) <= 1e-12 * span else "xL"
                rod = self.rods[self.rod_index(key[0])]
                kind = "clamped" if key in clamped else rod.supports.get(key[1], "free")
                own = set(self._held(key, clamped))
                supports[chain_end] = kind if own == held[key] else components
                if key in clamped:
                    _, joint_name, rod_first = clamped[key]
                    body_joints.append((joint_name, chain_end, rod_first))
            elif components:  # an end inside the mesh (a shared vertex, a piece's end)
                extra.append((s, components, f"{key[0]}:{key[1]}"))
                if key in clamped:
                    _, joint_name, rod_first = clamped[key]
                    inner.append((joint_name, s, rod_first))
        object.__setattr__(self, "end_supports", supports)
        object.__setattr__(self, "body_joints", tuple(sorted(body_joints, key=lambda j: j[1])))
        object.__setattr__(self, "extra_supports", tuple(sorted(extra)))
        object.__setattr__(self, "inner_body_joints", tuple(inner))

    def piece_ends(self) -> tuple[float, ...]:
        """The mesh coordinates of the pieces' ends inside the mesh (boundary vertices other
        than 0 and `length`)."""
        return tuple(s for piece in self.pieces for s in piece
                     if 0.0 < s < self.length)

    def compiled_key(self) -> tuple:
        """What of the structure is compiled into a problem's mesh and forms: everything but
        the numbers of the rods' own sections and materials (held by piecewise-constant
        fields, rewritten in place: `fe_beam.fem.structure.ChainGeometry.set_rod_values`);
        which rods have them is part of it."""
        rods = tuple(replace(rod, section=tuple(name for name, _ in rod.section),
                             material=bool(rod.material)) for rod in self.rods)
        return (repr(rods), repr(self.joints), repr(self.bodies))

    def with_rod_values(self, index: int, section: dict | None = None,
                        material: tuple | None = None) -> Structure:
        """The structure with rod ``index``'s own section dimensions ({name: value}, merged
        into its own) or (E, G) replaced; the rods must carry their own values (`section`,
        `material` not empty)."""
        rod = self.rods[index]
        if section:
            if not rod.section:
                raise ValueError(f"[[rods]] '{rod.name}' has no own section fields")
            dims = dict(rod.section) | section
            rod = replace(rod, section=tuple(sorted(dims.items())))
        if material is not None:
            if not rod.material:
                raise ValueError(f"[[rods]] '{rod.name}' has no own material fields")
            rod = replace(rod, material=tuple(material))
        rods = self.rods[:index] + (rod,) + self.rods[index + 1:]
        return Structure(rods, self.joints, self.bodies)

    def refined(self, factor: int) -> Structure:
        """The same structure with every rod's elements multiplied by ``factor`` (a mesh
        refinement study of the chain)."""
        rods = tuple(replace(rod, elements=rod.elements * int(factor))
                     for rod in self.rods)
        return Structure(rods, self.joints, self.bodies)

    # --- what the finite elements need --------------------------------------------------------
    def chain_point_loads(self) -> tuple[tuple, tuple]:
        """(point_forces, point_moments) of every rod at chain coordinates (and a free body's
        force and moment at its first rod end: the body's pose is that end's)."""
        forces, moments = [], []
        for segment in self.chain:
            rod = self.rods[segment.rod]
            forces += [(segment.s_of(x), *rest) for x, *rest in rod.point_forces]
            moments += [(segment.s_of(x), *rest) for x, *rest in rod.point_moments]
        for tie in self.body_ties:
            body = self.body(tie.name)
            if any(body.force):
                forces.append((tie.ends[0][0], *body.force))
            if body.moment:
                moments.append((tie.ends[0][0], body.moment))
        return tuple(sorted(forces)), tuple(sorted(moments))

    def boundaries(self) -> tuple[float, ...]:
        """The mesh coordinates of the rods' ends inside the mesh (joints and piece ends)."""
        points = {seg.s0 for seg in self.chain} | {seg.s0 + seg.length for seg in self.chain}
        return tuple(sorted(s for s in points if 0.0 < s < self.length))

    def segment_at(self, s: float) -> ChainSegment:
        """The segment holding s (the later one at a joint)."""
        found = self.chain[0]
        for segment in self.chain:
            if s >= segment.s0 - 1e-12 * self.length:
                found = segment
        return found

    def reference_point(self, s: float, segment: ChainSegment | None = None):
        """The reference position (X, Y) (spatial: (X, Y, Z)) of chain coordinate s."""
        segment = segment or self.segment_at(s)
        t = s - segment.s0
        if segment.curvature:
            return arc_point(segment.origin, segment.theta0, segment.curvature, t)
        return tuple(o + t * d for o, d in zip(segment.origin, segment.tangent, strict=True))

    def reference_polyline(self, samples: int = 24) -> list[tuple]:
        """Points along the reference axes for drawing: each rod's ends (``samples`` points
        along an arc), a row of NaN between pieces (a break in the line)."""
        points, end = [], None
        for segment in self.chain:
            if end is not None and segment.s0 > end:
                points.append(tuple(math.nan for _ in range(self.dim)))
            count = samples if segment.curvature else 1
            start = 0 if end is None or segment.s0 > end else 1
            for k in range(start, count + 1):
                s = segment.s0 + segment.length * k / count
                points.append(self.reference_point(s, segment))
            end = segment.s0 + segment.length
        return points

    def rod_tip(self, index: int) -> tuple[float, str]:
        """(chain coordinate, chain side) of rod ``index``'s own end ("end" of the rod)."""
        segment = next(seg for seg in self.chain if seg.rod == index)
        return (segment.s0 if segment.reversed else segment.s0 + segment.length), segment
