"""The page at ``/`` in a real headless browser: Debian's chromium driven by Selenium through
/usr/bin/chromedriver (no browser download).  Skipped, with the reason, where no browser, no
driver or no Selenium is installed (.ci/run installs all three and runs this)."""
from __future__ import annotations

import json
import os
import shutil
import socket
from contextlib import contextmanager
from pathlib import Path

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")
webdriver = pytest.importorskip("selenium.webdriver", reason="Selenium is not installed (pip install selenium)")

from serve_process import served  # noqa: E402
from test_server_api import long_job  # noqa: E402

CHROMIUM = os.environ.get("ARMCTL_CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("ARMCTL_CHROMEDRIVER", "/usr/bin/chromedriver")
if not (shutil.which(CHROMIUM) and shutil.which(CHROMEDRIVER)):
    pytest.skip(f"no headless browser: {CHROMIUM} and {CHROMEDRIVER} are needed "
                "(apt-get install chromium chromium-driver)", allow_module_level=True)

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

pytestmark = [pytest.mark.realtime, pytest.mark.timeout(120)]

BAD = (Path(__file__).parent / "data" / "scripts_cli" / "compile_error_job.txt").read_text()


@contextmanager
def headless_chromium():
    """A headless chromium driven by Selenium, quit at the end of the block."""
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for argument in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync", "--window-size=1400,1100"):
        options.add_argument(argument)
    driver = webdriver.Chrome(options=options, service=webdriver.ChromeService(executable_path=CHROMEDRIVER))
    driver.set_page_load_timeout(30)
    try:
        yield driver
    finally:
        driver.quit()


@pytest.fixture(scope="module")
def browser():
    with headless_chromium() as driver:
        yield driver


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with served("--arm", "a=sim://?speed=20", "--arm", "b=sim://?speed=20",
                journal=tmp_path_factory.mktemp("journal")) as running:
        yield running


def wait(driver, condition, timeout_s: float = 20.0):
    return WebDriverWait(driver, timeout_s, poll_frequency=0.05).until(lambda d: condition(d))


@pytest.fixture(autouse=True)
def page_loaded(browser, server):
    """The page at ``/``, loaded once per browser: each test runs alone too (``-k``, or pytest-xdist
    handing this module's tests to two workers), not only after the first one loaded it."""
    if not browser.current_url.startswith(server.base):
        browser.get(server.base + "/")
        wait(browser, lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1")


def card(driver, arm: str):
    return driver.find_element(By.CSS_SELECTOR, f'section[data-arm="{arm}"]')


def put_script(driver, arm: str, text: str) -> None:
    area = card(driver, arm).find_element(By.CSS_SELECTOR, 'textarea[data-role="script"]')
    driver.execute_script("arguments[0].value = arguments[1]; arguments[0].dispatchEvent(new Event('input'));", area, text)


def test_the_page_renders_both_arms_with_live_status(browser, server):
    browser.get(server.base + "/")
    wait(browser, lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1")
    assert [s.get_attribute("data-arm") for s in browser.find_elements(By.CSS_SELECTOR, "section.arm")] == ["a", "b"]
    for arm in ("a", "b"):
        wait(browser, lambda d: card(d, arm).find_element(By.CSS_SELECTOR, '[data-role="status"]').text.startswith("X "))
        wait(browser, lambda d: card(d, arm).find_element(By.CSS_SELECTOR, ".badge").text == "free")
        card(browser, arm).find_element(By.CSS_SELECTOR, 'button[data-action="control"]').click()
        wait(browser, lambda d: card(d, arm).find_element(By.CSS_SELECTOR, ".badge").text == "in control")


def test_lint_findings_show_at_their_lines(browser, server):
    put_script(browser, "a", BAD)
    findings = wait(browser, lambda d: card(d, "a").find_elements(By.CSS_SELECTOR, '[data-role="findings"] li.error'))
    assert findings[0].get_attribute("data-line") == "3" and "line 3:" in findings[0].text
    gutter = card(browser, "a").find_elements(By.CSS_SELECTOR, ".gutter div")
    assert gutter[2].get_attribute("class") == "error" and gutter[0].get_attribute("class") in ("", None)


def test_an_uploaded_script_is_linted(browser, server):
    path = Path(__file__).parent / "data" / "scripts_cli" / "lint_error_job.txt"
    card(browser, "a").find_element(By.CSS_SELECTOR, 'input[data-role="file"]').send_keys(str(path))
    area = card(browser, "a").find_element(By.CSS_SELECTOR, 'textarea[data-role="script"]')
    wait(browser, lambda d: area.get_attribute("value") == path.read_text())
    status, lint = server.request("POST", "/api/arms/a/lint", path.read_text())
    expected = [f"line {d['line']}:{d['column']} {d['code']}" for d in lint["diagnostics"]]
    assert expected
    wait(browser, lambda d: [item.text.split(" ", 3)[:3] for item in
                             card(d, "a").find_elements(By.CSS_SELECTOR, '[data-role="findings"] li')]
         == [e.split(" ") for e in expected])


def test_run_pause_and_stop_buttons_work_and_the_preview_draws_the_path(browser, server):
    put_script(browser, "b", long_job(30))
    wait(browser, lambda d: len(card(d, "b").find_elements(By.CSS_SELECTOR, 'svg[data-role="preview"] polyline')) == 31)
    card(browser, "b").find_element(By.CSS_SELECTOR, 'button[data-action="run"]').click()
    job_line = card(browser, "b").find_element(By.CSS_SELECTOR, '[data-role="job"]')
    wait(browser, lambda d: "frames, last line executed" in job_line.text)
    job_id = job_line.text.split()[1].rstrip(":")
    status, arms = server.request("GET", "/api/arms")
    assert arms[1]["job"] == job_id
    card(browser, "b").find_element(By.CSS_SELECTOR, 'button[data-action="pause"]').click()
    wait(browser, lambda d: server.request("GET", f"/api/arms/b/jobs/{job_id}")[1].get("pause_state") == "paused")
    wait(browser, lambda d: "paused" in job_line.text)
    card(browser, "b").find_element(By.CSS_SELECTOR, 'button[data-action="resume"]').click()
    wait(browser, lambda d: server.request("GET", f"/api/arms/b/jobs/{job_id}")[1].get("pause_state") == "running")
    card(browser, "b").find_element(By.CSS_SELECTOR, 'button[data-action="stop"]').click()
    wait(browser, lambda d: job_line.get_attribute("data-outcome") == "interrupted", 40)
    job = server.request("GET", f"/api/arms/b/jobs/{job_id}")[1]
    assert job["outcome"] == "interrupted" and job["frames_sent"] < job["total_frames"]
    progress = card(browser, "b").find_element(By.CSS_SELECTOR, '[data-role="progress"]')
    assert float(progress.get_attribute("value")) == job["frames_sent"]


def test_a_job_runs_to_finished_from_the_page(browser, server):
    put_script(browser, "a", (Path(__file__).parent / "data" / "scripts_cli" / "short_job.txt").read_text())
    wait(browser, lambda d: not card(d, "a").find_elements(By.CSS_SELECTOR, '[data-role="findings"] li.error'))
    card(browser, "a").find_element(By.CSS_SELECTOR, 'button[data-action="run"]').click()
    job_line = card(browser, "a").find_element(By.CSS_SELECTOR, '[data-role="job"]')
    wait(browser, lambda d: job_line.get_attribute("data-outcome") == "finished", 40)
    assert "5/5 frames, last line executed 6" in job_line.text
    browser.save_screenshot(os.environ.get("ARMCTL_SCREENSHOT", str(Path(os.environ.get("TMPDIR", "/tmp")) / "armctl-serve-page.png")))


def test_jog_buttons_move_the_arm_while_held_and_it_stops_on_release_and_on_a_closed_page(browser, tmp_path):
    """Hold J1+ (the page's 25 ms heartbeat): joint 1 turns; release: it stops.  Hold J1− and
    leave the page (its WebSocket closes, no release ever comes): it stops too — short of the
    joint's limit (±170°), which a jog that never stopped would reach in seconds (an arm in real
    time: at speed 20 a 0.15 s hold already reaches it)."""
    import time

    from selenium.webdriver.common.action_chains import ActionChains

    with served("--arm", "a=sim://", journal=tmp_path) as server:
        def joint1() -> float:
            return server.request("GET", "/api/arms/a/status")[1]["joints"][0]

        def settled() -> float:
            """Joint 1 once two reads 0.3 s apart agree (the arm stands still)."""
            deadline = time.monotonic() + 10
            before = joint1()
            while time.monotonic() < deadline:
                time.sleep(0.3)
                now = joint1()
                if now == before:
                    return now
                before = now
            raise AssertionError("joint 1 never stopped moving")

        for ending, jog in (("release", "j1_plus"), ("closed page", "j1_minus")):
            browser.get(server.base + "/")
            wait(browser, lambda d: card(d, "a").find_element(By.CSS_SELECTOR, ".badge").text == "in control")
            card(browser, "a").find_element(By.TAG_NAME, "details").click()
            button = card(browser, "a").find_element(By.CSS_SELECTOR, f'button[data-jog="{jog}"]')
            start = settled()
            ActionChains(browser).click_and_hold(button).perform()
            time.sleep(0.3)
            if ending == "release":
                ActionChains(browser).release(button).perform()
            else:
                browser.get("about:blank")
            stopped = settled()
            assert abs(stopped - start) > 0.5 and abs(stopped) < 160, (ending, start, stopped)  # turned while held, then stood


def another_users_socket(server, arm: str) -> tuple[socket.socket, dict]:
    """A WebSocket of another client asking to control ``arm`` (kept open: control lasts while it
    is), and its hello."""
    host, port = server.base.removeprefix("http://").split(":")
    raw = socket.create_connection((host, int(port)), timeout=10)
    raw.sendall(f"GET /api/arms/{arm}/events?control=1&client=other HTTP/1.1\r\nHost: {host}:{port}\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                "Sec-WebSocket-Version: 13\r\n\r\n".encode())
    data = b""
    while b"\r\n\r\n" not in data or len(data) < data.index(b"\r\n\r\n") + 8:
        data += raw.recv(4096)
    frame = data[data.index(b"\r\n\r\n") + 4:]
    size, start = (frame[1], 2) if frame[1] < 126 else (int.from_bytes(frame[2:4], "big"), 4)  # (unmasked, under 64 kB)
    while len(frame) < start + size:
        frame += raw.recv(4096)
    return raw, json.loads(frame[start:start + size])


def test_a_page_controls_only_the_arms_its_user_takes(browser, tmp_path):
    """The page asked to control every arm it showed: in a workshop the first page opened
    controlled every arm and everyone else was read-only on all of them.  Now a page showing
    several arms controls an arm once its user takes it (its button) and until they release it;
    another user takes the other arm meanwhile."""
    with served("--arm", "a=sim://?speed=20", "--arm", "b=sim://?speed=20", journal=tmp_path) as server:
        browser.get(server.base + "/")
        wait(browser, lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1")
        wait(browser, lambda d: [card(d, arm).find_element(By.CSS_SELECTOR, ".badge").text for arm in "ab"]
             == ["free", "free"])
        card(browser, "a").find_element(By.CSS_SELECTOR, 'button[data-action="control"]').click()
        wait(browser, lambda d: card(d, "a").find_element(By.CSS_SELECTOR, ".badge").text == "in control")
        other_b, hello_b = another_users_socket(server, "b")
        other_a, hello_a = another_users_socket(server, "a")
        try:
            assert (hello_b["control"], hello_a["control"]) == (True, False)
            wait(browser, lambda d: card(d, "b").find_element(By.CSS_SELECTOR, ".badge").text == "read-only")
            other_a.close()
            card(browser, "a").find_element(By.CSS_SELECTOR, 'button[data-action="control"]').click()  # Release
            wait(browser, lambda d: card(d, "a").find_element(By.CSS_SELECTOR, ".badge").text == "free")
            wait(browser, lambda d: server.request("GET", "/api/server")[1]["a"]["controlled"] is False)
        finally:
            other_b.close()
            other_a.close()
