"""Cross-board equivalence beyond the conformance suite's (tests/boards:
every example's own stimulus): VCD traces and the native suites' stimuli
give the host board's trace byte for byte; and the harness itself (pins,
hardware limits, UARTs on ptys, options)."""

from __future__ import annotations

import os
import subprocess
import time
from pathlib import Path

import pytest

from sim_modbus import check_persist_round_trip, check_rtu_frames_kept_apart
from avr_testlib import ROOT, run, stimulus_of

NATIVE = ROOT / "tests" / "native" / "data"


def both(sim_builds, host_builds, name, tmp_path, stimulus: Path | None, duration: str, ext: str = "csv"):
    """(host trace, AVR trace) of one example and stimulus."""
    host_trace, avr_trace = tmp_path / f"host.{ext}", tmp_path / f"avr.{ext}"
    args = ["--fast", "--duration", duration] + (["--stimulus", stimulus] if stimulus else [])
    run(host_builds[name], *args, "--trace", host_trace)
    proc = run(sim_builds[name].simulator, *args, "--trace", avr_trace)
    assert proc.stderr == "", proc.stderr
    return host_trace.read_bytes(), avr_trace.read_bytes()


@pytest.mark.parametrize("name", ["line_follower", "pt100_sensor"])
def test_vcd_traces_are_equal_too(sim_builds, host_builds, name, tmp_path):
    host, avr = both(sim_builds, host_builds, name, tmp_path, stimulus_of(name), "1500ms", "vcd")
    assert host.startswith(b"$comment") and avr == host


# The native tests' stimuli: other inputs, longer runs (pt100_sensor's own
# stops before its out-of-range ADC values, tested below).
@pytest.mark.parametrize("name, stimulus, duration", [
    ("blink", "blink.stimulus.csv", "3s"),
    ("cd_to_dat", "cd_to_dat.stimulus.csv", "400ms"),
    ("line_follower", "line_follower.stimulus.csv", "3s"),
    ("pneumatic_cylinder", "pneumatic_cylinder.stimulus.csv", "3600ms"),
    ("pt100_sensor", "pt100_sensor.stimulus.csv", "2s"),
    ("pt100_sensor", "pt100_stats.stimulus.csv", "5s"),
])
def test_the_native_suites_stimuli_give_equal_traces(sim_builds, host_builds, name, stimulus, duration, tmp_path):
    path = NATIVE / stimulus
    if not path.is_file():  # another suite's data: its absence is not this board's failure
        pytest.fail(f"{path} is missing")
    host, avr = both(sim_builds, host_builds, name, tmp_path, path, duration)
    assert avr == host


def test_16_bit_ticks_wrap_and_the_trace_stays_the_hosts(sim_builds, host_builds, tmp_path):
    """blink's timing allows 16-bit ticks (docs/ir.md, "Dispatcher widths"):
    the firmware's tick wraps at 2^16, 65.5 s of 1 ms ticks. Over two wraps,
    with the param written after each, the harness extends the tick it reads
    and the trace is the host's byte for byte."""
    built = sim_builds["blink"]
    nm = subprocess.run(["avr-nm", "-S", str(built.elf)], capture_output=True, text=True, check=True).stdout
    assert any(line.split()[1:] == ["00000002", "B", "el_avr_sim_tick"] for line in nm.splitlines()), nm
    stim = tmp_path / "wrap.csv"
    stim.write_text("time_us,half_period\n0,500\n70000000,250\n135000000,40\n")
    host, avr = both(sim_builds, host_builds, "blink", tmp_path, stim, "140s")
    assert avr == host
    last = host.splitlines()[-1].split(b",")  # time_us, half_period, led.level
    assert int(last[0]) > 2 * 65536 * 1000 and last[1] == b"40", last


