"""Benchmark of remote execution (docs/remote.md): per example, the bytes
of the frames of one release instant (UP + DOWN, on the wire), their time
at 115200 baud and at 1 Mbaud against the earliest deadline, and the round
trip per release instant measured in lock-step between the host's
interpreter (`easylab remote --fast`'s engine, in this process, timed from
START: start-up excluded) and the host board's proxy over a pty. Then
the AVR proxy in the simavr harness in real time against `easylab remote`
at each baud rate: its CPU cycles per release instant (the slope of the
harness's awake cycles between two run lengths), the frames' wire time in
cycles, and the round trip with the host's share (the lock-step figure
above); and the proxy's flash and RAM on the ATmega328P. Prints tables and
writes ``<out_dir>/remote.json``.

    python bench/bench_remote.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

from easylab.pipeline import lower_file  # noqa: E402
from easylab.remote.budget import link_budget  # noqa: E402
from easylab.remote.device_model import device_model  # noqa: E402
from easylab.remote.proxy import build_proxy  # noqa: E402
from easylab.remote.stimulus import device_columns  # noqa: E402

EXAMPLES = {"blink": "2s", "line_follower": "3s", "pneumatic_cylinder": "3600ms", "pt100_sensor": "3500ms"}
BAUDS = (115200, 1_000_000)
# The AVR proxy in real time: an example whose 10 ms deadlines fit at both
# baud rates; the size on the ATmega328P: blink (pt100_sensor's LED pin,
# PB7, is a crystal pin there).
AVR_RUN = ("pt100_sensor", "atmega2560", "1s")
AVR_SIZE = ("blink", "atmega328p")
# Remote execution at 1 kHz: blink (a 1 ms task) through the AVR proxy at
# 1 Mbaud in real time, 10,000 instants a run, on an idle machine and with
# part of the test suite running beside it.
ONE_KHZ = ("blink", "atmega328p", 1_000_000, "10s", 3)
SUITE_BESIDE = [sys.executable, "-m", "pytest", "-q", "-n", "2", "-p", "no:cacheprovider", "tests/frontend",
                "tests/sdf"]


def _device_stimulus(stimulus: Path, program, out: Path) -> Path | None:
    text = device_columns(stimulus.read_text(), program)
    if text is None:
        return None
    out.write_text(text)
    return out


def _round_trip(name: str, program, work: Path, duration: str) -> tuple[int, float]:
    """(release instants, seconds) of the interpreter in lock-step with the
    host board's proxy over a pty for ``duration`` of logical time, timed
    in this process from START to the last DOWN (start-up, plug-ins and
    HELLO excluded): the host's share of a round trip, and a pty's."""
    from easylab.interp.clock import Clock
    from easylab.interp.plugins import PluginCache
    from easylab.interp.stimulus import load as load_stimulus
    from easylab.remote.host import RemoteEngine
    from easylab.remote.link import Link

    exe = build_proxy(program, "host", work / "proxy").executable
    stimulus = ROOT / "examples" / f"{name}.stimulus.csv"
    devices = _device_stimulus(stimulus, program, work / "devices.csv")
    link_path = work / "link"
    proxy = subprocess.Popen([str(exe), "--fast", "--link", f"pty:{link_path}",
                              *(["--stimulus", str(devices)] if devices else [])],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
    try:
        while not link_path.exists():
            time.sleep(0.01)
        model = device_model(program)
        cache = PluginCache()
        cache.load_all(program.specs)
        link = Link(str(link_path), model)
        link.connect()
        engine = RemoteEngine(program, model, link, load_stimulus(str(stimulus), program), plugin_cache=cache)
        clock = Clock(None)
        engine.clock = clock
        link.start(lock_step=True)
        start = time.perf_counter()
        engine.run(_us(duration), clock)
        seconds = time.perf_counter() - start
        link.stop()
        link.close()
        engine.shutdown()
        proxy.wait(timeout=30)
    finally:
        if proxy.poll() is None:
            proxy.kill()
    return engine.frames, seconds


def _us(text: str) -> int:
    from easylab.cli.run_command import parse_duration

    return parse_duration(text)


_REPORT = re.compile(r"cycles (\d+) \(asleep (\d+)\), instants (\d+)")


def _report(err: str) -> tuple[int, int, int]:
    """(cycles, awake cycles, instants) of the harness's --report."""
    m = _REPORT.search(err)
    return int(m.group(1)), int(m.group(1)) - int(m.group(2)), int(m.group(3))


