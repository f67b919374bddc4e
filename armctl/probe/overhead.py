"""The arm's wait before every motion command (``[timing] command_overhead_s``), from the timed moves.

Strategy: a timed move's start delay (its fit's intercept, armctl/probe/motion.py) is the wait plus
the probe's lag (a report trails the arm by up to a status step, plus what is left of the reads'
lateness), known only to a status step: the joint moves sample joint 5 every 270 ms, 54 steps of
0.01° apart at 2°/s, so every sample sits at one phase of the 5 ms step and averaging them gains
nothing (a 4 ms and a 7 ms arm both read 5.6 ms).  A single move cannot tell a wait under a step
from the lag.  So the back joint move is sent behind a **chain** of ``CHAIN_COMMANDS`` delays, each
longer than a frame's time on the line, so the arm runs them back to back: its start then carries
the wait once per delay and once for itself, and its start delay counted from the first delay's
landing + the delays' model time, less the lone joint move's (the same lag, the same kind of
error), is ``n`` waits: the wait to (the two intercepts' errors) / ``n`` — a step / 10 at n = 20 —
and the lag cancels.  Delays take the wait as every motion command does (armctl/core/motion.py).

The chain needs room in the connector: it is sent only when the probe measured a FIFO that holds
it (``fifo_frames`` ≥ its delays), else the wait is the lone rule (``overhead_of``) and a wait
under a step is "not resolved", never a confident 0.  A chain whose answer disagrees with the lone
moves by more than their errors (a delay lost, an arm whose delays do not wait) is not used either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core.protocol import Delay
from .plan import LIKELY, SURE, Finding
from .steps import DOCUMENTED

CHAIN_COMMANDS = 20  # delays before the back joint move: their waits add up in its start
CHAIN_DELAY_MS = 100.0  # each at least this long and twice a frame's line time: they queue and run back to back
LONE_LAG_STEPS = 0.8  # how far, in status steps, a lone move's start delay may lie above the wait (its samples' phase)
MIN_CHAIN_COMMANDS = 5  # a FIFO that holds fewer: no chain (± 2/5 of a step or worse: not worth its time)


@dataclass(frozen=True)
class Chain:
    """The delays a timed move is sent behind: ``model_s`` their time without waits, ``allowed_s``
    how long they may take on the arm (the lone move's start delay each, and a tenth of the delay)."""

    commands: tuple
    model_s: float
    allowed_s: float


@dataclass(frozen=True)
class Wait:
    """The wait as measured: ``value_s`` (stated), ``measured_s`` (before rounding: what each chained
    wait took out of a start delay), ``precision_s`` (None: not resolved below a status step, the
    lone rule) and what says so."""

    value_s: float
    measured_s: float
    precision_s: float | None
    evidence: str
    sure: bool


def chain_for(probe, lone) -> tuple[Chain | None, str]:
    """The chain the back joint move goes behind (``lone``: the first joint move's ``MoveFit``), or
    None, and why not."""
    if lone is None:
        return None, "the first joint move gave no start delay"
    fifo = probe.finding("fifo_frames")
    room = fifo.value if fifo is not None and fifo.value is not None else 0
    count = min(CHAIN_COMMANDS, room)
    if count < MIN_CHAIN_COMMANDS:
        return None, f"no chain of delays: the connector was not shown to hold {MIN_CHAIN_COMMANDS} frames"
    delay_ms = max(CHAIN_DELAY_MS, math.ceil(round(2 * probe.frame_s * 100, 6)) * 10.0)  # a frame on the line: 50 ms at 9600
    delay_s = delay_ms / 1000
    each_s = 1.1 * delay_s + max(lone.start_delay_s, 0.0) + lone.delay_error_s
    return Chain(tuple(Delay(delay_ms=delay_ms) for _ in range(count)), count * delay_s, count * each_s), ""


def overhead_of(fits) -> float:
    """The lone rule, from the moves' ``(start_delay_s, step_s)``: the wait is common to every move, the rest
    of a start delay is the probe's lag — the status step (a report trails the arm by up to one) and what is
    left of the reads' lateness — which a coarser step makes larger either way (the linear moves' 0.1 mm at
    5 mm/s is 20 ms and their fits run ~5 ms low).  So: the least start delay of the finest moves (the joint
    moves: 0.01° at 2°/s, 5 ms), in whole milliseconds down; none (0) under one of their steps, which a lone
    move cannot tell from its lag (the document's arm: ≤ 1 ms in virtual time, ≤ 2.9 ms through a pty)."""
    finest_s = min(step_s for _, step_s in fits)
    delay_s = min(delay_s for delay_s, step_s in fits if step_s <= finest_s * (1 + 1e-6))
    return 0.0 if delay_s < finest_s else math.floor(round(delay_s * 1000, 6)) / 1000


def measured_wait(measured, no_chain: str = "", lateness_s: float = 0.0) -> Wait:
    """The wait from the timed moves (``MoveFit``s; a chained one has ``waits`` > 1): the chain's
    answer where it has one that agrees with the lone moves, else the lone rule (``no_chain``: why
    there is no chained move).  ``lateness_s``: how late a status read may be (one way: the two
    intercepts' lateness differs by at most that)."""
    lone = [r for r in measured if r.waits == 1] or measured
    floor_s = overhead_of([(r.start_delay_s, r.step_s) for r in lone])
    finest_s = min(r.step_s for r in lone)
    chained = [r for r in measured if r.waits > 1]
    same = [r for r in lone if chained and abs(r.step_s - chained[0].step_s) <= chained[0].step_s * 1e-6]
    if not same:
        return _lone(floor_s, finest_s, no_chain if not chained else "no lone move of the chained move's kind")
    chain, alone = chained[0], min(same, key=lambda r: r.start_delay_s)
    count = chain.waits - alone.waits
    value_s = (chain.start_delay_s - alone.start_delay_s) / count
    precision_s = (chain.delay_error_s + alone.delay_error_s + lateness_s) / count
    told = (f"a joint move behind {count} delays started {chain.start_delay_s * 1000:.1f} ms after their model time, "
            f"the lone one {alone.start_delay_s * 1000:.1f} ms after landing: "
            f"{value_s * 1000:.2f} ±{precision_s * 1000:.2f} ms each")
    # the lone delay is the wait + the lag (≥ 0, up to a step) ± its error: a chain outside that lost a delay,
    # or the arm's delays do not wait as its moves do
    slack_s = alone.delay_error_s + lateness_s + alone.step_s + precision_s
    if value_s < -precision_s or abs(value_s - alone.start_delay_s) > slack_s:
        return _lone(floor_s, finest_s, f"{told}: the chain disagrees with the lone moves", False)
    # The chain assumes the arm's delays take the wait as its moves do (the document does not say).
    # Where they do not, the chained move carries one wait, as the lone one: the chain reads 0 while
    # the lone move started a wait late.  A lone start delay is the wait plus a lag of at most about
    # 0.7 of a step (its samples' phase: 3.4 ms of 5 seen), its landing's uncertainty (an adapter
    # that held the frame: 30 ms) and the reads' lateness: a chain below that is stated as the lone
    # rule states it, the larger and so the safer, and only "likely".
    landing_s = alone.delay_error_s - alone.step_s  # (delay_error_s: a step and the landing's uncertainty)
    if value_s < floor_s - LONE_LAG_STEPS * alone.step_s - landing_s - lateness_s - precision_s:
        return _lone(floor_s, finest_s, f"{told}: under the lone moves' {floor_s * 1000:g} ms, as on an arm whose delays "
                     "do not take the wait (the document does not say; the chain assumes they do)", False)
    # stated to the precision's decade (0.1 ms at ±0.5 ms; 1 ms behind a real port's ±2.5 ms), 0 within it
    stated_s = 0.0 if abs(value_s) <= precision_s else round(value_s, min(4, -math.floor(math.log10(precision_s))))
    said = f"{stated_s * 1000:g} ms before every motion command" if stated_s else f"none (under {precision_s * 1000:.2f} ms)"
    return Wait(stated_s, value_s, precision_s, f"{told}: {said}", True)


def _lone(floor_s: float, finest_s: float, why: str, sure: bool = True) -> Wait:
    """The lone rule's answer: a wait of a step or more to a step; under one, "not resolved"."""
    why = f" ({why})" if why else ""
    if floor_s:
        return Wait(floor_s, floor_s, None,
                    f"{floor_s * 1000:g} ms before every motion command, to {finest_s * 1000:.1f} ms{why}", sure)
    return Wait(0.0, 0.0, None, f"none beyond the probe's lag: under {finest_s * 1000:.1f} ms, not resolved{why}", False)


def overhead_finding(wait: Wait, measured, factor: str) -> Finding:
    """``command_overhead_s`` as a finding: sure where the chain resolved it (or the lone rule found
    a wait of a step or more) and every move's own start delay (a chained one's less its chain's
    waits as measured) is within its status step (+ 1 ms) of it; likely beyond (speed_tolerance
    covers what is left) or where a wait under a step was not resolved; no surer than the factor
    fitted with it."""
    overhead_s, own_s = wait.value_s, [r.own_delay_s(wait.measured_s) for r in measured]
    delays_ms = [round(delay_s * 1000, 1) for delay_s in own_s]
    agree = all(abs(delay_s - overhead_s) <= r.step_s + 0.001 for delay_s, r in zip(own_s, measured))
    confidence = factor if factor != SURE else SURE if agree and wait.sure else LIKELY
    evidence = (f"start delays {delays_ms} ms (the intercepts of the timed moves' fits; one status step is "
                f"{min(r.step_s for r in measured) * 1000:.1f} ms on the finest): " + wait.evidence
                + ("" if agree else "; the moves disagree by more than their steps"))
    details = {"start_delay_s": [round(delay_s, 4) for delay_s in own_s]}
    if wait.precision_s is not None:
        details["precision_s"] = round(wait.precision_s, 5)
    return Finding("command_overhead_s", DOCUMENTED["command_overhead_s"], overhead_s, evidence, confidence, details)
