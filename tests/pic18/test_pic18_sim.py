"""The PIC18 firmware in gpsim beyond the conformance suite's examples:
every driver against the host board's trace (tests/pic18/models/
drivers.elab on the PIC18F4520), the pins and PWM duties the harness
records, the tick in instruction cycles, the harness's options and
errors, the EEPROM over Modbus RTU."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from sim_modbus import check_persist_round_trip, check_rtu_frames_kept_apart
from pic18_testlib import DATA, MODELS, ROOT, changes, pic18_build, pins_rows, run

DRIVERS_STIMULUS = DATA / "drivers.stimulus.csv"


def traces(builds: dict, tmp_path: Path, stimulus: Path, duration: str, *pic_args) -> tuple[str, str]:
    """(host trace, PIC18 trace) of one build pair and stimulus."""
    args = ["--fast", "--duration", duration, "--stimulus", stimulus]
    run(builds["host"].executable, *args, "--trace", tmp_path / "host.csv")
    proc = run(builds["pic18"].simulator, *args, "--trace", tmp_path / "pic18.csv", *pic_args)
    assert proc.stderr == "", proc.stderr
    return (tmp_path / "host.csv").read_text(), (tmp_path / "pic18.csv").read_text()


def test_every_driver_gives_the_host_trace(drivers, tmp_path):
    """AnalogIn and Pt100 (the ADC), DigitalIn (PORTD, RE2), DigitalOut,
    PwmOut and Motor (the data they are given), Encoder on INT0/INT1, on
    PORTB's change interrupt and on both, counting up and down at once."""
    host, pic = traces(drivers, tmp_path, DRIVERS_STIMULUS, "200ms")
    assert pic == host
    last = host.splitlines()[-1].split(",")
    header = host.splitlines()[0].split(",")
    assert dict(zip(header, last))["wheel_count"] == "0" and "250" in host and "-40" in host


def test_outputs_reach_their_pins_and_pwm_duties(drivers, tmp_path):
    """--pins: each DigitalOut follows its level, the PwmOut's duty is
    clamped to 0..255 on CCP1, the Motor's magnitude is CCP2's duty and its
    sign the direction pin, in the order the trace gives them."""
    pins = tmp_path / "pins.csv"
    _, pic = traces(drivers, tmp_path, DRIVERS_STIMULUS, "200ms", "--pins", pins)
    header, *rows = [line.split(",") for line in pic.splitlines()]
    col = {name: [int(r[header.index(name)]) for r in rows] for name in
           ("lamp.level", "beacon.level", "heater.duty", "drive.speed")}
    recorded = pins_rows(pins)

    def pin(name):
        return changes(v for _, _, p, v in recorded if p == name)

    assert pin("RD7") == changes(col["lamp.level"])
    assert pin("RA4") == changes(col["beacon.level"])
    assert pin("RC2.pwm") == changes(max(0, min(255, d)) for d in col["heater.duty"]) == [0, 100, 255, 0, 255, 128]
    assert pin("RC1.pwm") == changes(min(255, abs(s)) for s in col["drive.speed"])
    assert pin("RD6") == changes(int(s < 0) for s in col["drive.speed"])
    cycles = [c for c, *_ in recorded]
    assert cycles == sorted(cycles)


def test_the_harness_counts_instruction_cycles(drivers, tmp_path):
    proc = run(drivers["pic18"].simulator, "--fast", "--duration", "100ms", "--report")
    assert "drivers-sim: cycles 1" in proc.stderr and "instants 10, time 100000 us" in proc.stderr
    cycles = int(proc.stderr.split("cycles ")[1].split()[0])
    # 10 MIPS: the instant of 100 ms begins 1,000,000 cycles after the first
    # one, which start-up (clearing RAM, the devices) delays by under 2 ms.
    assert 1_000_000 < cycles < 1_020_000
    # The port's wait loops, at their bare cost, are most of a 10 ms period
    # (the PIC18 polls: "asleep" counts them, docs/boards.md).
    asleep = int(proc.stderr.split("(asleep ")[1].split(")")[0])
    assert cycles // 2 < asleep < cycles


def test_the_tick_is_exact_in_instruction_cycles(blink_4620, tmp_path):
    """blink toggles RB5 at its deadlines, 100 ms apart: Timer2 divides the
    1 ms tick exactly (10,000 cycles at 10 MIPS), so n toggles take n x 1 M
    cycles with no drift; each one comes within the turn of the port's
    waiting loop (el_idle serves the debug server) after its tick."""
    pins = tmp_path / "pins.csv"
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,half_period\n0,100\n")
    run(blink_4620.simulator, "--fast", "--duration", "2s", "--stimulus", stim, "--pins", pins)
    edges = [c for c, _, p, _ in pins_rows(pins) if p == "RB5"][1:]
    assert len(edges) >= 19
    gaps = [b - a for a, b in zip(edges, edges[1:])]
    assert all(abs(g - 1_000_000) <= 500 for g in gaps), gaps
    assert abs(edges[-1] - edges[0] - 1_000_000 * len(gaps)) <= 500  # no drift: the jitter does not add up


