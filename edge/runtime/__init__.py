"""`cavatar run`: the edge runtime — carpet frames in, private 3D bodies out (docs/runtime.md).

    from edge.runtime import Runtime, load_config
    rt = Runtime(load_config("cavatar.toml").with_overrides(seconds=30))
    rt.start(); rt.wait(); rt.stop()

Modules: ``config`` (typed TOML configuration), ``config_docs`` (every key described, the file
as TOML), ``reader`` (the source with decode timing), ``carpet_calibration`` (which calibration,
the virtual carpet's automatic one), ``errors`` (``SetupError``), ``stages`` (one frame through
calibrate → scene → infer → record; a person's inference is edge.infer's ``PeopleInference``),
``publisher`` (the publisher thread), ``counters`` and ``status`` (health), ``loop`` (the threads:
reader → frame loop → publisher), ``demo`` (`make run`: the runtime on the virtual carpet, then a
truth-vs-reconstruction strip).
"""

from edge.runtime.config import ConfigError, RuntimeConfig, default_bundle_path, load_config
from edge.runtime.config_docs import describe
from edge.runtime.errors import SetupError
from edge.runtime.loop import Runtime

__all__ = ["ConfigError", "Runtime", "RuntimeConfig", "SetupError", "default_bundle_path", "describe", "load_config"]
