"""The errors a user may meet, with no finite-element imports: every layer raises them."""

from __future__ import annotations

__all__ = ["ConfigError", "LoadSteppingFailed", "SolveFailed", "UpdateFailed"]


class ConfigError(ValueError):
    """A user mistake in a configuration (message is shown as is, exit code 2)."""


class SolveFailed(RuntimeError):
    """SNES did not converge (the iterate is left as SNES left it)."""


class LoadSteppingFailed(RuntimeError):
    """Load stepping gave up; the state of ``last_load_factor`` has been restored. Raised by
    the engine as its subclass `fe_beam.solvers.continuation.ContinuationFailed`, which carries the
    cause in ``reason`` (never parse the message)."""

    def __init__(self, message: str, last_load_factor: float, results: list):
        super().__init__(message)
        self.last_load_factor = last_load_factor
        self.results = results


class UpdateFailed(RuntimeError):
    """No equilibrium was reached for the new values (neither by Newton from the last
    equilibrium nor by load stepping towards them); the last equilibrium and its values are
    restored. ``reached`` is the fraction of the way to the new values that converged."""

    def __init__(self, message: str, reached: float):
        super().__init__(message)
        self.reached = reached
