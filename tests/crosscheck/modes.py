"""The ways a model runs, each giving a trace of the same model and
stimulus: local execution (the reference), the host board built with the
undefined-behaviour sanitizer, the AVR and the PIC18 in their simulators,
the F16's 16-bit proxy in s51, and remote execution in lock-step with a
host-board proxy or an AVR proxy in simavr.

Every mode is what a user runs (``easylab build``, ``run``, ``proxy``,
``remote`` and the built programs). A build that the board refuses because
the model does not fit the part is a skip, counted; every other failure
is a finding."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

SANITIZE = "-fsanitize=undefined -fno-sanitize-recover=all"
TIMEOUT = 600

# A build that fails only because the model is larger than the part: a
# skip, not a finding (the boards' own wording).
DOES_NOT_FIT = re.compile(r"does not fit|too large for|overflow(?:s|ed)? (?:the|its)|exceeds the|no UART|"
                          r"RAM.*(?:over|exceed)|flash.*(?:over|exceed)|not enough (?:RAM|memory|program)|"
                          r"region .* overflowed|has no (?:pin|ADC|PWM)", re.I)


@dataclass
class Outcome:
    """A mode's result for one model: ``status`` is ``trace`` (then
    ``trace`` holds it), ``skip`` (does not fit the part) or ``fail``."""

    status: str
    trace: bytes = b""
    detail: str = ""


def easylab(*args, cwd: Path | None = None, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, cwd=cwd)


def program(*args, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


def built(proc: subprocess.CompletedProcess, key: str = "") -> tuple[Path | None, Outcome | None]:
    """The program a build names (its last line, or its ``simulator:``
    line with ``key``), or the Outcome of a failed build."""
    if proc.returncode != 0:
        text = (proc.stdout + proc.stderr).strip()
        if DOES_NOT_FIT.search(text) and "Internal Error" not in text:
            return None, Outcome("skip", detail=text[-400:])
        return None, Outcome("fail", detail="build: " + text[-3000:])
    if key:
        line = next((ln for ln in proc.stdout.splitlines() if ln.startswith(key)), None)
        if line is None:
            return None, Outcome("fail", detail=f"build: no '{key}' line:\n{proc.stdout}")
        return Path(line.split(": ", 1)[1]), None
    return Path(proc.stdout.strip().splitlines()[-1]), None


def traced(proc: subprocess.CompletedProcess, trace: Path, *, quiet: bool = True) -> Outcome:
    """The Outcome of a run that wrote ``trace``; with ``quiet`` anything
    on stderr (a sanitizer's report) is a failure too."""
    if proc.returncode != 0 and DOES_NOT_FIT.search(proc.stderr):
        # a simulated part that runs out of what it has (the F16 proxy's
        # 8051 stack), as the program says: a skip, as at build time
        return Outcome("skip", detail=proc.stderr[-400:])
    if proc.returncode != 0 or (quiet and proc.stderr.strip()):
        return Outcome("fail", detail=f"run: status {proc.returncode}\n{proc.stderr[-3000:]}")
    if not trace.is_file():
        return Outcome("fail", detail="run: no trace written")
    return Outcome("trace", trace.read_bytes())


def run_args(case, trace: Path) -> list[str]:
    return ["--fast", "--duration", f"{case.duration_ms}ms", "--stimulus", str(case.stimulus), "--trace", str(trace)]


def local(case, work: Path) -> Outcome:
    trace = work / "local.csv"
    return traced(easylab("run", case.model, *run_args(case, trace)), trace)


def host(case, work: Path) -> Outcome:
    exe, failed = built(easylab("build", case.model, "--board", "host", f"--cflags={SANITIZE}", "-o", work / "host"))
    if failed:
        return failed
    trace = work / "host.csv"
    return traced(program(exe, *run_args(case, trace)), trace)


def simulated(board: str, mcu: str | None):
    """A mode running the board's simulation build."""
    def mode(case, work: Path) -> Outcome:
        out = work / f"{board}-{mcu or 'default'}"
        mcu_args = ["--mcu", mcu] if mcu else []
        sim, failed = built(easylab("build", case.model, "--board", board, *mcu_args, "--sim", "-o", out),
                            "simulator: ")
        if failed:
            return failed
        trace = out / "trace.csv"
        return traced(program(sim, *run_args(case, trace)), trace, quiet=False)
    return mode


def lock_step(case, out: Path, proxy_cmd: list[str], link: Path) -> Outcome:
    """`easylab remote --fast` against a proxy started with ``proxy_cmd``
    (which opens ``link``), the proxy given the stimulus's device columns."""
    from easylab.pipeline import lower_file
    from easylab.remote.stimulus import device_columns

    program_ir, _ = lower_file(case.model)
    devices = device_columns(case.stimulus.read_text(), program_ir)
    if devices is not None:
        (out / "devices.csv").write_text(devices)
        proxy_cmd = proxy_cmd + ["--stimulus", str(out / "devices.csv")]
    proxy = subprocess.Popen(proxy_cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 10
        while not link.exists() and time.monotonic() < deadline and proxy.poll() is None:
            time.sleep(0.01)
        trace = out / "trace.csv"
        outcome = traced(easylab("remote", case.model, "--target", link, *run_args(case, trace)), trace, quiet=False)
        if outcome.status != "trace":
            return outcome
        try:  # STOP ends a host-board proxy; a simulated one is ended here
            proxy.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proxy.terminate()
        _, err = proxy.communicate(timeout=30)
        if proxy.returncode not in (0, -15):
            return Outcome("fail", detail=f"proxy: status {proxy.returncode}\n{err}")
        return outcome
    finally:
        if proxy.poll() is None:
            proxy.kill()
            proxy.communicate()


def remote_host(case, work: Path) -> Outcome:
    """Remote execution in lock-step with a host-board proxy."""
    out = work / "proxy-host"
    exe, failed = built(easylab("proxy", case.model, "-o", out))
    if failed:
        return failed
    return lock_step(case, out, [str(exe), "--link", f"pty:{out / 'link'}", "--fast"], out / "link")


def remote_avr(case, work: Path) -> Outcome:
    """Remote execution in lock-step with an ATmega2560 proxy in simavr,
    its link on the UART the build gives it."""
    out = work / "proxy-avr"
    sim, failed = built(easylab("proxy", case.model, "--board", "avr", "--mcu", "atmega2560", "--sim", "-o", out),
                        "simulator: ")
    if failed:
        return failed
    uart = re.search(r"#define EL_AVR_REMOTE_UART (\d+)u", (out / "el_avr_config.h").read_text()).group(1)
    return lock_step(case, out, [str(sim), f"--uart{uart}", f"pty:{out / 'link'}", "--fast"], out / "link")


# name -> (the part whose pins the model uses, runner). The host, AVR and
# remote modes share the ATmega2560's model; each other part has its own.
MODES = {
    "local": ("atmega2560", local),
    "host": ("atmega2560", host),
    "avr": ("atmega2560", simulated("avr", "atmega2560")),
    "avr328": ("atmega328p", simulated("avr", "atmega328p")),
    "pic18": ("pic18f4620", simulated("pic18", "pic18f4620")),
    "f16": ("mb90f543", simulated("f16", None)),
    "remote-host": ("atmega2560", remote_host),
    "remote-avr": ("atmega2560", remote_avr),
}