def test_the_simulation_runs_in_real_time_unless_fast(drivers):
    start = time.monotonic()
    run(drivers["pic18"].simulator, "--duration", "300ms")
    assert 0.28 <= time.monotonic() - start < 3.0


def test_a_value_the_adc_cannot_give_is_an_error(drivers, tmp_path):
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,level.value\n0,300\n30000,1024\n")
    proc = run(drivers["pic18"].simulator, "--fast", "--duration", "1s", "--stimulus", stim, "--trace",
               tmp_path / "t.csv", ok=False)
    assert proc.returncode == 1
    assert "level.value = 1024 at 30000 us: the pic18f4520's ADC gives 0..1023 (10 bits)" in proc.stderr


def test_stimulus_errors_are_reported_as_on_the_host_board(drivers, tmp_path):
    stim = tmp_path / "bad.csv"
    stim.write_text("time_us,nonsense\n0,1\n")
    pic = run(drivers["pic18"].simulator, "--fast", "--duration", "1s", "--stimulus", stim, ok=False)
    host = run(drivers["host"].executable, "--fast", "--duration", "1s", "--stimulus", stim, ok=False)
    assert pic.returncode == host.returncode == 2
    assert pic.stderr.splitlines()[0] == host.stderr.splitlines()[0] == f"{stim}:1: unknown column 'nonsense'"


def test_bad_command_lines_exit_2_and_help_exits_0(drivers):
    exe = drivers["pic18"].simulator
    for args, message in [(["--duration", "10"], "--duration 10: a duration needs a unit"),
                          (["--uart1", "pty:x"], "--uart1: the pic18f4520 has no UART 1 (UARTs: 0)"),
                          (["--bogus"], "unknown option '--bogus'"),
                          (["--uart0", "serial"], "give pty:LINK, tcp:PORT, file:PATH or null"),
                          (["--cod", "/nonexistent.cod"], "cannot load the firmware /nonexistent.cod")]:
        proc = run(exe, *args, ok=False)
        assert proc.returncode == 2 and message in proc.stderr, (args, proc.stderr)
    out = run(exe, "--help").stdout
    assert "Runs the pic18f4520 firmware of model drivers in gpsim." in out
    for option in ("--fast", "--duration T", "--cycles N", "--stimulus FILE", "--trace FILE", "--pins FILE",
                   "--nvram FILE", "--uartN SPEC", "--wait", "--halt", "--report"):
        assert option in out, option
    assert "the EEPROM (256 bytes)" in out


def test_the_nvram_file_is_the_eeprom(drivers, tmp_path):
    """--nvram: the EEPROM's bytes (256 on the PIC18F4520), erased (0xFF)
    when the file is new, written back at the end."""
    nv = tmp_path / "eeprom.bin"
    run(drivers["pic18"].simulator, "--fast", "--duration", "20ms", "--nvram", nv)
    assert nv.read_bytes() == b"\xff" * 256
    nv.write_bytes(bytes(range(256)))
    run(drivers["pic18"].simulator, "--fast", "--duration", "20ms", "--nvram", nv)
    assert nv.read_bytes() == bytes(range(256))
    nv.write_bytes(b"\0" * 100)
    proc = run(drivers["pic18"].simulator, "--fast", "--duration", "20ms", "--nvram", nv, ok=False)
    assert proc.returncode == 2 and "256" in proc.stderr, proc.stderr


@pytest.fixture(scope="module")
def pt100_rtu(tmp_path_factory):
    """The PIC18 variant of pt100_sensor with Modbus RTU on uart0, a
    PIC18F4620 release simulation build (with Modbus it needs more than the
    PIC18F4520's 32 KB)."""
    from firmware_builds import board_model

    out = tmp_path_factory.mktemp("pt100_rtu")
    model = board_model("pic18", ROOT / "examples" / "pt100_sensor.elab", "modbus-rtu", out / "model")
    return pic18_build(model, out / "b", "--mcu", "pic18f4620", "--sim", "--release")


def test_persist_params_written_over_modbus_are_in_the_eeprom_at_the_next_run(pt100_rtu, tmp_path):
    """The pty plumbing end to end (pymodbus over Modbus RTU on the
    EUSART), and the data EEPROM: a persist param written over Modbus is
    there again in the next run with the same --nvram file (the
    PIC18F4620's 1024 bytes: EEADRH)."""
    check_persist_round_trip(pt100_rtu.simulator, "uart0", tmp_path, 1024)


