"""``python -m armctl.jog``: the jog command on its own (the same as ``armctl jog``)."""

from .command import jog

if __name__ == "__main__":
    jog(prog_name="armctl jog")
