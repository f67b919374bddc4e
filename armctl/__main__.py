"""``python -m armctl`` — the same as the ``armctl`` command."""

from armctl.ui.cli import main

if __name__ == "__main__":  # pragma: no cover
    main()
