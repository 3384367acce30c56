"""What a command runs, as data: the parsed configuration of a static rod analysis (the
parsers of `fe_beam.config` build these; the drivers of `fe_beam.analyses` take them)."""

from __future__ import annotations

from dataclasses import dataclass, field

from fe_beam.model.beam import BeamModel
from fe_beam.model.obstacles import ContactSettings
from fe_beam.model.settings import LoadStepping, SolverSettings

__all__ = ["OutputOptions", "StaticConfig"]


@dataclass(frozen=True)
class OutputOptions:
    xdmf: bool = True
    plots: bool = True
    gif: bool = False


@dataclass(frozen=True)
class StaticConfig:
    model: BeamModel
    solver: SolverSettings = field(default_factory=SolverSettings)
    stepping: LoadStepping = field(default_factory=LoadStepping)
    max_rotation_jump: float = 1.0
    output: OutputOptions = field(default_factory=OutputOptions)
    tendons: tuple = ()
    raw: dict = field(default_factory=dict)
    #: rigid obstacles ([[obstacles]], `fe_beam.model.obstacles`) and how contact is enforced
    obstacles: tuple = ()
    contact: ContactSettings | None = None
