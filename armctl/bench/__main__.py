"""``python -m armctl.bench``: the streaming benchmark table (see armctl/bench/table.py)."""

from .table import main

raise SystemExit(main())
