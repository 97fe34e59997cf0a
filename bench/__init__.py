"""The benchmarks and their committed results (bench/results/). Run them as modules from the checkout,
``python -m bench.speed_error`` (see bench/README.md); `cavatar bench` runs speed_error too."""


class BenchmarkError(Exception):
    """A benchmark that cannot run as asked (a bundle without weights.npz when errors are wanted, bad data)."""
