"""armctl — drive a 6-axis desktop robot arm over its serial connector.

Importing armctl is cheap on purpose: heavy modules (lark, rich, serial) are imported by the
commands that need them, so ``armctl --help`` stays fast.
"""

__version__ = "0.1.0"
