"""The interactive console driven the way a person uses it, in tmux: tab
completion, a live watch, a breakpoint hit while the program runs."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time

import pytest

from debug_testlib import builds, env_with_tools, firmware  # noqa: F401 (fixtures)

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


class Pane:
    def __init__(self, sock: str, command: list[str], env: dict):
        self.sock = sock
        self.tmux("new-session", "-d", "-s", "dbg", "-x", "120", "-y", "40", " ".join(map(_quote, command)),
                  env=env)

    def tmux(self, *args, env=None):
        return subprocess.run(["tmux", "-L", self.sock, *args], capture_output=True, text=True, check=True,
                              env=env).stdout

    def keys(self, *keys):
        self.tmux("send-keys", "-t", "dbg", *keys)

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "dbg")

    def wait_for(self, text: str, timeout: float = 10.0) -> str:
        text = text.rstrip()  # capture-pane drops trailing spaces
        deadline = time.monotonic() + timeout
        while True:
            screen = self.screen()
            if text in screen:
                return screen
            if time.monotonic() > deadline:
                raise AssertionError(f"{text!r} not on the screen:\n{screen}")
            time.sleep(0.05)

    def wait_line(self, start: str, timeout: float = 10.0) -> str:
        """The first line of the screen that starts with `start`."""
        deadline = time.monotonic() + timeout
        while True:
            for line in self.screen().splitlines():
                if line.startswith(start):
                    return line
            if time.monotonic() > deadline:
                raise AssertionError(f"no line starting with {start!r}:\n{self.screen()}")
            time.sleep(0.05)

    def last_line(self) -> str:
        lines = [line for line in self.screen().splitlines() if line.strip()]
        return lines[-1] if lines else ""

    def close(self):
        subprocess.run(["tmux", "-L", self.sock, "kill-server"], capture_output=True)


def _quote(word: str) -> str:
    import shlex
    return shlex.quote(word)


def test_a_person_at_the_console(builds, firmware, tmp_path):
    fw = firmware(builds["pneumatic_cylinder"], halt=False, fast=False)  # real time, running
    env = env_with_tools()
    env["HOME"] = str(tmp_path)  # the console's history file goes there
    env["TERM"] = "xterm"
    pane = Pane(f"easylab-test-{tmp_path.name}",
                ["env", f"PYTHONPATH={env.get('PYTHONPATH', '')}", f"HOME={tmp_path}", sys.executable, "-m",
                 "easylab.host_tools.debug_console", "--map", str(fw.map_path), str(fw.link)], env)
    try:
        pane.wait_for("(easylab) ")
        # completion of a command, then of an item name
        pane.keys("rea", "Tab")
        pane.wait_for("(easylab) read ")
        pane.keys("start_c", "Tab")
        pane.wait_for("(easylab) read start_cmd ")
        pane.keys("Enter")
        pane.wait_for("start_cmd = false")
        # a live watch: the table is redrawn in place while the program runs
        pane.keys("watch drive PositionControl.pid.integral --every 50ms", "Enter")
        tick1 = pane.wait_line("tick ")
        time.sleep(0.5)
        tick2 = pane.wait_line("tick ")
        assert tick1 != tick2, "the watch does not update"
        assert pane.screen().count("PositionControl.pid.integral  ") == 1, "the table is not redrawn in place"
        pane.keys("C-c")
        pane.wait_for("(watch ended)")
        pane.wait_for("(easylab) ")
        # a breakpoint, completed by name, hit while the program runs
        pane.keys("break at Cylinder.Extend", "Tab", "Tab")
        pane.wait_for("Cylinder.Extended")  # both candidates listed
        pane.keys("i", "Tab")
        pane.wait_for("(easylab) break at Cylinder.Extending ")
        pane.keys("Enter")
        pane.wait_for("breakpoint 0 at step Cylinder.Extending")
        pane.keys("write start_cmd 1", "Enter")
        pane.wait_for("[halted (breakpoint) at breakpoint 0 at step Cylinder.Extending")
        pane.keys("stack", "Enter")
        pane.wait_for("chart       Cylinder: Extending")
        pane.keys("delete 0", "Enter")
        pane.wait_for("deleted breakpoint 0")
        pane.keys("run", "Enter")
        pane.wait_for("running")
        # the history remembers what was typed
        pane.keys("Up")
        time.sleep(0.2)
        assert pane.last_line().endswith("(easylab) run")
        pane.keys("C-u", "quit", "Enter")
        time.sleep(0.5)
        assert (tmp_path / ".easylab_debug_history").read_text().count("write start_cmd 1") == 1
    finally:
        pane.close()
