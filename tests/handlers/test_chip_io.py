"""Chip models on a UART and on pins (docs/boards.md, "Chip models"): a
serial range finder answering a query byte with its distance, and a
shift register that latches switch levels at a pulse of its load pin and
shifts them onto its data pin at each clock edge the firmware drives, in
the model folder tests/handlers/own_chips (handler files for host, AVR and
PIC18, each with its chip model). On one stimulus the host board, local
execution, the AVR in simavr and the PIC18 in gpsim give the same trace.

The harnesses' shared dispatch (sim/sim_chips.c) is checked on its own
too, against generated tables and events: a byte the MCU sends reaches the
chips on that UART only, the level the firmware drives a pin to reaches
the chip whose device claims the pin only (and only when it changed), and
a chip sends and drives only where its device claims."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from firmware_builds import ROOT, build
from test_chip_models import DURATION, board_trace, local_trace

SOURCE = Path(__file__).with_name("own_chips")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """The model folder, copied outside the package."""
    out = tmp_path_factory.mktemp("user") / "own_chips"
    shutil.copytree(SOURCE, out)
    return out


@pytest.mark.parametrize("name", ["own_uart", "own_pins"])
@pytest.mark.parametrize("board", ["host", "avr", "pic18"])
def test_a_uart_or_pin_device_of_ones_own_gives_local_executions_trace(folder, tmp_path, name, board):
    reference = local_trace(folder, name, tmp_path)
    rows = [row.split(",") for row in reference.decode().splitlines()[1:]]
    assert len({row[1] for row in rows}) >= 3, "the chip's answers should move the model's variable"
    assert board_trace(folder, name, board, tmp_path) == reference


def test_each_chip_hears_its_own_uart_and_pins(folder, tmp_path):
    """Two range finders on the ATmega2560's UARTs 1 and 2 and two shift
    registers on port C, each with values of its own: a byte reaching the
    wrong chip, or a clock edge the wrong register, shows in the trace."""
    reference = local_trace(folder, "own_io", tmp_path)
    header, *rows = reference.decode().splitlines()
    columns = header.split(",")
    last = dict(zip(columns, rows[-1].split(",")))
    assert len({last["near_cm"], last["far_cm"]}) == 2 and len({last["left_closed"], last["right_closed"]}) == 2
    built = build(folder / "own_io.elab", "avr", tmp_path / "io", "--sim", "--mcu", "atmega2560")
    trace = tmp_path / "io.csv"
    subprocess.run([str(built.simulator), "--fast", "--duration", DURATION, "--stimulus",
                    str(folder / "own_io.stimulus.csv"), "--trace", str(trace)], check=True, timeout=120)
    assert trace.read_bytes() == reference
    # the chip table: each device's pins in the order of its claims, each range finder at its UART
    table = (tmp_path / "io" / "sim_model.c").read_text()
    assert "{ 16u /* PC0 */, 17u /* PC1 */, 18u /* PC2 */ }" in table
    assert "{ 19u /* PC3 */, 20u /* PC4 */, 21u /* PC5 */ }" in table
    assert table.count("SIM_CHIP_UART, 1u,") == 1 and table.count("SIM_CHIP_UART, 2u,") == 1
    assert table.count("SIM_CHIP_PINS, 0u,") == 2



# ---- the shared dispatch, on its own ----

# A program around sim/sim_chips.c: the board's side prints what reaches
# the MCU, every chip (one recorder model, its index a parameter) prints
# what reaches it; commands on stdin drive both sides.
DISPATCH_C = r"""
#include "sim_chips.h"

#include <stdarg.h>
#include <stdio.h>

const char *el_host_prog = "dispatch";
bool sim_stop;       /* what sim_harness.c has: a chip's error ends the run */
int sim_exit_status;

void el_host_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("error ");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
}

uint64_t sim_board_now_us(void) { return 0u; }
void sim_board_uart_receive(uint8_t uart, uint8_t byte) { printf("rx %u %u\n", uart, byte); }
void sim_board_pin_drive(uint16_t pin, bool level) { printf("drive %u %d\n", pin, (int)level); }

static el_chip_t *chips[16];

static int index_of(const el_chip_t *chip) { return (int)el_chip_param(chip, "index", -1); }
static void on_reset(el_chip_t *chip) { chips[index_of(chip)] = chip; }
static void on_byte(el_chip_t *chip, uint8_t byte) { printf("byte %d %u\n", index_of(chip), byte); }
static void on_edge(el_chip_t *chip, uint16_t pin, bool level)
{
    printf("edge %d %u %d\n", index_of(chip), pin, (int)level);
}