def test_the_debug_server_of_a_pic18f4520_with_model_sized_buffers_answers(tmp_path):
    """blink's debug build on the PIC18F4520 (1.5 KB of RAM: buffers sized
    from the model, no transmit ring) in gpsim: the debugger identifies it,
    reads and writes an item, is refused a value out of its range, halts it,
    lets it go, and resets it into a halt at its first instant (the reply
    comes before the restart)."""
    import re
    import subprocess

    from easylab.host_tools.debug_protocol import K, DebugClient, DebugError

    built = pic18_build(ROOT / "examples" / "blink.elab", tmp_path / "s", "--sim")
    dmap = (tmp_path / "s" / "debug_map.json").read_text()
    program_id = int(re.search(r'"program_id": "0x([0-9a-f]+)"', dmap).group(1), 16)
    proc = subprocess.Popen([str(built.simulator), "--uart0", "tcp:0", "--wait"], stderr=subprocess.PIPE, text=True)
    try:
        port = int(re.search(r"uart0 on tcp 127\.0\.0\.1:(\d+)", proc.stderr.readline()).group(1))
        client = DebugClient.open(f"socket://127.0.0.1:{port}", timeout=3.0)
        try:
            hello = client.hello()
            assert hello.program_id == program_id and hello.max_frame == 30  # the model's frame, not 160
            assert client.read([(0, "uint16", 1)]) == [500]  # half_period
            with pytest.raises(DebugError) as e:
                client.write(0, "uint16", 5001)  # range 10..5000
            assert e.value.status == K.E_RANGE
            client.halt()
            deadline = time.monotonic() + 10
            while not client.flags().halted:
                assert time.monotonic() < deadline
                time.sleep(0.05)
            assert client.write(0, "uint16", 250) == K.APPLIED  # halted at an instant: at once
            assert client.read([(0, "uint16", 1)]) == [250]
            client.run()
            assert not client.flags().halted
            client.retries = 0  # RESET's reply goes out from the server's buffer before the restart
            client.reset(halt=True)
            assert client.hello_again(10.0).program_id == program_id
            assert client.read([(0, "uint16", 1)]) == [500]  # started again: half_period as at boot
            flags = client.flags()
            assert flags.halted and flags.why == "start" and flags.tick == 0  # RESET_HALT
        finally:
            client.close()
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_rtu_frames_that_come_together_reach_the_slave_apart(pt100_rtu, tmp_path):
    check_rtu_frames_kept_apart(pt100_rtu.simulator, "uart0", tmp_path)


@pytest.mark.parametrize("name, mcu, duration", [("pneumatic_cylinder", "pic18f4620", "3600ms"),
                                                 ("pt100_sensor", "pic18f4520", "2s")])
def test_the_pic18_variants_of_the_examples_give_the_host_trace(name, mcu, duration, tmp_path, build_cache):
    """The examples that need two UARTs, as the suites run them on the PIC18
    (boards/pic18/conformance/: the part's pins, no interface), against the host
    board's trace of the same model; release builds (pneumatic_cylinder
    needs more than the PIC18F4520's 32 KB)."""
    from firmware_builds import build, stimulus_of

    model = ROOT / "boards" / "pic18" / "conformance" / f"{name}.elab"
    pic = build_cache.get(("pic18-variant", name, mcu),
                          lambda out: pic18_build(model, out, "--mcu", mcu, "--sim", "--release"))
    host = build_cache.get(("host-variant", name), lambda out: build(model, "host", out))
    host_trace, pic_trace = traces({"host": host, "pic18": pic}, tmp_path, stimulus_of(name), duration)
    assert pic_trace == host_trace and host_trace.count("\n") > 20


def test_an_encoder_counts_every_edge_at_its_instant(tmp_path, build_cache):
    """1,313 edges at 1.3 kHz on INT1/INT2, then 800 back at 4 kHz: the
    count at every instant is the host board's (gpsim took no interrupt
    whose flag rose while the handler ran: the harness has it taken)."""
    from firmware_builds import build

    model = MODELS / "encoder_rate.elab"
    pic = build_cache.get(("pic18-encoder-rate",), lambda out: pic18_build(model, out, "--sim", "--release"))
    host = build_cache.get(("host-encoder-rate",), lambda out: build(model, "host", out))
    host_trace, pic_trace = traces({"host": host, "pic18": pic}, tmp_path, DATA / "encoder_rate.stimulus.csv",
                                   "1210ms")
    assert pic_trace == host_trace
    assert host_trace.splitlines()[-1].endswith(",553") and ",1313," in host_trace
