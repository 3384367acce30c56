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

__all__ = ["Body", "ChainSegment", "Joint", "JOINT_KINDS", "Rod", "Structure",
           "SUPPORTED_JOINT_KINDS"]

#: the joint kinds of the interface (issue 29) and those this slice solves
JOINT_KINDS = ("rigid", "pin", "ball", "hinge")
SUPPORTED_JOINT_KINDS = ("rigid",)
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

    def __post_init__(self):
        where = f"[[rods]] '{self.name}'"
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
        return tuple(x + self.length * d for x, d in zip(self.start, self.direction,
                                                         strict=True))


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
                             "joins rods rigidly only: kind = \"rigid\")")
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
    """A rigid body at ``position``; ``fixed`` = true (the only kind this slice supports)."""

    name: str
    position: tuple[float, float]
    fixed: object = True

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
        if self.fixed is not True:
            raise ValueError(f"{where} fixed = {self.fixed!r}: free and partly fixed bodies are "
                             "not supported yet (give fixed = true)")


@dataclass(frozen=True)
class ChainSegment:
    """Rod ``rod`` (index in `Structure.rods`) on the chain's [s0, s0 + length], traversed
    from its start (``reversed`` False) or from its end; ``theta0`` the reference angle of the
    chain's tangent on it, ``origin`` the reference point at s0."""

    rod: int
    reversed: bool
    s0: float
    length: float
    theta0: float
    origin: tuple
    #: spatial: the reference directors (d1, d2, d3) of the chain on it (d1 the chain's
    #: tangent; a reversed rod's frame turned by pi about its d3); None: planar
    frame: tuple | None = None

    @property
    def tangent(self) -> tuple:
        """The chain's reference tangent on the segment (world)."""
        if self.frame is not None:
            return self.frame[0]
        return (math.cos(self.theta0), math.sin(self.theta0))

    def s_of(self, x: float) -> float:
        """The chain coordinate of the rod's own arc length x (from its start)."""
        return self.s0 + (self.length - x if self.reversed else x)


@dataclass(frozen=True)
class ChainJoint:
    """A rigid joint between two rods at chain coordinate ``s``; ``first_before``: the first
    end of ``at`` lies on the chain before s (the reported force is on that end)."""

    name: str
    s: float
    first_before: bool
    segment: int  # the chain segment that ends at s