const el_chip_ops_t recorder = {
    .name = "recorder", .reset = on_reset, .uart_byte = on_byte, .pin_edge = on_edge,
};

TABLE

int main(void)
{
    char op;
    unsigned a, b, c;
    if (!sim_chips_start(NULL))
        return 2;
    while (scanf(" %c %u %u %u", &op, &a, &b, &c) == 4) {
        switch (op) {
        case 'D': sim_chips_pin_driven((uint16_t)a, b != 0u); break;
        case 'T': sim_chips_uart_byte((uint8_t)a, (uint8_t)b); break;
        case 'S': el_chip_uart_send(chips[a], (uint8_t)b); break;
        default: el_chip_pin_drive(chips[a], (uint16_t)b, c != 0u); break;
        }
    }
    printf("finish %d %d %d\n", (int)sim_chips_finish(), (int)sim_stop, sim_exit_status);
    return 0;
}
"""

KINDS = ("SIM_CHIP_UART", "SIM_CHIP_PINS", "SIM_CHIP_I2C")
PINS = 48


def table_c(chips: list[tuple[str, int, list[int]]]) -> str:
    """sim_chip_table of ``chips`` (kind, UART, pins), chip k named ck."""
    lines, rows = [], []
    for k, (kind, uart, pins) in enumerate(chips):
        lines += [f"static const char *const names_{k}[] = {{ \"index\" }};",
                  f"static const int64_t values_{k}[] = {{ {k} }};",
                  f"static const uint16_t pins_{k}[] = {{ {', '.join(f'{p}u' for p in pins) or '0u'} }};"]
        address = 0x20 + k if kind == "SIM_CHIP_I2C" else 0
        rows.append(f"    {{ &recorder, {kind}, {uart}u, 0x{address:02x}u, 0u, \"\", \"c{k}\", 0u, 0, 1u, names_{k}, "
                    f"values_{k}, {len(pins)}u, pins_{k} }},")
    return "\n".join(lines + [f"const sim_chip_entry_t sim_chip_table[{len(rows)}] = {{", *rows, "};",
                              f"const uint16_t sim_chip_table_count = {len(rows)}u;"])


def expected(chips: list[tuple[str, int, list[int]]], commands: list[tuple[str, int, int, int]]) -> list[str]:
    """What sim/sim_chips.h says the commands give."""
    out, last, failed = [], {}, False
    for op, a, b, c in commands:
        if op == "D":  # the firmware drives pin a to b
            for k, (_kind, _uart, pins) in enumerate(chips):
                if a in pins and last.get(a) != bool(b):
                    last[a] = bool(b)
                    out.append(f"edge {k} {a} {int(bool(b))}")
        elif op == "T":  # the MCU sends b on UART a
            out += [f"byte {k} {b}" for k, (kind, uart, _p) in enumerate(chips)
                    if kind == "SIM_CHIP_UART" and uart == a]
        elif op == "S":  # chip a sends b
            kind, uart, _pins = chips[a]
            if kind == "SIM_CHIP_UART":
                out.append(f"rx {uart} {b}")
            else:
                failed = True
                out.append(f"error c{a} (chip model): sent 0x{b:02x} on a UART, but its device claims none")
        else:  # chip a drives pin b to c
            if b in chips[a][2]:
                out.append(f"drive {b} {int(bool(c))}")
            else:
                failed = True
                out.append(f"error c{a} (chip model): drove pin {b}, which its device does not claim")
    return out + [f"finish {int(not failed)} {int(failed)} {1 if failed else 0}"]


@st.composite
def boards(draw):
    """A table of chips (each pin claimed once, as the resource check
    ensures) and commands of both sides."""
    count = draw(st.integers(1, 6))
    pool = draw(st.permutations(range(PINS)))
    chips, used = [], 0
    for _k in range(count):
        n = draw(st.integers(0, 3))
        chips.append((draw(st.sampled_from(KINDS)), draw(st.integers(0, 3)), list(pool[used:used + n])))
        used += n
    pin = st.integers(0, PINS - 1)
    chip = st.integers(0, count - 1)
    claimed = [p for _kind, _u, pins in chips for p in pins]
    command = st.one_of(
        st.tuples(st.just("D"), st.sampled_from(claimed) if claimed else pin, st.integers(0, 1), st.just(0)),
        st.tuples(st.just("D"), pin, st.integers(0, 1), st.just(0)),
        st.tuples(st.just("T"), st.integers(0, 3), st.integers(0, 255), st.just(0)),
        st.tuples(st.just("S"), chip, st.integers(0, 255), st.just(0)),
        st.tuples(st.just("P"), chip, st.sampled_from(claimed) if claimed else pin, st.integers(0, 1)),
        st.tuples(st.just("P"), chip, pin, st.integers(0, 1)))
    return chips, draw(st.lists(command, max_size=40))


def run_dispatch(work: Path, chips, commands) -> list[str]:
    source = work / "dispatch.c"
    exe = work / "dispatch"
    source.write_text(DISPATCH_C.replace("TABLE", table_c(chips)))
    subprocess.run(["gcc", "-std=gnu99", "-O0", "-Wall", "-Wextra", "-Werror", f"-I{ROOT / 'sim'}",
                    f"-I{ROOT / 'boards' / 'host'}", f"-I{ROOT / 'runtime_c'}", "-o", str(exe), str(source),
                    str(ROOT / "sim" / "sim_chips.c")], check=True, capture_output=True, text=True)
    stdin = "".join(f"{op} {a} {b} {c}\n" for op, a, b, c in commands)
    proc = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True, timeout=30)
    return proc.stdout.splitlines()


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(boards())
def test_the_dispatch_reaches_only_the_chip_that_claims_the_uart_or_pin(tmp_path, board):
    chips, commands = board
    assert run_dispatch(tmp_path, chips, commands) == expected(chips, commands)


def test_the_dispatch_on_a_hand_written_board(tmp_path):
    """Two chips on UARTs 1 and 2 and one with pins 3 and 5: the cases the
    generated boards hold, spelled out."""
    chips = [("SIM_CHIP_UART", 1, []), ("SIM_CHIP_UART", 2, [7]), ("SIM_CHIP_PINS", 0, [3, 5])]
    commands = [("T", 1, 0x55, 0), ("T", 2, 0x56, 0), ("T", 0, 1, 0),  # only the chip on that UART
                ("D", 3, 0, 0), ("D", 3, 0, 0), ("D", 3, 1, 0), ("D", 4, 1, 0), ("D", 7, 1, 0),
                ("S", 0, 0xFF, 0), ("S", 1, 0x10, 0), ("P", 2, 5, 1), ("P", 1, 7, 0),
                ("S", 2, 0x20, 0), ("P", 2, 7, 1)]  # a chip's errors: a UART, a pin not its device's
    assert run_dispatch(tmp_path, chips, commands) == [
        "byte 0 85", "byte 1 86",
        "edge 2 3 0", "edge 2 3 1", "edge 1 7 1",
        "rx 1 255", "rx 2 16", "drive 5 1", "drive 7 0",
        "error c2 (chip model): sent 0x20 on a UART, but its device claims none",
        "error c2 (chip model): drove pin 7, which its device does not claim",
        "finish 0 1 1"]


def test_the_pin_example_of_docs_boards_md_is_this_model():
    docs = (ROOT / "docs" / "boards.md").read_text()
    chip = (SOURCE / "drivers" / "switches_chip.c").read_text()
    assert "enum { LOAD, CLOCK, DATA }; /* chip->pins, in the order of the claims */\n" in chip
    start = chip.index("static void output(")
    excerpt = chip[start:chip.index("const el_chip_ops_t", start)].rstrip() + "\n```"
    assert excerpt in docs


def test_a_chip_driving_a_pin_its_device_does_not_claim_fails_the_run(tmp_path):
    """On the AVR in simavr: the chip's word, naming its device, once (the
    run ends there), and exit status 1."""
    folder = tmp_path / "m"
    shutil.copytree(SOURCE, folder)
    (folder / "drivers" / "switches_chip.c").write_text(
        '#include "el_chip.h"\n'
        "static void edge(el_chip_t *chip, uint16_t pin, bool level)\n"
        "{\n"
        "    (void)pin;\n"
        "    el_chip_pin_drive(chip, (uint16_t)(chip->pins[2] + 1u), level); /* PD7 + 1: no pin of its own */\n"
        "}\n"
        'const el_chip_ops_t EL_CHIP = { .name = "stray", .pin_edge = edge };\n')
    built = build(folder / "own_pins.elab", "avr", tmp_path / "b", "--sim")
    proc = subprocess.run([str(built.simulator), "--fast", "--duration", DURATION, "--trace", str(tmp_path / "t.csv")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr.count("panel (chip model): drove pin 32, which its device does not claim") == 1, proc.stderr