def test_a_value_the_adc_cannot_give_is_an_error(sim_builds, tmp_path):
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,sensor.raw\n0,300\n30000,1024\n")
    proc = run(sim_builds["pt100_sensor"].simulator, "--fast", "--duration", "1s", "--stimulus", stim, "--trace",
               tmp_path / "t.csv", ok=False)
    assert proc.returncode == 1
    assert "sensor.raw = 1024 at 30000 us: the atmega2560's ADC gives 0..1023 (10 bits)" in proc.stderr


def test_stimulus_errors_are_reported_as_on_the_host_board(sim_builds, host_builds, tmp_path):
    stim = tmp_path / "bad.csv"
    stim.write_text("time_us,nonsense\n0,1\n")
    avr = run(sim_builds["blink"].simulator, "--fast", "--duration", "1s", "--stimulus", stim, ok=False)
    host = run(host_builds["blink"], "--fast", "--duration", "1s", "--stimulus", stim, ok=False)
    assert avr.returncode == host.returncode == 2
    assert avr.stderr.splitlines()[0] == host.stderr.splitlines()[0] == f"{stim}:1: unknown column 'nonsense'"


def test_bad_command_lines_exit_2(sim_builds):
    exe = sim_builds["blink"].simulator
    for args, message in [(["--duration", "10"], "--duration 10: a duration needs a unit"),
                          (["--uart7", "x"], "unknown option '--uart7'"),
                          (["--bogus"], "unknown option '--bogus'"),
                          (["--uart0", "serial"], "give pty:LINK, tcp:PORT, file:PATH or null")]:
        proc = run(exe, *args, ok=False)
        assert proc.returncode == 2 and message in proc.stderr, (args, proc.stderr)
    assert "--stimulus FILE" in run(exe, "--help").stdout


def test_the_pins_trace_shows_levels_and_pwm_duties(sim_builds, tmp_path):
    pins = tmp_path / "pins.csv"
    run(sim_builds["pneumatic_cylinder"].simulator, "--fast", "--duration", "200ms", "--stimulus",
        stimulus_of("pneumatic_cylinder"), "--pins", pins)
    rows = [line.split(",") for line in pins.read_text().splitlines()[1:]]
    assert pins.read_text().startswith("cycle,time_us,pin,value\n")
    duty = [int(r[3]) for r in rows if r[2] == "PB5.pwm"]
    assert duty[0] == 0 and 255 in duty and any(0 < d < 255 for d in duty)  # the valve's PID output
    assert ["PA1", "1"] == [r[2:] for r in rows if r[2] == "PA1"][0]  # end_in, driven by the stimulus
    cycles = [int(r[0]) for r in rows]
    assert cycles == sorted(cycles)


def test_the_tick_is_exact_in_cpu_cycles(sim_builds, tmp_path):
    """blink toggles its LED at its deadlines: 100 ms apart to the cycle."""
    pins = tmp_path / "pins.csv"
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,half_period\n0,100\n")
    run(sim_builds["blink"].simulator, "--fast", "--duration", "1s", "--stimulus", stim, "--pins", pins)
    edges = [int(line.split(",")[0]) for line in pins.read_text().splitlines()[1:] if ",PB5," in line][1:]
    assert len(edges) >= 9
    gaps = [b - a for a, b in zip(edges, edges[1:])]
    # No drift: n half periods are n x 1.6 M cycles; the only jitter is a
    # cycle of simavr's timer rounding around each tick.
    assert abs((edges[-1] - edges[0]) - 1_600_000 * len(gaps)) <= 1, gaps
    assert all(abs(g - 1_600_000) <= 1 for g in gaps), gaps


def test_the_simulation_runs_in_real_time_unless_fast(sim_builds, tmp_path):
    start = time.monotonic()
    run(sim_builds["blink"].simulator, "--duration", "300ms")
    assert 0.28 <= time.monotonic() - start < 3.0


def test_a_uart_on_a_pty_serves_modbus_rtu_and_the_eeprom_persists(sim_builds, tmp_path):
    """The harness's pty plumbing end to end (pymodbus over Modbus RTU on
    USART1), and the EEPROM: a persist param written over Modbus is there
    again in the next run with the same --nvram file."""
    check_persist_round_trip(sim_builds["pt100_sensor"].simulator, "uart1", tmp_path, 4096)


