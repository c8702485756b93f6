"""The AVR board: generated code against hand-written C in CPU cycles, and
the runtime's own footprint.

1. Cycles per activation, exact, in simavr: pt100_sensor's Acquire and
   cd_to_dat's Convert, the generated dataflow function (model.c of an AVR
   build, avr-gcc -Os) against the hand-written C of bench/handwritten/ on
   the same inputs (the same cases as bench_codegen.py, whose checks must
   agree), on the ATmega2560 (cd_to_dat's buffers, generated or hand-
   written, need more than the ATmega328P's 2 KB). A small libsimavr runner
   stamps avr->cycle at markers the program writes to GPIOR0. Flash: the
   program's flash with one side minus the same program with neither.
   Goals: at most 1.10x the cycles and 1.15x the flash of hand-written C.
2. Footprint on the ATmega328P (release builds unless noted): a one-actor
   model (the dispatcher, the port, the model), then what a debug interface
   and a Modbus RTU slave add; flash and RAM by part (symbol sizes by
   object file): the debug server's own against its goal (GOALS).
3. The examples' sizes (those of docs/boards.md), blink's against GOALS.
4. The Modbus slave's answer to a 125-register read, in cycles: goal
   MODBUS_GOAL_CYCLES with the RTU CRCs.

Writes out_dir/avr.json and prints a table. Run: python bench/bench_avr.py [out_dir]
"""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = ROOT / "bench"
MCU = "atmega2560"
CFLAGS_EXTRA = ["-DEL_RELEASE=1", "-DEL_AVR_NO_MAIN", "-Wno-unused-function"]

PROGRAM = """
#include "model.c"
#include <avr/io.h>
#include <avr/interrupt.h>
#include <avr/sleep.h>
{decls}
#define MARK(v) do {{ __asm__ __volatile__("" ::: "memory"); GPIOR0 = (v); }} while (0)

__attribute__((noinline)) static uint32_t run(uint16_t n)
{{
    uint16_t i;
    uint32_t check = 0u;
    MARK(1u);
    for (i = 0u; i < n; i++) {{ {body}
    }}
    MARK(2u);
    return check;
}}

int main(void)
{{
    uint32_t check;
    {setup}
    check = run({n}u);
    uint8_t k;
    for (k = 0u; k < 4u; k++) {{ GPIOR1 = (uint8_t)(check >> (8u * k)); MARK((uint8_t)(0x10u + k)); }}
    cli();
    sleep_cpu(); /* simavr ends a run that sleeps with interrupts off */
    return 0;
}}
"""

RUNNER = r"""
/* Stamp avr->cycle at each GPIOR0 write of an AVR program; print them. */
#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_core.h"
#include <stdio.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

static avr_cycle_count_t start, stop;
static uint32_t check;

static void mark(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    avr->data[addr] = v;
    if (v == 1u) start = avr->cycle;
    else if (v == 2u) stop = avr->cycle;
    else if (v >= 0x10u && v < 0x14u) check |= (uint32_t)avr->data[0x4A] << (8u * (v - 0x10u));
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    avr_t *avr;
    int null = open("/dev/null", O_WRONLY), out = dup(1), state;
    memset(&fw, 0, sizeof fw);
    dup2(null, 1);
    if (argc < 3 || elf_read_firmware(argv[2], &fw) != 0) return 2;
    avr = avr_make_mcu_by_name(argv[1]);
    if (!avr) return 2;
    avr_init(avr);
    avr_load_firmware(avr, &fw);
    dup2(out, 1);
    avr->frequency = 16000000;
    avr->log = 0;
    avr_register_io_write(avr, 0x3E, mark, NULL);
    do {
        state = avr_run(avr);
    } while (state != cpu_Done && state != cpu_Crashed && avr->cycle < 4000000000ull);
    fflush(stdout);
    printf("%llu %lu\n", (unsigned long long)(stop - start), (unsigned long)check);
    return state == cpu_Done ? 0 : 1;
}
"""


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _generate(model: Path, out: Path, mcu: str, schedule: str | None = None):
    """model.c and the AVR board's generated headers of a release build."""
    from easylab.board.registry import load_board
    from easylab.build import generate
    from easylab.pipeline import lower_file

    program, result = lower_file(model, schedule=schedule)
    if program is None:
        raise SystemExit(result.report())
    board = load_board("avr").configure(mcu)
    generate(program, board, out, release=True, checked=board.check(program))
    return program, board