@dataclass(frozen=True)
class Structure:
    """Rods, joints and bodies, validated into a serial chain (`chain`, `joints_on_chain`,
    `end_supports`)."""

    rods: tuple[Rod, ...]
    joints: tuple[Joint, ...] = ()
    bodies: tuple[Body, ...] = ()
    chain: tuple[ChainSegment, ...] = field(init=False, default=())
    joints_on_chain: tuple[ChainJoint, ...] = field(init=False, default=())
    #: {"x0" | "xL": support kind} of the chain's two ends
    end_supports: dict = field(init=False, default_factory=dict)
    #: ((joint name, chain end "x0" | "xL", the rod end is named first), ...): rod ends
    #: joined to a fixed body
    body_joints: tuple = field(init=False, default=())

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
        self._resolve()

    # --- the serial chain ---------------------------------------------------------------------
    @property
    def length(self) -> float:
        return sum(rod.length for rod in self.rods)

    @property
    def dim(self) -> int:
        """2 (planar) or 3 (spatial)."""
        return self.rods[0].dim

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
        used: dict[tuple[str, str], str] = {}  # rod end -> joint
        links = []  # (joint, (rod, end), (rod, end))
        clamped: dict[tuple[str, str], tuple] = {}  # rod end -> (body, joint, rod first)
        for joint in self.joints:
            ends = [self._end(joint, entry) for entry in joint.at]
            rods = [(name, end) for kind, name, end in ends if kind == "rod"]
            bodies = [name for kind, name, _ in ends if kind == "body"]
            for key in rods:
                if key in used or len(set(rods)) != len(rods):
                    raise ValueError(
                        f"[[joints]] '{joint.name}' at: {key[0]}:{key[1]} is already joined "
                        f"(by '{used.get(key, joint.name)}'): three or more rod ends at a point "
                        "(a T junction) are not supported yet; this version solves serial "
                        "chains")
                used[key] = joint.name
            if len(rods) > 2 or (bodies and len(rods) != 1) or len(bodies) > 1:
                raise ValueError(f"[[joints]] '{joint.name}' at: {len(rods)} rod ends and "
                                 f"{len(bodies)} bodies; this version joins two rod ends, or "
                                 "one rod end to one fixed body (a serial chain)")
            points = [self.rods[self.rod_index(n)].point(e) for n, e in rods]
            points += [next(b for b in self.bodies if b.name == n).position for n in bodies]
            distance = max(math.dist(points[0], p) for p in points[1:])
            if distance > COINCIDENCE * scale:
                raise ValueError(f"[[joints]] '{joint.name}' at: the ends do not coincide in "
                                 f"the reference geometry: {', '.join(joint.at)} are "
                                 f"{distance:.6g} m apart")
            if bodies:
                clamped[rods[0]] = (bodies[0], joint.name,
                                    joint.at[0].partition(":")[0] != "body")
            else:
                links.append((joint, rods[0], rods[1]))
        joined_bodies = {body for body, _, _ in clamped.values()}
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
        self._order(links, clamped)

    def _order(self, links, clamped) -> None:
        names = [rod.name for rod in self.rods]
        neighbours: dict[str, list] = {n: [] for n in names}
        for joint, a, b in links:
            if a[0] == b[0]:
                raise ValueError(f"[[joints]] '{joint.name}' joins the two ends of rod "
                                 f"'{a[0]}': closed loops are not supported yet")
            neighbours[a[0]].append((joint, a, b))
            neighbours[b[0]].append((joint, b, a))
        if len(links) != len(names) - 1 or any(len(v) > 2 for v in neighbours.values()):
            raise ValueError(f"[[joints]]: {len(names)} rods and {len(links)} rod-to-rod joints "
                             "do not make one serial chain (closed loops and separate pieces "
                             "are not supported yet)")
        # the chain starts at a free end of an end rod, a held one if there is (the single
        # rod's convention: x0 supported, the tip free), else the first in [[rods]] order
        starts = []
        for n in names:
            if not neighbours[n]:
                starts += [(n, "start"), (n, "end")]
            elif len(neighbours[n]) == 1:
                joined = neighbours[n][0][1][1]
                starts.append((n, "end" if joined == "start" else "start"))
        if not starts:
            raise ValueError("[[joints]]: the rods form a closed loop, which is not supported "
                             "yet")

        def held(start):
            rod = self.rods[self.rod_index(start[0])]
            return start in clamped or rod.supports.get(start[1], "free") != "free"

        first, first_end = next((c for c in starts if held(c)), starts[0])
        # walk the chain: each rod entered at one end leaves by the other
        order, entered = [], None
        current, visited = first, set()
        while current is not None:
            visited.add(current)
            exits = [link for link in neighbours[current] if entered is None
                     or link[0].name != entered.name]
            if entered is None:  # the first rod: from the chosen end
                start_end = first_end
            else:
                start_end = next(link for link in neighbours[current]
                                 if link[0].name == entered.name)[1][1]
            order.append((current, start_end == "end"))
            nxt = None
            for joint, _mine, other in exits:
                if other[0] not in visited:
                    nxt, entered = other[0], joint
            current = nxt
        if len(order) != len(names):
            raise ValueError("[[joints]]: the rods do not make one connected serial chain")
        segments, s = [], 0.0
        for name, flipped in order:
            rod = self.rods[self.rod_index(name)]
            angle = rod.angle + (math.pi if flipped else 0.0)
            origin = rod.point("end" if flipped else "start")
            frame = None
            if rod.dim == 3:
                d1, d2, d3 = rod.frame
                frame = ((tuple(-c for c in d1), tuple(-c for c in d2), d3) if flipped
                         else (d1, d2, d3))
                angle = 0.0
            segments.append(ChainSegment(self.rod_index(name), flipped, s, rod.length, angle,
                                         origin, frame))
            s += rod.length
        object.__setattr__(self, "chain", tuple(segments))
        joints = []
        for k in range(len(segments) - 1):
            a, b = self.rods[segments[k].rod].name, self.rods[segments[k + 1].rod].name
            joint, mine, other = next(link for link in neighbours[a] if link[2][0] == b)
            first_before = joint.at[0].partition(":")[0] == a
            joints.append(ChainJoint(joint.name, segments[k + 1].s0, first_before, k))
        object.__setattr__(self, "joints_on_chain", tuple(joints))
        self._end_supports(order, clamped)

    def _end_supports(self, order, clamped) -> None:
        interior = set()
        for k, (name, flipped) in enumerate(order):
            ends = ("end", "start") if flipped else ("start", "end")
            if k > 0:
                interior.add((name, ends[0]))
            if k < len(order) - 1:
                interior.add((name, ends[1]))
        for rod in self.rods:
            for end in rod.supports:
                if (rod.name, end) in interior and rod.supports[end] != "free":
                    key = "x0" if end == "start" else "xL"
                    raise ValueError(f"[[rods]] '{rod.name}' supports.{key}: a support at an "
                                     "end joined to another rod is not supported yet (support "
                                     "the chain's free ends, or join a fixed body there)")
        supports, body_joints = {}, []
        for chain_end, (name, flipped), which in (("x0", order[0], 0), ("xL", order[-1], 1)):
            ends = ("end", "start") if flipped else ("start", "end")
            end = ends[which]
            rod = self.rods[self.rod_index(name)]
            kind = "clamped" if (name, end) in clamped else rod.supports.get(end, "free")
            supports[chain_end] = kind
            if (name, end) in clamped:
                _, joint_name, rod_first = clamped[(name, end)]
                body_joints.append((joint_name, chain_end, rod_first))
        object.__setattr__(self, "end_supports", supports)
        object.__setattr__(self, "body_joints", tuple(body_joints))

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
        """(point_forces, point_moments) of every rod at chain coordinates."""
        forces, moments = [], []
        for segment in self.chain:
            rod = self.rods[segment.rod]
            forces += [(segment.s_of(x), *rest) for x, *rest in rod.point_forces]
            moments += [(segment.s_of(x), *rest) for x, *rest in rod.point_moments]
        return tuple(sorted(forces)), tuple(sorted(moments))

    def boundaries(self) -> tuple[float, ...]:
        """The chain coordinates of the joints (interior rod boundaries)."""
        return tuple(segment.s0 for segment in self.chain[1:])

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
        return tuple(o + t * d for o, d in zip(segment.origin, segment.tangent, strict=True))

    def rod_tip(self, index: int) -> tuple[float, str]:
        """(chain coordinate, chain side) of rod ``index``'s own end ("end" of the rod)."""
        segment = next(seg for seg in self.chain if seg.rod == index)
        return (segment.s0 if segment.reversed else segment.s0 + segment.length), segment
