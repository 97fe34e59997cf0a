"""Which configuration `cavatar run`, `status` and `doctor` use when no --config is given.

On an installed board the service reads /etc/cavatar/cavatar.toml; a command typed by the
IT person months later must look at the same file, not at the built-in defaults (the virtual
carpet, out/cavatar/), or `cavatar doctor` says "ready" about a carpet that is not there and
`cavatar status` reads the wrong status file. In order:

1. ``--config FILE``;
2. ``$CAVATAR_CONFIG`` (a file; non-empty);
3. ``/etc/cavatar/cavatar.toml`` when it exists (what deploy/install.sh writes);
4. the built-in defaults.

Each command says which one it uses (:attr:`ConfigChoice.describe`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

SYSTEM_CONFIG = "/etc/cavatar/cavatar.toml"
CONFIG_ENV = "CAVATAR_CONFIG"


@dataclass(frozen=True)
class ConfigChoice:
    """``path`` (None: the built-in defaults) and why it was chosen."""

    path: str | None
    reason: str

    @property
    def describe(self) -> str:
        return f"configuration {self.path} ({self.reason})" if self.path else f"configuration: {self.reason}"


def choose_config(explicit: str | None, env: Mapping[str, str] | None = None,
                  system_config: str | None = None) -> ConfigChoice:
    """The configuration to use (see the module doc)."""
    env = os.environ if env is None else env
    system = SYSTEM_CONFIG if system_config is None else system_config
    if explicit:
        return ConfigChoice(str(explicit), "--config")
    from_env = env.get(CONFIG_ENV, "").strip()
    if from_env:
        return ConfigChoice(from_env, f"from ${CONFIG_ENV}")
    if Path(system).is_file():
        return ConfigChoice(system, "the installed one; --config FILE for another")
    return ConfigChoice(None, f"the built-in defaults (no --config, no ${CONFIG_ENV}, no {system})")


def load_chosen(explicit: str | None, env: Mapping[str, str] | None = None):
    """(RuntimeConfig, ConfigChoice); ConfigError as :func:`edge.runtime.config.load_config` raises it."""
    from edge.runtime.config import ConfigError, RuntimeConfig, load_config

    choice = choose_config(explicit, env)
    if not choice.path:
        return RuntimeConfig(), choice
    try:
        return load_config(choice.path), choice
    except ConfigError as exc:  # say where the path came from: $CAVATAR_CONFIG may be long forgotten
        raise ConfigError(exc.problems, f"{exc.source} ({choice.reason})") from None


__all__ = ["CONFIG_ENV", "SYSTEM_CONFIG", "ConfigChoice", "choose_config", "load_chosen"]
