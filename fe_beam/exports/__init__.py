"""Exports: what a run writes, as objects the driver composes (summary, tables, states, pictures).

A driver builds a list of exports, wraps it in `Exports` and calls, on every rank,

    exports.start(summary)     once, before the first step (summary.json with status "running")
    exports.on_step(record)    after each accepted step / time / load point / level
    exports.finish(summary)    once at the end, in a ``finally``: success, failure (status
                               "failed"), interruption (status "interrupted") alike

``record`` is the driver's dict of one step (the entry it also keeps in summary.json's
``steps`` / ``history`` / ``table``); ``summary`` the final content of summary.json. Every file
stays readable at any moment (`fe_beam.exports.outputs`): summaries and whole tables are replaced
atomically, growing tables and XDMF series are appended by the two-copy scheme. Files that grow
with the run are brought up to date together, at a bounded share of the wall time
(`fe_beam.runctl.Throttle`; ``throttle=False``: after every step), so that after an interruption
they hold the same steps. Text files are written by rank 0; exports whose ``collective`` is true
(XDMF: the fields are gathered) are called on every rank.

Pictures (`PlotExport`) are drawn for a finished analysis (converged, completed or failed),
never for an interrupted one.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from fe_beam import runctl
from fe_beam.exports import outputs
from fe_beam.exports.outputs import figure

__all__ = [
    "CSVExport",
    "Column",
    "Export",
    "Exports",
    "PlotExport",
    "SummaryExport",
    "TableExport",
    "XDMFExport",
    "figure",
    "indexed_columns",
    "tip_columns",
]


class Export:
    """One kind of output. Subclasses override what they need; all three are no-ops here.

    ``flush`` in `on_step` says whether the files are brought up to date now (else the step is
    buffered until a later flush or `finish`)."""

    collective = False  # True: called on every rank (else on rank 0 only)

    def start(self, summary: dict | None) -> None:
        pass

    def on_step(self, record: dict, flush: bool) -> None:
        pass

    def finish(self, summary: dict | None) -> None:
        pass


class Exports:
    """A driver's exports, called together (see the module docstring); ``comm`` decides which
    rank writes (rank 0; None: this one) and ``throttle`` how often growing files are flushed
    (False: after every step)."""

    def __init__(self, exports: Sequence[Export], comm=None, throttle: bool = True):
        self.root = comm is None or comm.rank == 0
        self.exports = [e for e in exports if e is not None and (e.collective or self.root)]
        self._throttle = runctl.Throttle() if throttle else None

    def start(self, summary: dict | None = None) -> None:
        for export in self.exports:
            export.start(summary)

    def on_step(self, record: dict) -> None:
        if self._throttle is None:
            due = True
        else:
            due = self._throttle.due() if self.root else False
        with self._throttle.timing() if due and self._throttle else contextlib.nullcontext():
            for export in self.exports:
                export.on_step(record, due)

    def finish(self, summary: dict | None = None) -> None:
        for export in self.exports:
            export.finish(summary)


class SummaryExport(Export):
    """A JSON summary (summary.json), replaced atomically: at `start`, at the flushed steps
    (``content()``: the summary as it stands) and at `finish` (the final summary given, else
    ``content()``)."""

    def __init__(self, path: str | Path, content: Callable[[], dict] | None = None):
        self.path = Path(path)
        self.content = content

    def write(self, summary: dict) -> None:
        outputs.atomic_write_json(self.path, summary)

    def start(self, summary):
        if summary is not None:
            self.write(summary)

    def on_step(self, record, flush):
        if flush and self.content is not None:
            self.write(self.content())

    def finish(self, summary):
        if summary is None and self.content is not None:
            summary = self.content()
        if summary is not None:
            self.write(summary)


@dataclass(frozen=True)
class Column:
    """A CSV column: its header and how a record gives its cell (``get(record)``)."""

    name: str
    get: Callable[[dict], object]


def tip_columns(prefix: str = "tip_", tip=lambda r: r["tip"]) -> list[Column]:
    """u, v, theta of a record's tip dict (``tip(record)``) as columns ``{prefix}u`` ..."""
    return [Column(f"{prefix}{k}", lambda r, k=k: tip(r)[k]) for k in ("u", "v", "theta")]


