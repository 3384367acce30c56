"""Progress bars on rank 0 only (tqdm), quiet in tests and under ``FE_BEAM_PROGRESS=0``.

`ProgressBar.update` is also the step boundary where a pending SIGINT/SIGTERM is noticed: every
load- and time-stepping loop calls it after each converged step on all ranks, so it checks the
signal flag collectively (`fe_beam.runctl.check`) whether or not a bar is shown."""

from __future__ import annotations

import os
import sys

from fe_beam import runctl


class ProgressBar:
    """A bar over a continuous quantity (load factor, simulated time) in [0, total]."""

    def __init__(self, comm, total: float, label: str, enabled: bool = True, unit: str = ""):
        self._bar = None
        self._done = 0.0
        self._comm = comm
        if not enabled or comm.rank != 0 or os.environ.get("FE_BEAM_PROGRESS", "1") == "0":
            return
        try:
            from tqdm import tqdm
        except ImportError:  # the bar is a nicety, never a reason to fail
            return
        self._bar = tqdm(
            total=total,
            desc=label,
            unit=unit,
            file=sys.stderr,
            leave=False,
            bar_format=(
                "{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} "
                "[{elapsed}<{remaining}] {postfix}"
            ),
        )

    def update(self, value: float, message: str = "") -> None:
        """Show ``value``; then raise `fe_beam.runctl.Interrupted` on every rank if any rank
        got SIGINT/SIGTERM (collective)."""

        self._show(value, message)
        runctl.check(self._comm)

    def _show(self, value: float, message: str) -> None:
        if self._bar is None:
            return
        self._bar.update(value - self._done)
        self._done = value
        if message:
            self._bar.set_postfix_str(message, refresh=False)

    def note(self, message: str) -> None:
        if self._bar is not None:
            self._bar.write(message, file=sys.stderr)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
