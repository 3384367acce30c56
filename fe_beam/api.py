"""The Python front door: ``fe_beam.run(command, config, out=None, **keys)``::

    import fe_beam

    summary = fe_beam.run("static", "examples/cantilever.toml", **{"mesh.elements": 20})
    summary["steps"][-1]["tip"]          # the same dict as summary.json of the same CLI run

``config`` is a TOML file or a dict as the TOML would parse; the keyword arguments are
``--set`` overrides by dotted name (``{"section.h": 0.02, "tendons.0.tension": 1.5}``). The
run is the CLI's own (`fe_beam.cli.prepare`, the command's driver of the registry): the same
validation, the same driver and the same summary (`fe_beam.analyses.result.Result`), so a
script and a shell give the same numbers. A mistake in the configuration raises
`fe_beam.ConfigError` with the sentence the CLI prints (exit code 2 there); an analysis that
stops (exit code 3 there) returns its summary with ``status`` "failed"; SIGINT/SIGTERM during a
run raise `fe_beam.runctl.Interrupted` after the last good state is written.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import os
import shutil
import tempfile
import threading
import warnings
from collections.abc import Mapping
from pathlib import Path

from fe_beam import cli, runctl
from fe_beam.config.finger import override_defaults
from fe_beam.config.schema import apply_overrides, load_config
from fe_beam.errors import ConfigError

__all__ = ["SUMMARY_FILES", "run"]

SUMMARY_FILES = runctl.SUMMARY_FILES  # the file that holds a command's summary
#: commands whose study lives in its folder (resumable points): out=None runs them in a
#: private temporary folder, removed afterwards
NEEDS_A_FOLDER = ("validity",)


def _overrides(keys: Mapping[str, object]) -> list[str]:
    """``--set`` assignments (TOML syntax) of dotted keys and Python values."""
    assignments = []
    for name, value in keys.items():
        if "." not in name:
            raise ConfigError(f"override {name!r}: expected a dotted key such as section.h "
                              "(table.key, or tendons.0.tension)")
        assignments.append(f"{name}={_toml(value)}")
    return assignments


def _toml(value) -> str:
    if hasattr(value, "item") and getattr(value, "shape", None) == ():  # a numpy scalar
        value = value.item()
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):  # a numpy array
        value = value.tolist()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(float(value)) if isinstance(value, float) else str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(item) for item in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{key} = {_toml(item)}" for key, item in value.items()) + "}"
    raise ConfigError(f"override value {value!r}: expected a number, string, boolean, list or "
                      "table")


def _remove(folder: Path, comm) -> None:
    comm.barrier()
    if comm.rank == 0:
        shutil.rmtree(folder, ignore_errors=True)


def run(command: str, config: str | os.PathLike | Mapping, out: str | os.PathLike | None = None,
        *, comm=None, progress: bool = False, verbose: bool = False, data=None,
        levels: int | None = None, ratio: float | None = None,
        quantity: list[str] | None = None, **keys) -> dict:
    """Run ``fe-beam COMMAND`` from Python and return its summary (the dict of summary.json;
    refine: of refinement.json).

    ``command`` is a subcommand of the CLI (static, finger, dynamic, modes, solid, compare,
    validity, refine, calibrate, design, buckling, path); ``config`` a TOML file or a dict as
    the TOML would parse (not modified); ``out`` the output folder, or None: nothing is written
    (validity, a resumable study, runs in a private temporary folder removed before
    returning). ``comm`` is an MPI communicator (default: the world, as under ``mpirun``);
    ``progress`` shows the progress bar; ``verbose`` prints the CLI's report on rank 0.
    ``data`` is calibrate's measurements (the CLI's ``--data``); ``levels``, ``ratio`` and
    ``quantity`` are refine's options. The remaining keyword arguments are overrides by
    dotted name, as ``--set table.key=value``.

    Raises `fe_beam.ConfigError` for a mistake in the configuration, the overrides or the
    output folder (the CLI's exit code 2), with the CLI's sentence.
    """
    if isinstance(config, Mapping):
        raw = copy.deepcopy(dict(config))
    elif isinstance(config, (str, os.PathLike)):
        raw = load_config(config)
    else:
        raise ConfigError(f"fe_beam.run: config must be a TOML file's path or a dict of tables "
                          f"as the TOML would parse; got {type(config).__name__}")
    assignments = _overrides(keys)
    raw = apply_overrides(raw, assignments, override_defaults(command, raw))
    if command == "calibrate" and data is None:
        raise ConfigError("fe_beam.run('calibrate', ...) needs data= (the measurements CSV, the "
                          "CLI's --data)")
    world = comm if comm is not None else cli._world()
    folder = None if out is None else Path(out)
    if command in NEEDS_A_FOLDER and folder is None:
        made = tempfile.mkdtemp(prefix="fe_beam_run_") if world.rank == 0 else None
        folder = Path(world.bcast(made, root=0) if world.size > 1 else made)
    try:
        if folder is not None:
            cli._check_output_folder(folder, world)
        args = argparse.Namespace(
            command=command, config="<dict>" if isinstance(config, Mapping) else str(config),
            out=folder, set=assignments, quiet=not progress,
            data=None if data is None else str(data),
            levels=None if levels is None else str(levels),
            ratio=None if ratio is None else str(ratio), quantity=quantity)
        notes: list[str] = []
        validated = cli.prepare(args, raw, world, notes)
        cli.quiet_jit_logging()
        cli.check_solver_options(validated)

        def echo(stream: str, text: str) -> None:
            if verbose:
                cli.report_line(world, stream, text)

        results = []
        deferred = (runctl.signals_deferred() if threading.current_thread()
                    is threading.main_thread() else contextlib.nullcontext())
        try:
            with deferred:  # SIGINT/SIGTERM stop at a step boundary (runctl.Interrupted)
                if folder is None:  # nothing written: the driver alone
                    cli.check_communicators(world, command)
                    results.append(cli.run_driver(command, validated, raw, None, world,
                                                  progress=progress, echo=echo))
                else:
                    cli.execute(args, validated, raw, world, on_result=results.append,
                                echo=echo)
        except (runctl.FolderBusy, runctl.TooLarge) as error:
            raise ConfigError(str(error)) from None
    finally:
        if out is None and folder is not None:
            _remove(folder, world)
    summary = results.pop().summary()
    cli.free_parallel_garbage(world)  # every rank returned here (an error did not)
    for note in notes:  # what the CLI prints as notes (unused tables): warnings here
        warnings.warn(f"fe-beam {command}: {note}", stacklevel=2)
    return summary