def _avr_idle_share(built) -> float:
    """Awake cycles per cycle of the proxy waiting for a host (its tick
    interrupts and polling): simavr flat out, deterministic."""
    proc = subprocess.run([str(built.simulator), "--uart0", "null", "--fast", "--cycles", "16000000", "--report"],
                          capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    cycles, awake, _ = _report(proc.stderr)
    return awake / cycles


def _avr_run(built, name: str, program, baud: int, work: Path, duration: str) -> tuple[int, int, int]:
    """(cycles, awake cycles, instants) of the AVR proxy in simavr (the
    harness's --report) in real time, through a run of ``easylab remote``
    of ``duration``. Awake: every cycle the MCU does not sleep (tick
    interrupts, device reads, the frames' CRC and COBS, a wake-up per
    UART byte, polling)."""
    stimulus = ROOT / "examples" / f"{name}.stimulus.csv"
    work.mkdir(parents=True, exist_ok=True)
    devices = _device_stimulus(stimulus, program, work / "devices.csv")
    link = work / "link"
    # The link is the first UART no device claims: uart0 here.
    sim = subprocess.Popen([str(built.simulator), "--uart0", f"pty:{link}", "--report",
                            *(["--stimulus", str(devices)] if devices else [])],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        while not link.exists():
            time.sleep(0.01)
        subprocess.run([sys.executable, "-m", "easylab", "remote", str(ROOT / "examples" / f"{name}.elab"),
                        "--target", str(link), "--baud", str(baud), "--duration", duration, "--stimulus",
                        str(stimulus)], check=True, stdin=subprocess.DEVNULL, capture_output=True)
    finally:
        sim.send_signal(signal.SIGTERM)
        err = sim.communicate(timeout=30)[1]
    return _report(err)


def _avr_proxy(work: Path, figures: dict, tiny: bool) -> dict:
    """The AVR proxy's round trip per release instant at each baud rate and
    its size on the ATmega328P."""
    name, mcu, duration = AVR_RUN
    program, _ = lower_file(ROOT / "examples" / f"{name}.elab")
    model = device_model(program)
    result = {"example": name, "mcu": mcu}
    for baud in BAUDS[-1:] if tiny else BAUDS:
        built = build_proxy(program, "avr", work / f"avr-{baud}", mcu=mcu, sim=True, baud=baud)
        clock = built.board.clock_hz
        idle = _avr_idle_share(built)
        run = _us("300ms" if tiny else duration)
        runs = [_avr_run(built, name, program, baud, work / f"avr-{baud}-{k}", f"{k * run}us") for k in (1, 4)]
        # Beyond what waiting costs, per instant: the slope between the two
        # runs (start-up, the wait for the host and STOP cancel; what is
        # left varies by some 300000 cycles a run, hence runs 3 s apart).
        (c1, a1, n1), (c2, a2, n2) = runs
        proxy_cycles = round(((a2 - idle * c2) - (a1 - idle * c1)) / max(n2 - n1, 1))
        # Its load: that, and waiting between two release instants.
        spacing = model.hyperperiod * model.tick_us * clock / 1e6 / max(1, sum(1 for i in model.instants if i.release))
        worst = max(link_budget(program, model, baud), key=lambda b: b.wire_us / b.deadline_us)
        wire_cycles = round(worst.wire_us * clock / 1e6)
        host_us = figures[name]["lock_step_round_trip_us"]
        result[str(baud)] = {
            "proxy_cycles_per_instant": proxy_cycles,
            "proxy_load_percent": round(100 * (proxy_cycles / spacing + idle), 1),
            "wire_cycles": wire_cycles, "host_share_us": host_us,
            "round_trip_us": round((proxy_cycles + wire_cycles) / clock * 1e6 + host_us, 1),
            "deadline_ms": worst.deadline_us / 1000}
    name, mcu = AVR_SIZE
    program, _ = lower_file(ROOT / "examples" / f"{name}.elab")
    size = build_proxy(program, "avr", work / "avr-size", mcu=mcu).compiled.size
    result["size"] = {"example": name, "mcu": mcu, "flash": size.flash, "ram": size.ram,
                      "flash_max": size.flash_max, "ram_max": size.ram_max}
    return result


_COUNTED = re.compile(r"the proxy counted (\d+) overruns")
_SAFE = re.compile(r"at ([\d.]+) s the proxy applied its safe values")


def _one_khz_run(built, program_path: Path, work: Path, duration: str, tcp: bool, options: tuple) -> dict:
    """One real-time run of ``easylab remote OPTIONS`` against the AVR proxy
    in simavr: the instants it ran, the proxy's overruns (values that came
    after their deadline), and whether it ended in the safe state (K late
    in a row). ``tcp``: over a TCP link (the harness on 127.0.0.1), else a
    pty."""
    work.mkdir(parents=True, exist_ok=True)
    if tcp:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        uart, target = f"tcp:{port}", f"socket://127.0.0.1:{port}"
    else:
        uart = target = str(work / "link")
    sim = subprocess.Popen([str(built.simulator), "--uart0", uart if tcp else f"pty:{uart}"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        while not tcp and not Path(uart).exists():
            time.sleep(0.01)
        if tcp:
            time.sleep(0.5)  # the harness listens
        host = subprocess.run([sys.executable, "-m", "easylab", "remote", str(program_path), "--target", target,
                               "--baud", str(ONE_KHZ[2]), "--duration", duration, "--stimulus",
                               str(program_path.with_suffix(".stimulus.csv")), *options],
                              stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=300)
    finally:
        sim.send_signal(signal.SIGTERM)
        sim.communicate(timeout=30)
    safe = _SAFE.search(host.stderr)
    counted = _COUNTED.search(host.stderr)
    if host.returncode != 0 and safe is None:
        raise RuntimeError(f"easylab remote failed:\n{host.stderr}")
    instants = round(float(safe.group(1)) * 1000) if safe else _us(duration) // 1000
    # A run that ended in the safe state had K late values in a row at least.
    late = int(counted.group(1)) if counted else (device_model(lower_file(program_path)[0]).overrun_limit if safe
                                                  else 0)
    return {"instants": instants, "overruns": late, "safe_state": safe is not None}


# (setting, the suite beside, over TCP, easylab remote's options): the
# default polls the link at blink's 1 ms deadline; `--wait sleep` is the
# wait the host had before (docs/remote.md, "Real time at 1 kHz").
ONE_KHZ_SETTINGS = (("idle", False, False, ()), ("idle_tcp", False, True, ()),
                    ("idle_sleeping", False, False, ("--wait", "sleep")),
                    ("idle_tcp_sleeping", False, True, ("--wait", "sleep")),
                    ("idle_realtime_tcp", False, True, ("--realtime",)), ("suite_beside", True, False, ()),
                    ("suite_beside_tcp", True, True, ()), ("suite_beside_realtime_tcp", True, True, ("--realtime",)))


def _one_khz(work: Path, tiny: bool) -> dict:
    """Overruns per 10,000 instants of blink at 1 kHz through the AVR proxy
    at 1 Mbaud in real time: idle and with part of the suite beside it, each
    over a pty and a TCP link, polling, sleeping and with `--realtime`."""
    name, mcu, baud, duration, runs = ONE_KHZ
    model = ROOT / "examples" / f"{name}.elab"
    program, _ = lower_file(model)
    built = build_proxy(program, "avr", work / "one-khz", mcu=mcu, sim=True, baud=baud)
    duration, runs = ("300ms", 1) if tiny else (duration, runs)
    result = {"example": name, "mcu": mcu, "baud": baud}
    for setting, beside, tcp, options in ONE_KHZ_SETTINGS:
        load = None
        if beside:
            load = subprocess.Popen(["sh", "-c", 'while :; do "$@" >/dev/null 2>&1; done', "sh", *SUITE_BESIDE],
                                    cwd=ROOT, stdin=subprocess.DEVNULL, start_new_session=True)
            time.sleep(1.0)
        try:
            each = [_one_khz_run(built, model, work / f"one-khz-{setting}-{k}", duration, tcp, options)
                    for k in range(runs)]
        finally:
            if load is not None:
                os.killpg(load.pid, signal.SIGTERM)
                load.wait(timeout=30)
        instants = sum(r["instants"] for r in each)
        result[setting] = {"runs": each, "overruns_per_10000": round(sum(r["overruns"] for r in each) * 10000
                                                                      / max(instants, 1), 1),
                           "ended_safe": sum(r["safe_state"] for r in each)}
    return result


def main(out_dir: Path, tiny: bool = False) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    examples = {"pt100_sensor": "200ms"} if tiny else EXAMPLES
    figures = {}
    print(f"{'example':20} {'bytes/instant':>13} {'115200 baud ms':>14} {'1 Mbaud ms':>10} {'deadline ms':>11} "
          f"{'round trip us':>13}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, duration in examples.items():
            program, _ = lower_file(ROOT / "examples" / f"{name}.elab")
            model = device_model(program)
            worst = {baud: max(link_budget(program, model, baud), key=lambda b: b.wire_us / b.deadline_us)
                     for baud in BAUDS}
            instants, seconds = _round_trip(name, program, Path(tmp) / name, duration)
            b = worst[BAUDS[0]]
            figures[name] = {
                "bytes_per_instant": b.up_bytes + b.down_bytes, "up_bytes": b.up_bytes, "down_bytes": b.down_bytes,
                "deadline_ms": b.deadline_us / 1000,
                **{f"wire_ms_{baud}": round(worst[baud].wire_us / 1000, 3) for baud in BAUDS},
                **{f"fits_{baud}": worst[baud].fits for baud in BAUDS},
                "lock_step_instants": instants, "lock_step_round_trip_us": round(seconds / max(instants, 1) * 1e6, 1),
            }
            f = figures[name]
            print(f"{name:20} {f['bytes_per_instant']:>13} {f['wire_ms_115200']:>14} {f['wire_ms_1000000']:>10} "
                  f"{f['deadline_ms']:>11g} {f['lock_step_round_trip_us']:>13}")
        avr = _avr_proxy(Path(tmp), figures, tiny)
    print(f"\nAVR proxy ({avr['example']}, {avr['mcu']}, simavr, real time):")
    print(f"{'baud':>8} {'proxy cycles':>12} {'load %':>6} {'wire cycles':>11} {'host us':>8} {'round trip us':>13} "
          f"{'deadline ms':>11}")
    for baud in BAUDS:
        if str(baud) in avr:
            a = avr[str(baud)]
            print(f"{baud:>8} {a['proxy_cycles_per_instant']:>12} {a['proxy_load_percent']:>6} {a['wire_cycles']:>11} "
                  f"{a['host_share_us']:>8} {a['round_trip_us']:>13} {a['deadline_ms']:>11g}")
    size = avr["size"]
    print(f"AVR proxy of {size['example']} on the {size['mcu']}: flash {size['flash']} of {size['flash_max']} bytes, "
          f"RAM {size['ram']} of {size['ram_max']} bytes")
    figures["avr_proxy"] = avr
    with tempfile.TemporaryDirectory() as tmp:
        khz = _one_khz(Path(tmp), tiny)
    print(f"\n{khz['example']} at 1 kHz through the AVR proxy ({khz['mcu']}) at {khz['baud']} baud, real time:")
    for setting, *_ in ONE_KHZ_SETTINGS:
        k = khz[setting]
        print(f"  {setting:25} overruns per 10,000 instants {k['overruns_per_10000']:>7}, runs ended in the safe "
              f"state {k['ended_safe']} of {len(k['runs'])}: " + ", ".join(f"{r['instants']} instants "
                                                                         f"{r['overruns']} overruns"
                                                                         for r in k["runs"]))
    figures["one_khz"] = khz
    (out_dir / "remote.json").write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "bench" / "results")
