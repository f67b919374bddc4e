"""The user's folders for armctl: its config (``armctl.toml``) and its cache (the parser tables).

Strategy: platformdirs' answer on every OS (``user_config_dir``, ``user_cache_dir``, appname
"armctl", no author folder), without importing platformdirs on Linux and the BSDs, where its
rule is the XDG one and a start-up pays for every import (issue 13): ``$XDG_CONFIG_HOME`` /
``$XDG_CACHE_HOME`` when absolute (a relative or empty one is ignored), else ``~/.config`` /
``~/.cache``.  tests/test_user_config.py and tests/test_newcomer_packaging.py hold the two to agreeing.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

APP_NAME = "armctl"
_XDG = {"config": ("XDG_CONFIG_HOME", "~/.config"), "cache": ("XDG_CACHE_HOME", "~/.cache")}


def user_folder(kind: str) -> Path:
    """The user's ``kind`` ("config" or "cache") folder for armctl (not created)."""
    variable, default = _XDG[kind]
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        base = os.environ.get(variable, "")
        return Path(base if os.path.isabs(base) else os.path.expanduser(default)) / APP_NAME
    import platformdirs

    where = platformdirs.user_config_dir if kind == "config" else platformdirs.user_cache_dir
    return Path(where(APP_NAME, appauthor=False))