def test_rtu_frames_that_come_together_reach_the_slave_apart(sim_builds, tmp_path):
    check_rtu_frames_kept_apart(sim_builds["pt100_sensor"].simulator, "uart1", tmp_path)


def test_the_uart_link_and_harness_files_of_a_build(sim_builds):
    built = sim_builds["pt100_sensor"]
    out = built.elf.parent
    assert built.simulator == out / "pt100_sensor-sim" and os.access(built.simulator, os.X_OK)
    hw = (out / "hw_map.json").read_text()
    assert '"adc": 0' in hw and '"pin": "PF0"' in hw and '"use": "modbus-rtu"' in hw


def test_the_debug_interface_answers_on_a_tcp_uart(sim_builds):
    """The debug transport of the AVR port (USART0), through the harness's
    TCP socket: hello and a read with the project's own client."""
    import re

    from avr_testlib import debug_client_class

    DebugClient = debug_client_class()

    proc = subprocess.Popen([str(sim_builds["pt100_sensor"].simulator), "--uart0", "tcp:0", "--wait"],
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stderr.readline()
        port = int(re.search(r"uart0 on tcp 127\.0\.0\.1:(\d+)", line).group(1))
        client = DebugClient.open(f"socket://127.0.0.1:{port}", timeout=2.0)
        try:
            hello = client.hello()
            program_id = int((sim_builds["pt100_sensor"].elf.parent / "model.c").read_text()
                             .split("Program id 0x")[1][:8], 16)
            assert hello.program_id == program_id and hello.max_frame == 160
            assert client.read([(0, "int16", 1)]) == [1000]  # cal_gain
        finally:
            client.close()
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_the_debug_uart_sends_each_response_whole_from_the_servers_buffer(tmp_path):
    """The 328P's debug UART has no transmit ring: a response goes out from
    the server's own buffer, so the server must take no further request
    until it is out. Requests sent back to back (as many as its receive
    ring holds) each get their whole response, in order, with nothing
    dropped; RESET's reply goes out before the watchdog restarts the MCU,
    which comes back halted at its first instant (RESET_HALT)."""
    import re

    from avr_testlib import ROOT, avr_build, debug_client_class
    from easylab.host_tools.debug_protocol import K, decode_frame, encode_frame

    built = avr_build(ROOT / "examples/blink.elab", tmp_path / "s", "--sim")
    program_id = int((tmp_path / "s" / "model.c").read_text().split("Program id 0x")[1][:8], 16)
    proc = subprocess.Popen([str(built.simulator), "--uart0", "tcp:0", "--wait"], stderr=subprocess.PIPE, text=True)
    try:
        port = int(re.search(r"uart0 on tcp 127\.0\.0\.1:(\d+)", proc.stderr.readline()).group(1))
        client = debug_client_class().open(f"socket://127.0.0.1:{port}", timeout=2.0)
        try:
            client.hello()
            before = client.counters()
            seqs = [(client.seq + 1 + k) & 0xFF for k in range(5)]
            burst = b"".join(encode_frame(seq, K.CMD_GET_PROGRAM_ID) for seq in seqs)
            assert len(burst) < 33  # blink's receive ring (EL_DBG_FRAME 30 + 3) holds them all
            client.t.send(burst)
            answers = [decode_frame(client.t.recv(2.0)) for _ in seqs]
            assert answers == [(seq, K.CMD_GET_PROGRAM_ID | K.RESPONSE, bytes([K.OK]) + program_id.to_bytes(4, "little"))
                               for seq in seqs]
            client.seq = seqs[-1]
            after = client.counters()
            assert after["tx_dropped"] == before["tx_dropped"] and after["frames"] == before["frames"] + 6
            client.retries = 0  # RESET's reply must come the first time
            client.reset(halt=True)
            assert client.hello_again().program_id == program_id
            flags = client.flags()
            assert flags.halted and flags.why == "start" and flags.tick == 0
        finally:
            client.close()
    finally:
        proc.kill()
        proc.wait()


ENCODERS = {
    # pins with pin-change interrupts of every group simavr simulates, and
    # external interrupts (INTn)
    "atmega328p": {"wheel": ("PB0", "PB1"), "knob": ("PC0", "PC1"), "axle": ("PD4", "PD5"), "ext": ("PD2", "PD3")},
    "atmega2560": {"wheel": ("PB0", "PB1"), "axle": ("PD0", "PE4"), "ext": ("PE6", "PE7")},
}


@pytest.mark.parametrize("mcu", ["atmega328p", "atmega2560"])
def test_encoders_count_the_stimulus_quadrature_edges(tmp_path, mcu):
    from avr_testlib import avr_build, host_build

    encoders = ENCODERS[mcu]
    lines = ["model enc", "import std"]
    lines += [f'device {n}: Encoder(pin_a = "{a}", pin_b = "{b}")' for n, (a, b) in encoders.items()]
    lines += [f"var v_{n}: int32" for n in encoders]
    lines.append("dataflow D { " + "  ".join(f"{n}.count -> v_{n}" for n in encoders) + " }")
    lines.append("task t period 10 ms { run D }")
    model = tmp_path / "enc.elab"
    model.write_text("\n".join(lines) + "\n")
    stim = tmp_path / "enc.csv"
    names = list(encoders)
    rows = [[0] * len(names), [5, -3, 7, 1][:len(names)], [-10, 100, -2, 0][:len(names)], [250, -40, 0, -9][:len(names)]]
    stim.write_text("time_us," + ",".join(f"{n}.count" for n in names) + "\n" +
                    "".join(f"{t},{','.join(map(str, r))}\n" for t, r in zip([0, 20000, 50000, 120000], rows)))
    sim = avr_build(model, tmp_path / "avr", "--mcu", mcu, "--sim", "--release").simulator
    host = host_build(model, tmp_path / "host")
    run(host, "--fast", "--duration", "300ms", "--stimulus", stim, "--trace", tmp_path / "h.csv")
    run(sim, "--fast", "--duration", "300ms", "--stimulus", stim, "--trace", tmp_path / "a.csv")
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "h.csv").read_text()
    assert "250" in (tmp_path / "h.csv").read_text()


