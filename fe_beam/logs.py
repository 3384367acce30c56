"""Logging set-up shared by the command line, worker processes and demos (no finite-element
imports)."""

from __future__ import annotations

import logging

__all__ = ["quiet_jit_logging"]


class _WarningsOnly(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= logging.WARNING


def quiet_jit_logging() -> None:
    """Drop FFCx/setuptools JIT chatter: it logs every compilation at INFO on the root logger
    and resets the root level while doing so, so a level alone does not hold."""
    root = logging.getLogger()
    if not any(isinstance(f, _WarningsOnly) for f in root.filters):
        root.addFilter(_WarningsOnly())
