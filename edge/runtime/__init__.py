"""`cavatar run`: the edge runtime — carpet frames in, private 3D bodies out (docs/runtime.md).

    from edge.runtime import Runtime, load_config
    rt = Runtime(load_config("cavatar.toml").with_overrides(seconds=30))
    rt.start(); rt.wait(); rt.stop()

Modules: ``config`` (typed TOML configuration), ``reader`` (the source with decode timing),
``carpet_calibration`` (which calibration, the virtual carpet's automatic one), ``model_input``
(one person's input, prepared as in training), ``tracks`` (feature windows per track),
``stages`` (one frame through calibrate → scene → encoder → head → record), ``publisher``
(the publisher thread), ``counters`` and ``status`` (health), ``pipeline`` (the threads),
``demo`` (`make run`: the runtime on the virtual carpet, then a truth-vs-reconstruction strip).
"""

from edge.runtime.carpet_calibration import SetupError
from edge.runtime.config import ConfigError, RuntimeConfig, default_bundle_path, describe, load_config
from edge.runtime.pipeline import Runtime

__all__ = ["ConfigError", "Runtime", "RuntimeConfig", "SetupError", "default_bundle_path", "describe", "load_config"]