def test_a_sim_build_warns_of_what_simavr_does_not_simulate(tmp_path):
    from avr_testlib import avr_build

    model = tmp_path / "k.elab"
    model.write_text('model k\nimport std\ndevice knob: Encoder(pin_a = "PK0", pin_b = "PK1")\nvar x: int32\n'
                     'dataflow D { knob.count -> x }\ntask t period 10 ms { run D }\n')
    out = avr_build(model, tmp_path / "o", "--mcu", "atmega2560", "--sim", "--release").proc.stdout
    assert "warning: simavr 1.6 simulates the atmega2560's pin-change interrupts on port B only: encoder 'knob'" in out


def test_cd_to_dat_with_the_flat_schedule_gives_the_same_trace(sim_builds, host_builds, tmp_path):
    """The flat single-appearance schedule (the benchmark's like-for-like
    comparison with hand-written C) on the ATmega2560: the host trace of
    the example's own schedule, byte for byte."""
    from avr_testlib import avr_build

    flat = avr_build(ROOT / "examples" / "cd_to_dat.elab", tmp_path / "flat", "--mcu", "atmega2560", "--sim",
                     "--schedule", "flat")
    assert "(147 src) (147 b)" in (tmp_path / "flat" / "model.c").read_text()
    host_trace, avr_trace = tmp_path / "host.csv", tmp_path / "avr.csv"
    args = ["--fast", "--duration", "1s"]
    run(host_builds["cd_to_dat"], *args, "--trace", host_trace)
    assert run(flat.simulator, *args, "--trace", avr_trace).stderr == ""
    assert avr_trace.read_bytes() == host_trace.read_bytes() and host_trace.read_bytes().count(b"\n") > 10
