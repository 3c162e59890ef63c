"""End to end in headless Chromium (Debian ``chromium`` + ``chromium-driver``): load the page, ask,
wait for the plan, check what is shown. Screenshots go to build/screenshots/ (or
$CONCEPTBOT_SCREENSHOTS)."""

from __future__ import annotations

import os
import shutil
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import uvicorn

from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.web.app import create_app, local_hosts
from conceptbot.web.runs import RunManager
from conceptbot.web.worker import make_worker
from tests.web.conftest import REQUEST, scripted_bot

SHOTS = Path(os.environ.get("CONCEPTBOT_SCREENSHOTS", Path(__file__).parents[2] / "build" / "screenshots"))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


QUESTION = ClarifyingQuestion(
    "Should I give the apple to the user (something sour)?", "user", ("apple",), (0.5,)
)
CHOOSE = ClarifyingQuestion(
    "Which of these should I give to the user (something sour): the apple, the lemon or the lime? "
    "Name them, or say all or none.",
    "user",
    ("apple", "lemon", "lime"),
    (0.5, 0.6, 0.45),
    kind="choose",
)


def asking_worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
    """A run whose planner is unsure about one object: it asks, and plans by the answer."""
    answer = ask(QUESTION) if ask is not None else None
    plan = ["pick_and_place(apple, user)", "done()"] if answer == "yes" else ["done()"]
    emit("plan", {"plan": plan, "refused": False, "reason": None, "usage": {}})


ONE = ClarifyingQuestion(
    "Which one should I give to the user: the apple, the lemon or the lime? One of them, another, or none.",
    "user",
    ("apple", "lemon", "lime"),
    (0.4, 0.35, 0.25),
    kind="one",
    others=("orange",),
)


def choosing_worker(
    spec: Any,
    emit: Callable[..., None],
    out_dir: Path,
    ask: Any = None,
    question: ClarifyingQuestion = CHOOSE,
) -> None:
    """A run whose planner is unsure about three objects for one target: one question, which go."""
    chosen = question.read(ask(question)) if ask is not None else ()
    plan = [f"pick_and_place({o}, user)" for o in chosen or ()] + ["done()"]
    emit("plan", {"plan": plan, "refused": False, "reason": None, "usage": {}})


def _confident_plan(emit: Callable[..., None], **extra: Any) -> None:
    """Emit a plan with a confidence of 0.42 and the other fields of the event given."""
    plan = ["pick_and_place(apple, user)", "done()"]
    emit("plan", {"plan": plan, "refused": False, "reason": None, "usage": {}, "confidence": 0.42, **extra})


def confident_worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
    """A run whose plan carries a confidence and each target's share of it."""
    shares = [{"to": "user", "confidence": 0.6}, {"to": "bowl", "confidence": 0.7}]
    _confident_plan(emit, confidence_by_target=shares)


FOREIGN = {
    "coverage": 0.9,
    "model": "openai:gpt-4o-mini",
    "fitted_for": "qwen2.5-coder-1.5b",
    "source": "shipped",
    "own": False,
}


def foreign_worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
    """A run planned by a model the shipped conformal thresholds were not fitted for."""
    _confident_plan(emit, confidence_by_target=[], calibration=FOREIGN)


def picking_worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
    """A run whose planner has three candidates for a target taking one: which one."""
    choosing_worker(spec, emit, out_dir, ask, ONE)


READINGS = ('give the user one "fruit"', 'give the user one "fruit", and one "soda"')
READING = ClarifyingQuestion(
    f"Did you mean: {READINGS[0]}, or {READINGS[1]}? One of them, or none.",
    "",
    READINGS,
    (0.6, 0.3),
    kind="reading",
)


def reading_worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
    """A run whose request reads two ways: which reading was meant, then the plan by that one."""
    readings = [
        {"text": READINGS[0], "p": 0.6, "kind": "taken"},
        {"text": READINGS[1], "p": 0.3, "kind": "other"},
    ]
    goal = {"targets": [], "stack": False, "step": "fewer", "readings": readings, "preference": -0.1234}
    emit("goal", {"data": goal})
    chosen = READING.read(ask(READING)) if ask is not None else ()
    plan = {
        (READINGS[0],): ["pick_and_place(apple, user)"],
        (READINGS[1],): ["pick_and_place(apple, user)", "pick_and_place(7up, user)"],
    }
    emit(
        "plan",
        {"plan": [*plan.get(chosen or (), []), "done()"], "refused": False, "reason": None, "usage": {}},
    )


