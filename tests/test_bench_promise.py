"""The bound under the stop promise (issue 24): the best job time of any host that keeps armctl's
stop promise, the yardstick of every armctl row of ``armctl bench`` (≤ 1.01)."""

import pytest

from armctl.bench.scenarios import build_scenarios, physical_bound_s, promise_bound_s
from armctl.bench.table import PROMISE_RATIO, Cell, check_targets

SCENARIOS = {s.name: s for s in build_scenarios("test")}


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_the_promise_bound_is_never_below_the_physical_bound(name):
    scenario = SCENARIOS[name]
    floor_s = physical_bound_s(scenario.commands, scenario.options, scenario.outside_stop_s)
    for lead_s in (0.2, 2.0, 6.0):
        assert promise_bound_s(scenario.commands, scenario.options, lead_s, scenario.outside_stop_s) >= floor_s - 1e-9


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_a_lead_longer_than_the_job_costs_nothing(name):
    """With nothing the promise could hold back, the greedy host is the physical floor itself
    (two computations, one by a forward pass, one by the closed form, agree)."""
    scenario = SCENARIOS[name]
    commands, options = scenario.commands, scenario.options
    unconstrained = promise_bound_s(commands, options, 1e9, scenario.outside_stop_s)
    assert unconstrained == pytest.approx(physical_bound_s(commands, options, scenario.outside_stop_s), abs=1e-6)


def test_longfirst_pays_the_leads_price_and_a_longer_lead_removes_it():
    scenario = next(s for s in build_scenarios("full") if s.name == "longfirst")
    commands, options = scenario.commands, scenario.options
    floor_s = physical_bound_s(commands, options)
    assert promise_bound_s(commands, options, 2.0) > 1.02 * floor_s  # the line idles behind the long move
    assert promise_bound_s(commands, options, 3.4) < 1.01 * floor_s  # docs/bench.md: --lead 3.4 reaches the floor


def test_a_row_slower_than_the_promise_bound_misses_its_target():
    cell = Cell("mixed", "armctl", 10, 0, 10.0, 1, 1.0, None, None)
    cell.promise_ratio = PROMISE_RATIO + 0.005
    assert any("stop promise" in failure for failure in check_targets(cell))
    cell.promise_ratio = PROMISE_RATIO
    assert not any("stop promise" in failure for failure in check_targets(cell))
