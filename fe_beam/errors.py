"""The errors a user may meet, with no finite-element imports: every layer raises them."""

from __future__ import annotations

__all__ = ["ConfigError"]


class ConfigError(ValueError):
    """A user mistake in a configuration (message is shown as is, exit code 2)."""
