"""Review of the page at ``/`` against what the arm's reports prove, in a headless chromium (the
harness of tests/test_server_browser.py; skipped as it is where no browser is installed): a job
that failed says why, and a job whose end the page never saw (the server killed and started
again) is not left looking as if it still ran."""
from __future__ import annotations

import signal
import time

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")
pytest.importorskip("selenium.webdriver", reason="Selenium is not installed (pip install selenium)")

import serve_process  # noqa: E402
from serve_process import served  # noqa: E402
from test_server_api import long_job  # noqa: E402
from test_server_browser import headless_chromium, put_script, wait  # noqa: E402  (skips without a browser)

from selenium.webdriver.common.by import By  # noqa: E402

pytestmark = [pytest.mark.realtime, pytest.mark.timeout(120)]

MOVE = "G1 X220 Y0 Z250 A180 B0 C0 S1000 F3000\n"


def _open(driver, server) -> None:
    driver.get(server.base + "/")
    wait(driver, lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1")


def _job_line(driver):
    return driver.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] [data-role="job"]')


def _run(driver) -> None:
    driver.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] button[data-action="run"]').click()


def test_a_job_that_failed_shows_why(tmp_path):
    """An arm whose reports never arrive (``loss=1``): the job fails before anything is sent,
    and its summary says so ("no complete status from … within 3 s: received nothing (is the
    arm powered …); nothing was sent").  The page said only "— failed"."""
    with served("--arm", "a=sim://?loss=1&clock=virtual", journal=tmp_path) as server, headless_chromium() as driver:
        _open(driver, server)
        put_script(driver, "a", MOVE)
        _run(driver)
        wait(driver, lambda d: _job_line(d).get_attribute("data-outcome") == "failed")
        text = _job_line(driver).text
        assert "no complete status" in text and "nothing was sent" in text, text


def test_a_job_whose_end_the_page_never_saw_is_not_shown_running(tmp_path, monkeypatch):
    """The page watched a job; the server was killed (SIGKILL: no summary) and started again on
    the same address.  The page reconnected (its hello: no job running) and went on showing
    "job …: 4/41 frames, last line executed 2" with no outcome, for good.  Now it asks the
    server for the job: unknown to it, the line says the end was not seen and how the journal
    continues the job."""
    journal = tmp_path / "journal"
    port = serve_process.free_port()
    monkeypatch.setattr(serve_process, "free_port", lambda: port)  # the second server on the first's address
    with headless_chromium() as driver:
        with served("--arm", "a=sim://?speed=4", journal=journal) as first:
            _open(driver, first)
            put_script(driver, "a", long_job(40))
            _run(driver)
            wait(driver, lambda d: "last line executed 2" in _job_line(d).text)
            job_id = _job_line(driver).text.split()[1].rstrip(":")
            first.process.send_signal(signal.SIGKILL)
            first.process.wait(10)
        time.sleep(0.5)  # (the page sees its socket close and tries again every second)
        with served("--arm", "a=sim://?speed=4", journal=journal):
            wait(driver, lambda d: d.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] .badge').text
                 in ("free", "in control"))
            wait(driver, lambda d: _job_line(d).get_attribute("data-outcome") != "")
            text = _job_line(driver).text
            assert job_id in text and "not seen" in text and f"?resume={job_id}" in text, text
            assert "finished" not in text, text