def indexed_columns(name: str, count: int, values: Callable[[dict], Sequence]) -> list[Column]:
    """``{name}_0`` .. ``{name}_{count-1}``: the entries of ``values(record)``."""
    return [Column(f"{name}_{i}", lambda r, i=i: values(r)[i]) for i in range(count)]


class CSVExport(Export):
    """A table with one row per record, its columns declared once, appended as the run goes
    (`fe_beam.exports.outputs.AppendCSV`: O(1) per row, readable at any moment).

    ``columns``: a list of `Column`, or a function of the first record (None when the run ends
    without one) that returns it, for tables whose width is known from the data. ``empty``:
    write the header-only table of a run without records (else no file)."""

    def __init__(self, path: str | Path, columns, empty: bool = True):
        self.path = Path(path)
        self._columns = columns
        self._empty = empty
        self._table = None  # opened by `start` (rank 0 only) or the first record

    def start(self, summary):
        if not callable(self._columns) and self._empty:
            self._open(None)

    def _open(self, record) -> None:
        columns = self._columns(record) if callable(self._columns) else self._columns
        self._columns = list(columns)
        self._table = outputs.AppendCSV(self.path, [c.name for c in self._columns])

    def row(self, record: dict) -> list:
        return [column.get(record) for column in self._columns]

    def on_step(self, record, flush):
        if self._table is None:
            self._open(record)
        self._table.add([self.row(record)], flush=flush)

    def finish(self, summary):
        if self._table is None and self._empty:
            self._open(None)
        if self._table is not None:
            self._table.close()


class TableExport(Export):
    """A CSV table derived from the whole summary (``table(summary) -> (header, rows)``),
    rewritten atomically at every flushed step and at `finish`: for tables whose earlier rows
    change as records arrive (e.g. the analysis of a refinement study)."""

    def __init__(self, path: str | Path, table: Callable[[dict], tuple[list, list]],
                 content: Callable[[], dict]):
        self.path = Path(path)
        self.table, self.content = table, content

    def write(self, summary: dict) -> None:
        outputs.write_csv(self.path, *self.table(summary))

    def start(self, summary):
        if summary is not None:
            self.write(summary)

    def on_step(self, record, flush):
        if flush:
            self.write(self.content())

    def finish(self, summary):
        self.write(summary if summary is not None else self.content())


class XDMFExport(Export):
    """The states of a run as an XDMF time series (`fe_beam.exports.outputs.BeamXDMFWriter`, or any
    writer with ``write(t, flush)`` and ``close()``); collective. ``time``: the record key of
    the time axis ("t", "load_factor")."""

    collective = True

    def __init__(self, writer, time: str):
        self.writer, self.time = writer, time

    def on_step(self, record, flush):
        self.writer.write(record[self.time], flush=flush)

    def finish(self, summary):
        self.writer.close()


UNFINISHED = ("running", "interrupted")


class PlotExport(Export):
    """Pictures: ``draw(summary)`` (rank 0) at `finish` when the analysis finished (its status
    neither "running" nor "interrupted"), and with ``every_step`` also at every flushed step
    (``content()``: the summary as it stands), so that the pictures follow a slow sweep."""

    def __init__(self, draw: Callable[[dict | None], None], content=None,
                 every_step: bool = False):
        self.draw, self.content, self.every_step = draw, content, every_step

    def on_step(self, record, flush):
        if self.every_step and flush:
            self.draw(self.content() if self.content is not None else None)

    def finish(self, summary):
        if summary is None and self.content is not None:
            summary = self.content()
        if summary is None or summary.get("status") not in UNFINISHED:
            self.draw(summary)