def _compile(board, work: Path, name: str, source: str, extra: list[Path]) -> Path:
    from easylab.board.cbuild import include_flags, runtime_sources

    (work / f"{name}.c").write_text(source)
    elf = work / f"{name}.elf"
    cmd = ["avr-gcc", *board.cflags, *CFLAGS_EXTRA, *include_flags(work, board.description), "-o", str(elf),
           str(work / f"{name}.c"), *map(str, extra), *map(str, board.description.source_paths),
           *map(str, runtime_sources(release=True)), *board.description.toolchain.ldflags]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"avr-gcc failed for {name}:\n{proc.stderr}")
    return elf


def _flash(elf: Path) -> int:
    from easylab.board.cbuild import elf_sections

    s = elf_sections("avr-size", elf)
    return s.get(".text", 0) + s.get(".data", 0)


def _cycles(runner: Path, elf: Path) -> tuple[int, int]:
    out = subprocess.run([str(runner), MCU, str(elf)], capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        raise SystemExit(f"{elf.name} did not end cleanly in simavr: {out.stdout}{out.stderr}")
    cycles, check = out.stdout.strip().splitlines()[-1].split()
    return int(cycles), int(check)


def measure(name: str, case: dict, tmp: Path, runner: Path, tiny: bool = False) -> dict:
    """Cycles and flash per activation of a bench_codegen case on the AVR."""
    work = tmp / re.sub(r"\W+", "_", name)
    program, board = _generate(ROOT / case["model"], work, MCU, case.get("schedule"))
    hand = HERE / "handwritten" / case["handwritten"]
    row = _load("bench_codegen").compare_on_target(
        name, case, program, board, PROGRAM, 2 if tiny else max(1, case["activations"] // 10),
        build=lambda kind, src: _compile(board, work, kind, src, [hand]),
        cycles_of=lambda elf: _cycles(runner, elf), flash_of=_flash, target="AVR")
    return {"mcu": MCU, **row}


FOOTPRINT_MODELS = {
    "one-actor model": ("", "", True),
    "+ debug interface (debug build)": ("", "debug on uart0 baud 115200\n", False),
    "+ Modbus RTU slave": (" service ro", "modbus rtu on uart0 baud 19200 parity none unit 1\n", True),
}

FOOTPRINT_BASE = """model footprint
import std
var x: uint8{service}
dataflow D {{
    c = Const<uint8>(value = 1)
    c.y -> x
}}
task t period 1 ms {{ run D }}
"""

# Where a firmware's flash goes, by the object file that defines a symbol.
PARTS = [("dispatcher", ("el_dispatch",)), ("port (boards/avr)", ("avr_",)),
         ("debug server", ("el_debug", "debug_tables")),
         ("service map, persist, Modbus", ("el_service", "el_persist", "el_modbus", "service_tables", "el_crc16")),
         ("model", ("model_gen", "el_avr_devices", "el_arith"))]


def breakdown(elf: Path, ram: bool = False) -> dict[str, int]:
    """Flash bytes per part of the runtime (symbol sizes; the rest is avr-libc,
    libgcc and the vector table); ``ram``: the static RAM of each part
    instead (data and bss symbols)."""
    objs = sorted((elf.parent / "obj").glob("*.o"))
    owner = {}
    for obj in objs:
        out = subprocess.run(["avr-nm", "--defined-only", str(obj)], capture_output=True, text=True).stdout
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[1] in "tTdDrRbB":
                owner.setdefault(parts[2], obj.stem)
    sizes = {name: 0 for name, _ in PARTS}
    sizes["avr-libc, libgcc, vectors"] = 0
    out = subprocess.run(["avr-nm", "-S", "--defined-only", str(elf)], capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) != 4:
            continue
        in_ram = 0x800000 <= int(parts[0], 16) < 0x810000
        if (ram and not (in_ram and parts[2] in "bBdD")) or \
                (not ram and (parts[2] not in "tTdDrR" or int(parts[0], 16) >= 0x800000 and parts[2] in "tT")):
            continue
        size = int(parts[1], 16)
        obj = owner.get(parts[3], "")
        part = next((name for name, prefixes in PARTS if obj.startswith(prefixes)), "avr-libc, libgcc, vectors")
        sizes[part] += size
    return sizes


def footprint(tmp: Path) -> list[dict]:
    rows = []
    for label, (service, extra, release) in FOOTPRINT_MODELS.items():
        model = tmp / "footprint" / re.sub(r"\W+", "_", label) / "footprint.elab"
        model.parent.mkdir(parents=True)
        model.write_text(FOOTPRINT_BASE.format(service=service) + extra)
        cmd = [sys.executable, "-m", "easylab", "build", str(model), "--board", "avr", "--mcu", "atmega328p",
               "-o", str(model.parent / "out")] + (["--release"] if release else [])
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        if proc.returncode != 0:
            rows.append({"what": label, "error": proc.stderr.strip()})
            continue
        m = re.search(r"flash (\d+) of .* RAM (\d+) of", proc.stdout)
        elf = Path(proc.stdout.strip().splitlines()[-1])
        rows.append({"what": label, "mcu": "atmega328p", "flash": int(m.group(1)), "ram": int(m.group(2)),
                     "flash_by_part": breakdown(elf), "ram_by_part": breakdown(elf, ram=True)})
    base = rows[0]
    for r in rows[1:]:
        if "flash" in r and "flash" in base:
            r["flash_added"] = r["flash"] - base["flash"]
            r["ram_added"] = r["ram"] - base["ram"]
    return rows


def examples_sizes(tmp: Path, tiny: bool = False) -> list[dict]:
    """Every example on the ATmega2560 (debug builds), blink and cd_to_dat
    on the ATmega328P (tiny: blink only)."""
    rows = []
    builds = [(p.stem, "atmega2560", []) for p in sorted((ROOT / "examples").glob("*.elab"))]
    builds += [("blink", "atmega328p", []), ("blink", "atmega328p", ["--release"]),
               ("cd_to_dat", "atmega328p", ["--release", "--schedule", "min-buffer"]),
               ("cd_to_dat", "atmega328p", ["--schedule", "min-buffer"])]
    if tiny:
        builds = [b for b in builds if b[0] == "blink"][:1]
    for name, mcu, flags in builds:
        out = tmp / "examples" / f"{name}-{mcu}-{'-'.join(flags) or 'debug'}"
        cmd = [sys.executable, "-m", "easylab", "build", str(ROOT / "examples" / f"{name}.elab"), "--board", "avr",
               "--mcu", mcu, *flags, "-o", str(out)]
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        m = re.search(r"flash (\d+) of (\d+) .* RAM (\d+) of (\d+)", proc.stdout + proc.stderr)
        rows.append({"example": name, "mcu": mcu, "flags": " ".join(flags) or "(debug build)",
                     "flash": int(m.group(1)) if m else None, "ram": int(m.group(3)) if m else None,
                     "fits": proc.returncode == 0})
    return rows


MODBUS_MODEL = "model mbbench\nimport std\n" + "".join(f"var r{k}: int16 = {k} service ro\n" for k in range(125)) + (
    "var tick: int16\ndataflow D {\n    c = Const<int16>(value = 1)\n    c.y -> tick\n}\n"
    "task t period 10 ms { run D }\nmodbus rtu on uart0 baud 19200 parity none unit 1\n")

MODBUS_GOAL_CYCLES = 16000  # a 125-register read answered, RTU CRCs included

MODBUS_DECLS = """#include "el_modbus.h"
#include "el_crc16.h"
const uint8_t mb_request[5] = {{0x04u, 0x00u, 0x00u, 0x00u, 125u}}; /* read input registers 0..124 */
const uint8_t mb_frame[8] = {{{frame}}}; /* the same request as an RTU frame to unit 1 */
uint8_t mb_response[256];
el_mb_rtu_t mb_rtu;
void el_svc_gen_boot(void);
/* The slave's work for one request: the frame's bytes as the UART's
 * interrupt hands them over, the t3.5 silence, the reply with its CRC. */
static uint16_t mb_serve(void)
{{
    uint8_t j;
    for (j = 0u; j < 8u; j++)
        (void)el_mb_rtu_byte(&mb_rtu, mb_frame[j]);
    (void)el_mb_rtu_silence(&mb_rtu);
    return el_mb_rtu_reply(&mb_rtu);
}}"""


def _rtu_frame(unit: int, pdu: bytes) -> bytes:
    from easylab.core.crc import crc16

    body = bytes([unit]) + pdu
    crc = crc16(body)
    return body + bytes([crc & 0xFF, crc >> 8])


def modbus_decls() -> str:
    """MODBUS_DECLS with the request's RTU frame (shared with bench_pic18)."""
    return MODBUS_DECLS.format(frame=", ".join(f"0x{b:02X}u" for b in _rtu_frame(1, bytes([4, 0, 0, 0, 125]))))


# What the Modbus programs time: the PDU handler alone, the RTU exchange, and
# (not timed) the RTU exchange with the reply's CRC checked by the bitwise
# el_crc16 (0 over a frame and its CRC).
MODBUS_BODIES = {
    "pdu": "check += el_mb_pdu(mb_request, 5u, mb_response, false);",
    "rtu": "check += mb_serve();",
    "rtu_checked": "{ uint16_t len = mb_serve(); check += len + el_crc16(mb_rtu.buf, len); }",
    "baseline": "",
}
MODBUS_SETUP = "el_svc_gen_boot(); /* the map */ el_mb_rtu_init(&mb_rtu, 1u, false);"
# Bytes per answer: function, byte count, 250 data bytes; the RTU reply adds the unit and the CRC.
MODBUS_ANSWER = {"pdu": 252, "rtu": 255, "rtu_checked": 255}


def modbus_check(name: str, check: int, n: int) -> None:
    """Stop when a Modbus program's answers were not what a 125-register
    read gives (or a reply's CRC was wrong)."""
    want = MODBUS_ANSWER.get(name)
    if want is not None and check != n * want:
        raise SystemExit(f"the 125-register read ({name}) answered {check / n} bytes, not {want}"
                         " (or a reply with a wrong CRC)")


def modbus_response(tmp: Path, runner: Path, tiny: bool = False) -> dict:
    """Cycles the slave needs to answer a 125-register read (function 04)
    on the ATmega2560: the request's PDU handled into its response (el_mb_pdu
    alone), and the whole RTU exchange as a firmware runs it: the request
    frame's 8 bytes received (their running CRC), the silence, the reply
    built with its CRC (el_mb_rtu_reply). A reply's CRC is checked by the
    bitwise el_crc16 in a build that is not timed. Goal: the RTU exchange in
    MODBUS_GOAL_CYCLES."""
    work = tmp / "modbus"
    work.mkdir()
    model = work / "mbbench.elab"
    model.write_text(MODBUS_MODEL)
    program, board = _generate(model, work, MCU)
    extra = [p for p in work.glob("*.c") if p.name not in ("model.c",)]
    n = 1 if tiny else 10
    cycles = {}
    for name, body in MODBUS_BODIES.items():
        elf = _compile(board, work, f"mb_{name}",
                       PROGRAM.format(decls=modbus_decls(), body=body, n=n, setup=MODBUS_SETUP), extra)
        cycles[name], check = _cycles(runner, elf)
        modbus_check(name, check, n)
    pdu = (cycles["pdu"] - cycles["baseline"]) / n
    frame = (cycles["rtu"] - cycles["baseline"]) / n
    return {"mcu": MCU, "registers": 125, "pdu_cycles": round(pdu), "pdu_and_crc_cycles": round(frame),
            "pdu_and_crc_us_at_16mhz": round(frame / 16, 1), "goal_cycles": MODBUS_GOAL_CYCLES,
            "goal_met": frame <= MODBUS_GOAL_CYCLES}


# Footprint goals on the ATmega328P (bytes): (flash, RAM).
GOALS = {"blink --release": (1536, 64), "blink (debug build)": (4096, 300), "debug server": (2560, 160)}


def goals(results: dict) -> list[dict]:
    """Each footprint goal against what was measured (rows of the examples'
    sizes and of the footprint's debug build, by part)."""
    measured = {}
    for r in results["examples"]:
        if r["example"] == "blink" and r["mcu"] == "atmega328p" and r["flash"] is not None:
            measured["blink --release" if "--release" in r["flags"] else "blink (debug build)"] = (r["flash"], r["ram"])
    for r in results["footprint"]:
        if r["what"].startswith("+ debug interface") and "flash_by_part" in r:
            measured["debug server"] = (r["flash_by_part"]["debug server"], r["ram_by_part"]["debug server"])
    rows = []
    for what, (flash_goal, ram_goal) in GOALS.items():
        if what in measured:
            flash, ram = measured[what]
            rows.append({"what": what, "flash": flash, "ram": ram, "flash_goal": flash_goal, "ram_goal": ram_goal,
                         "met": flash <= flash_goal and ram <= ram_goal})
    return rows


def main(out_dir: Path, tiny: bool = False) -> dict:
    sys.path.insert(0, str(ROOT))
    codegen = _load("bench_codegen")
    results = {}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        pc = subprocess.run(["pkg-config", "--cflags", "--libs", "simavr"], capture_output=True, text=True,
                            check=True)
        runner = tmp / "runner"
        (tmp / "runner.c").write_text(RUNNER)
        subprocess.run(["gcc", "-O2", "-o", str(runner), str(tmp / "runner.c"), *pc.stdout.split(), "-lelf"],
                       check=True)
        results["cycles"] = [measure(name, case, tmp, runner, tiny) for name, case in codegen.CASES.items()]
        results["footprint"] = footprint(tmp)
        results["examples"] = examples_sizes(tmp, tiny)
        results["modbus"] = modbus_response(tmp, runner, tiny)
        results["goals"] = goals(results)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "avr.json").write_text(json.dumps(results, indent=2) + "\n")
    print(f"generated against hand-written C on the {MCU} (avr-gcc -Os, simavr cycles per activation)")
    print(f"  {'dataflow':28} {'generated':>10} {'hand':>10} {'ratio':>6} {'flash gen':>10} {'hand':>6} {'ratio':>6}")
    for r in results["cycles"]:
        print(f"  {r['case']:28} {r['generated_cycles']:>10} {r['handwritten_cycles']:>10} {r['cycle_ratio']:>6} "
              f"{r['generated_flash']:>10} {r['handwritten_flash']:>6} {r['flash_ratio']:>6}")
    print("runtime footprint on the atmega328p (bytes)")
    for r in results["footprint"]:
        if "error" in r:
            print(f"  {r['what']:34} does not build: {r['error'].splitlines()[0]}")
        else:
            added = f"  (+{r['flash_added']} flash, +{r['ram_added']} RAM)" if "flash_added" in r else ""
            print(f"  {r['what']:34} flash {r['flash']:>6}  RAM {r['ram']:>5}{added}")
            print("      flash: " + ", ".join(f"{k} {v}" for k, v in r["flash_by_part"].items() if v))
            print("      RAM:   " + ", ".join(f"{k} {v}" for k, v in r["ram_by_part"].items() if v))
    print("examples")
    for r in results["examples"]:
        print(f"  {r['example']:20} {r['mcu']:11} {r['flags']:34} flash {r['flash']!s:>6}  RAM {r['ram']!s:>5}"
              f"{'' if r['fits'] else '  (does not fit)'}")
    m = results["modbus"]
    print(f"Modbus response on the {MCU}: a {m['registers']}-register read takes {m['pdu_cycles']} cycles in the "
          f"PDU handler, {m['pdu_and_crc_cycles']} as an RTU exchange with its CRCs ({m['pdu_and_crc_us_at_16mhz']} us "
          f"at 16 MHz; goal {m['goal_cycles']}: {'met' if m['goal_met'] else 'NOT met'})")
    print("footprint goals on the atmega328p (flash / RAM bytes)")
    for g in results["goals"]:
        print(f"  {g['what']:22} {g['flash']:>6} / {g['ram']:<5} goal {g['flash_goal']} / {g['ram_goal']}: "
              f"{'met' if g['met'] else 'NOT met'}")
    return results


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"))
