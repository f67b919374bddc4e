"""``python -m armctl.bench``: the same command as ``armctl bench`` (options in armctl/ui/cli.py)."""

from ..ui.cli import bench

bench(prog_name="python -m armctl.bench")