@pytest.fixture
def server(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    worker = getattr(request, "param", None) or make_worker(lambda config, backend: scripted_bot(), False)
    manager = RunManager(worker)
    port = _free_port()
    app = create_app(
        manager,
        backends=["llamacpp:qwen2.5-coder-1.5b"],
        results_dir=tmp_path,
        can_simulate=False,
        allowed_hosts=local_hosts("127.0.0.1", port),
    )
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.time() + 20
    while not server.started and time.time() < deadline:
        time.sleep(0.05)
    assert server.started, "the web server did not start"
    yield f"http://127.0.0.1:{port}"
    server.should_exit = True
    thread.join(10)
    manager.close()


@pytest.fixture
def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    binary, driver = shutil.which("chromium"), shutil.which("chromedriver")
    assert binary and driver, "headless Chromium is missing: run bash scripts/install-browser.sh"
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1280,1600",
    ):
        options.add_argument(flag)
    os.environ.setdefault("SE_OFFLINE", "true")  # never let Selenium Manager look for downloads
    chrome = webdriver.Chrome(service=Service(executable_path=driver), options=options)
    yield chrome
    chrome.quit()


@pytest.mark.slow
def test_ask_and_watch_the_plan_in_chromium(server: str, browser) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as when
    from selenium.webdriver.support.ui import Select, WebDriverWait

    SHOTS.mkdir(parents=True, exist_ok=True)
    wait = WebDriverWait(browser, 30)
    browser.get(server + "/")
    wait.until(lambda b: len(Select(b.find_element(By.ID, "scene")).options) > 5)
    Select(browser.find_element(By.ID, "scene")).select_by_visible_text("example-scissors")
    wait.until(lambda b: "safety scissors" in b.find_element(By.ID, "pickable").get_attribute("value"))
    browser.save_screenshot(str(SHOTS / "web-1-loaded.png"))
    browser.find_element(By.ID, "request").send_keys(REQUEST)
    browser.find_element(By.ID, "run").click()
    wait.until(when.text_to_be_present_in_element((By.ID, "status"), "Done."))
    plan = [li.text for li in browser.find_elements(By.CSS_SELECTOR, "#plan li")]
    assert plan == ["pick_and_place(safety scissors, child)", "done()"]
    properties = browser.find_element(By.ID, "properties").text
    assert "scissors" in properties and "4" in properties
    assert browser.find_element(By.ID, "reasoning").text == "because"
    chosen = browser.find_elements(By.CSS_SELECTOR, "#steps .bar.chosen")
    assert [c.text.split("\n")[0] for c in chosen] == ["pick_and_place(safety scissors, child)", "done()"]
    assert browser.find_element(By.ID, "run").is_enabled()
    assert not browser.find_element(By.ID, "refusal").is_displayed()
    browser.save_screenshot(str(SHOTS / "web-2-plan.png"))
    # The results page says there are no reports yet (the results folder is empty).
    browser.get(server + "/results")
    wait.until(when.text_to_be_present_in_element((By.ID, "reports"), "No reports yet"))
    assert (SHOTS / "web-2-plan.png").stat().st_size > 10_000


def _ask(server: str, browser, box: str) -> None:
    """Open the page, send a request, and wait for the question's ``box`` to show."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as when
    from selenium.webdriver.support.ui import Select, WebDriverWait

    wait = WebDriverWait(browser, 30)
    browser.get(server + "/")
    wait.until(lambda b: len(Select(b.find_element(By.ID, "scene")).options) > 5)
    browser.find_element(By.ID, "request").send_keys("Bring me something sour")
    browser.find_element(By.ID, "run").click()
    wait.until(when.visibility_of_element_located((By.ID, box)))


def _planned(browser) -> list[str]:
    """Wait for the run to finish; the plan's actions as shown."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as when
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(browser, 30).until(when.text_to_be_present_in_element((By.ID, "status"), "Done."))
    return [li.text for li in browser.find_elements(By.CSS_SELECTOR, "#plan li")]


@pytest.mark.slow
@pytest.mark.parametrize("server", [asking_worker], indirect=True)
def test_the_page_asks_and_the_answer_finishes_the_plan(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "question-box")
    assert browser.find_element(By.ID, "question-text").text == QUESTION.text
    browser.save_screenshot(str(SHOTS / "web-3-question.png"))
    browser.find_element(By.ID, "answer-no").click()
    assert _planned(browser) == ["done()"]
    assert not browser.find_element(By.ID, "question-box").is_displayed()


@pytest.mark.slow
@pytest.mark.parametrize("server", [choosing_worker], indirect=True)
def test_the_page_asks_which_objects_go_and_the_ticked_ones_do(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "choose-box")
    assert browser.find_element(By.ID, "question-text").text == CHOOSE.text
    assert not browser.find_element(By.ID, "answer-yes").is_displayed()
    labels = [li.text.strip() for li in browser.find_elements(By.CSS_SELECTOR, "#choose-options li")]
    assert labels == ["apple", "lemon", "lime"]
    browser.find_element(By.ID, "choose-1").click()
    browser.find_element(By.ID, "choose-2").click()
    browser.save_screenshot(str(SHOTS / "web-4-choose.png"))
    browser.find_element(By.ID, "answer-chosen").click()
    assert _planned(browser) == ["pick_and_place(lemon, user)", "pick_and_place(lime, user)", "done()"]


