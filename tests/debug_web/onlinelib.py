"""Helpers of the online mode's tests: `easylab-debug web` processes, a
desktop-sized headless Chromium, the slow stimulus of pneumatic_cylinder.

Firmware processes and builds are those of the debug suite (tests/debug,
debug_testlib); HTTP and waiting are the service panel's (tests/web, weblib).
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "debug"))
sys.path.insert(0, str(HERE.parent / "web"))

from debug_testlib import ROOT  # noqa: E402
from weblib import CHROMIUM_FLAGS, PageServer, http, wait_for  # noqa: E402,F401

MODEL = ROOT / "examples" / "pneumatic_cylinder.elab"
MODEL_FILE = "examples/pneumatic_cylinder.elab"  # as the map's locations name it

# pneumatic_cylinder's cycle slowed down to one step a second (the example's
# own stimulus runs a cycle in 360 ms): Retracted, Extending from 0.5 s with
# the position ramping up, Extended from 1.5 s, Retracting from 2.5 s,
# Retracted from 3.5 s, the same again from 6.5 s, Extending again from
# 11.5 s; a timeout of 10 s.
SLOW_CYCLE = """time_us,start_cmd,position.value,end_out.level,end_in.level,timeout
0,0,0,0,1,10000
500000,1,,,0,
700000,,200,,,
900000,,400,,,
1100000,,600,,,
1300000,,800,,,
1500000,,910,1,,
2500000,0,,,,
2700000,,600,0,,
3000000,,300,,,
3500000,,100,,1,
6500000,1,,,0,
6700000,,200,,,
6900000,,400,,,
7100000,,600,,,
7300000,,800,,,
7500000,,910,1,,
8500000,0,,,,
8700000,,600,0,,
9000000,,300,,,
9500000,,100,,1,
11500000,1,,,0,
"""


def slow_cycle(directory: Path) -> Path:
    path = directory / "slow_cycle.csv"
    path.write_text(SLOW_CYCLE)
    return path


class OnlineServer(PageServer):
    """`easylab-debug web --map MAP TARGET --listen ... [--token T]`."""

    what = "easylab-debug web"
    info = "/api/model"
    start_timeout = 60.0

    def __init__(self, map_path: Path, target: str, listen: str = "127.0.0.1:0", token: str | None = None,
                 model: Path | None = MODEL, extra: list[str] | None = None):
        args = [sys.executable, "-m", "easylab.host_tools.debug_console", "web", "--map", str(map_path), target,
                "--listen", listen, "--timeout", "0.3", *(extra or [])]
        if model is not None:  # else the server finds it by the map's locations
            args += ["--model", str(model)]
        if token is not None:
            args += ["--token", token]
        super().__init__(args, cwd=ROOT)

    def model(self) -> dict:
        return self.document()

    def state(self, after: int = -1) -> dict:
        return self.api("GET", f"/api/state?after={after}").json()


class Browser:
    """Headless Chromium through chromedriver (selenium), desktop-sized."""

    def __init__(self, workdir: Path, width: int = 1400, height: int = 1500):
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        opts = webdriver.ChromeOptions()
        opts.binary_location = "/usr/bin/chromium"
        for flag in CHROMIUM_FLAGS + [f"--user-data-dir={workdir / 'profile'}", f"--window-size={width},{height}"]:
            opts.add_argument(flag)
        opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        self.driver = webdriver.Chrome(options=opts, service=Service("/usr/bin/chromedriver"))

    def get(self, url: str) -> None:
        self.driver.get(url)

    def js(self, script: str, *args):
        return self.driver.execute_script(script, *args)

    def click(self, element_id: str) -> None:
        """A real click (chromedriver's) on the middle of a drawing's element."""
        from selenium.webdriver.common.by import By
        el = self.driver.find_element(By.ID, element_id)
        self.js("arguments[0].scrollIntoView({block: 'center', inline: 'center'})", el)
        el.click()

    def button(self, css: str) -> None:
        from selenium.webdriver.common.by import By
        self.driver.find_element(By.CSS_SELECTOR, css).click()

    def text(self, css: str) -> str | None:
        return self.js("const e = document.querySelector(arguments[0]); return e ? e.textContent : null;", css)

    def active_steps(self) -> list[str]:
        return self.js("return [...document.querySelectorAll('#diagram g.active')].map(g => g.id)")

    def last(self) -> dict | None:
        return self.js("return window.easylabOnline && window.easylabOnline.last")

    def console_errors(self) -> list[dict]:
        return [e for e in self.driver.get_log("browser") if e.get("level") == "SEVERE"]

    def quit(self) -> None:
        self.driver.quit()
