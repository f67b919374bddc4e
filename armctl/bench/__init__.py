"""The streaming benchmark (docs/bench.md).  Only the scenario names live here, so the command
line can offer them without importing the benchmark itself."""

SCENARIO_NAMES = (
    "long", "tiny", "mixed", "slow", "fast", "lossy", "arrival", "pause", "longfirst", "backforth", "periodic",
    "fifo50", "resume", "robotxyz", "kinematics", "slow2x",
)
