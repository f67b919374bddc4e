"""Review of ``armctl serve`` as its users meet it: a refused resume in the server's words, jog
messages during the shutdown wait, a ``dropped`` event on the page.  The installed command on a
free loopback port (tests/serve_process.py)."""
from __future__ import annotations

import asyncio
import json
import signal
import time

import pytest

aiohttp = pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import served  # noqa: E402
from test_server_api import long_job  # noqa: E402

pytestmark = pytest.mark.timeout(60)

VIRTUAL = "sim://?clock=virtual"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z120\nG1 Z100\n"
CLI_WORDS = ("--resume", "--port", "--from-line", "--other-port")


def test_a_refused_resume_speaks_the_server_words(tmp_path):
    """A job of a server that has stopped since, on its simulated arm (gone with its process),
    resumed by the next server: refused (422, nothing sent) naming the job the request named and
    the server's ways out, not ``armctl run``'s flags."""
    with served("--arm", f"a={VIRTUAL}", journal=tmp_path) as server:
        status, created = server.request("POST", "/api/arms/a/jobs?name=job.txt", JOB)
        assert status == 201, created
        assert server.wait_job("a", created["id"])["outcome"] == "finished"
    with served("--arm", f"a={VIRTUAL}", journal=tmp_path) as server:
        status, refused = server.request("POST", f"/api/arms/a/jobs?resume={created['id']}")
    assert status == 422 and refused["code"] == "refused", refused
    message = refused["error"]
    assert "does not outlive its process" in message, message
    assert f"?resume={created['id']}" in message and "POST /api/arms/a/jobs" in message, message
    assert not any(flag in message for flag in CLI_WORDS), message


@pytest.mark.realtime
def test_no_jog_moves_an_arm_while_the_server_shuts_down(tmp_path):
    """SIGINT while arm ``a``'s job runs: the server waits for that job to stop (the arm to come to
    rest), its WebSockets still open.  A jog on arm ``b``, idle, from the page controlling it, was
    carried out meanwhile (its joystick frames went, a ``jog`` event) — only the dead-man's lease
    capped it.  Nothing may move an arm while the server shuts down: refused (an ``error`` event)."""
    async def main(server) -> list:
        ws = server.base.replace("http://", "ws://") + "/api/arms/b/events?control=1&client=page"
        async with aiohttp.ClientSession() as session, session.ws_connect(ws) as page:
            hello = await page.receive_json(timeout=10)
            assert hello["event"] == "hello" and hello["control"] is True, hello
            status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/a/jobs?name=long.txt",
                                                      long_job(40))
            assert status == 201, created
            while (await asyncio.to_thread(server.request, "GET", f"/api/arms/a/jobs/{created['id']}"))[1][
                    "frames_sent"] < 3:
                await asyncio.sleep(0.02)
            server.process.send_signal(signal.SIGINT)
            deadline = time.monotonic() + 10
            while (await asyncio.to_thread(server.request, "POST", "/api/arms/b/stop"))[0] != 503:  # stopping now
                assert time.monotonic() < deadline, "the server did not begin to stop"
                await asyncio.sleep(0.02)
            answers = []
            for _ in range(10):  # a held button's heartbeats, for 0.3 s
                await page.send_json({"jog": "j1_plus"})
                await asyncio.sleep(0.03)
            await page.send_json({"jog": None})
            async for message in page:
                if message.type == aiohttp.WSMsgType.TEXT and json.loads(message.data)["event"] in ("jog", "error"):
                    answers.append(json.loads(message.data))
            return answers

    with served("--arm", "a=sim://?speed=1", "--arm", "b=sim://", journal=tmp_path) as server:
        answers = asyncio.run(main(server))
        assert server.process.wait(30) == 130
    moved = [a for a in answers if a["event"] == "jog" and any(frame != [128] for frame in a["frames"])]
    assert moved == [], moved
    refused = [a for a in answers if a["event"] == "error"]
    assert refused and all("stopping" in a["error"] for a in refused), answers


# the page's socket losing events as the server loses them for a page that falls behind: not shown,
# counted, then the server's ``dropped`` event with their count (armctl/server/hub.py)
LOSE_EVENTS = """
const card = window.armCards.find(c => c.name === arguments[0]);
const deliver = card.ws.onmessage;
window.lost = 0; window.losing = true;
card.ws.onmessage = m => { if (window.losing) window.lost++; else deliver(m); };
window.catchUp = () => { window.losing = false;
  deliver({data: JSON.stringify({arm: card.name, event: "dropped", count: window.lost})}); };
"""


@pytest.mark.realtime
@pytest.mark.timeout(120)
def test_the_page_says_events_were_lost_and_reads_the_job_again(tmp_path):
    """A page too slow to read loses events (the server's queue for it is full) and is then sent
    ``dropped`` with their count.  The page ignored it: nothing said, and a job whose summary was
    among the lost ones stayed shown running ("job …: 2/7 frames", no outcome) for good."""
    pytest.importorskip("selenium.webdriver", reason="Selenium is not installed (pip install selenium)")
    from test_server_browser import headless_chromium, put_script, wait  # (skips without a browser)
    from selenium.webdriver.common.by import By

    def job_line(driver):
        return driver.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] [data-role="job"]')

    with served("--arm", "a=sim://?speed=4", journal=tmp_path) as server, headless_chromium() as driver:
        driver.get(server.base + "/")
        wait(driver, lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "1")
        put_script(driver, "a", long_job(6))
        driver.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] button[data-action="run"]').click()
        wait(driver, lambda d: "last line executed" in job_line(d).text)
        driver.execute_script(LOSE_EVENTS, "a")
        job_id = job_line(driver).text.split()[1].rstrip(":")
        assert server.wait_job("a", job_id)["outcome"] == "finished"
        assert job_line(driver).get_attribute("data-outcome") == "", job_line(driver).text  # its end lost
        driver.execute_script("window.catchUp()")
        wait(driver, lambda d: job_line(d).get_attribute("data-outcome") == "finished")
        message = driver.find_element(By.ID, "message").text
        lost = driver.execute_script("return window.lost")
    assert lost > 0 and f"a: {lost} events were lost" in message, (lost, message)
