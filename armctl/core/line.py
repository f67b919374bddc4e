"""The serial link's numbers (PROTOCOL.md, "Link"): frame sizes, the connector's buffer, the line
rate, the status period.

Strategy: plain constants, no imports, so the option ranges of armctl/core/limits.py can derive from
them without loading the frame codec at start-up (``armctl --help`` pays for every import).
armctl/core/protocol.py re-exports them: that is where the rest of the code reads them.
"""

FRAME_SIZE = 48  # every host→arm frame, motion or control
STATUS_SIZE = 9  # every arm→host status frame
CONNECTOR_BUFFER_BYTES = 9600
CONNECTOR_BUFFER_FRAMES = CONNECTOR_BUFFER_BYTES // FRAME_SIZE  # 200
DEFAULT_BAUD = 9600
BITS_PER_BYTE = 10  # 8N1: start bit, 8 data bits, stop bit
STATUS_PERIOD_S = 0.030  # one status frame every 30 ms