@pytest.mark.slow
@pytest.mark.parametrize("server", [picking_worker], indirect=True)
def test_the_page_asks_which_one_with_radio_buttons(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "choose-box")
    boxes = browser.find_elements(By.CSS_SELECTOR, "#choose-options input")
    assert [b.get_attribute("type") for b in boxes] == ["radio"] * 4
    labels = [li.text.strip() for li in browser.find_elements(By.CSS_SELECTOR, "#choose-options li")]
    assert labels == ["apple", "lemon", "lime", "or another: orange"]  # what the set left out
    boxes[0].click()
    boxes[2].click()  # a radio button: the last one ticked is the one
    browser.save_screenshot(str(SHOTS / "web-5-which-one.png"))
    browser.find_element(By.ID, "answer-chosen").click()
    assert _planned(browser) == ["pick_and_place(lime, user)", "done()"]


@pytest.mark.slow
@pytest.mark.parametrize("server", [picking_worker], indirect=True)
def test_the_person_may_pick_another_than_those_listed(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "choose-box")
    browser.find_elements(By.CSS_SELECTOR, "#choose-options input")[3].click()
    browser.find_element(By.ID, "answer-chosen").click()
    assert _planned(browser) == ["pick_and_place(orange, user)", "done()"]


@pytest.mark.slow
@pytest.mark.parametrize("server", [reading_worker], indirect=True)
def test_the_page_asks_which_reading_was_meant(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "choose-box")
    assert browser.find_element(By.ID, "question-text").text == READING.text
    # The goal says each reading's odds, and which the plan acts on unless told otherwise.
    shown = browser.find_element(By.ID, "targets").text
    assert 'readings (fewer): taken “give the user one "fruit"” P 0.60; dropped' in shown
    assert shown.endswith("P 0.30; the model prefers the dropped one by 0.12 nats")
    boxes = browser.find_elements(By.CSS_SELECTOR, "#choose-options input")
    assert [b.get_attribute("type") for b in boxes] == ["radio"] * 2  # one reading, no "another"
    labels = [li.text.strip() for li in browser.find_elements(By.CSS_SELECTOR, "#choose-options li")]
    assert labels == list(READINGS)
    assert browser.find_element(By.ID, "answer-chosen").text == "This is what I meant"
    boxes[1].click()  # the reading with a comma in it is sent whole
    browser.save_screenshot(str(SHOTS / "web-6-reading.png"))
    browser.find_element(By.ID, "answer-chosen").click()
    assert _planned(browser) == ["pick_and_place(apple, user)", "pick_and_place(7up, user)", "done()"]


@pytest.mark.slow
@pytest.mark.parametrize("server", [picking_worker], indirect=True)
def test_none_of_them_sends_nothing(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "choose-box")
    browser.find_elements(By.CSS_SELECTOR, "#choose-options input")[1].click()  # changed their mind
    browser.find_element(By.ID, "answer-none").click()
    assert _planned(browser) == ["done()"]


@pytest.mark.slow
@pytest.mark.parametrize("server", [confident_worker], indirect=True)
def test_the_page_shows_the_plans_confidence_and_where_it_is_lost(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "plan-box")
    assert _planned(browser) == ["pick_and_place(apple, user)", "done()"]
    assert browser.find_element(By.ID, "confidence").text == (
        "Confidence 0.42 that its calibrated decisions are all right (the user 0.60, the bowl 0.70)"
    )


@pytest.mark.slow
@pytest.mark.parametrize("server", [foreign_worker], indirect=True)
def test_the_page_says_when_the_thresholds_are_another_models(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "plan-box")
    assert browser.find_element(By.ID, "confidence").text == (
        "Confidence 0.42 that its calibrated decisions are all right — the thresholds were fitted for "
        "qwen2.5-coder-1.5b, not for openai:gpt-4o-mini: the 0.9 coverage is not promised (conceptbot "
        "calibrate --conformal fits this model's own)"
    )


@pytest.mark.slow
@pytest.mark.parametrize("server", [asking_worker], indirect=True)
def test_a_plan_without_a_confidence_shows_none(server: str, browser) -> None:
    from selenium.webdriver.common.by import By

    _ask(server, browser, "question-box")
    browser.find_element(By.ID, "answer-yes").click()
    assert _planned(browser) == ["pick_and_place(apple, user)", "done()"]
    assert browser.find_element(By.ID, "confidence").text == ""
