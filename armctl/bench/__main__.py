"""``python -m armctl.bench``: the same command as ``armctl bench`` (options in armctl/cli.py)."""

from ..cli import bench

bench(prog_name="python -m armctl.bench")
