"""Model bundles shipped with the package (package data): ``lean-96/`` is the default of `cavatar run`.

Find it with :func:`edge.runtime.config.default_bundle_path`, never by spelling the path.
"""
