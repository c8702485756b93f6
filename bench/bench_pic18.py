"""The PIC18 board: generated code against hand-written C in instruction
cycles, the footprint of the debug server, the Modbus response time.

1. Cycles per activation, exact, in gpsim (instruction cycles: 10 MHz at
   40 MHz): pt100_sensor's Acquire and cd_to_dat's Convert, the generated
   dataflow function (model.c of a PIC18 release build, through the
   board's sdcc pipeline: the 64-bit lowering, unreachable functions
   dropped, RAM-only pointers as __data) against the hand-written C of
   bench/handwritten/ compiled by the same sdcc, on the same inputs (the
   cases of bench_codegen.py; pt100_sensor is its PIC18 variant of
   boards/pic18/conformance/, the same Acquire). Convert runs its nested
   schedule against the hand-written nested version
   (cd_to_dat_convert_nested.c): the flat schedule's buffers, generated or
   hand-written, take 4,724 bytes, more than the part's RAM. A small libgpsim runner stamps
   the cycle counter at marks the program writes to a RAM byte. Program
   memory: the program with one side minus the program with neither.
   Goal: at most 1.10x the cycles of hand-written C.
2. Program memory and RAM of blink with and without the debug server (the
   PIC18F4620 and the PIC18F4520, whose debug buffers are sized from the
   model), and which examples fit.
3. The Modbus slave's answer to a 125-register read, in cycles.

Writes out_dir/pic18.json and prints a table. Run: python bench/bench_pic18.py [out_dir]
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
MCU = "pic18f4620"  # Convert's buffers, generated or hand-written, need more than the 4520's RAM
VARIANTS = ROOT / "boards" / "pic18" / "conformance"

PROGRAM = """
#include "model.c"
{decls}
volatile uint8_t bench_mark;   /* the runner stamps the cycles of each write */
volatile uint32_t bench_check; /* what the measured code computed */

static uint32_t run(uint16_t n)
{{
    uint16_t i;
    uint32_t check = 0u;
    bench_mark = 1u;
    for (i = 0u; i < n; i++) {{ {body}
    }}
    bench_mark = 2u;
    return check;
}}

void el_run(int argc, char **argv)
{{
    (void)argc;
    (void)argv;
    {setup}
    bench_check = run({n}u);
    bench_mark = 3u;
}}
"""

RUNNER = r"""
/* Run a PIC18 program in libgpsim; print the cycles between its marks 1
 * and 2 and its check value (written before mark 3). */
#include <gpsim/interface.h>
#include <gpsim/sim_context.h>
#include <gpsim/gpsim_time.h>
#include <gpsim/breakpoints.h>
#include "gpsim_hooks.h"
#include <cstdlib>

static Processor *cpu;
static guint64 start, stop;
static bool done;

static void mark(unsigned, unsigned v)
{
    if (v == 1u) start = get_cycles().get();
    else if (v == 2u) stop = get_cycles().get();
    else if (v == 3u) { done = true; get_bp().halt(); }
}

class Stopper : public TriggerObject {
public:
    void callback() override { get_bp().halt(); }
};

int main(int argc, char **argv)
{
    if (argc < 5) return 2;
    {
        QuietStdout quiet;
        initialize_gpsim_core();
        CSimulationContext::GetContext()->LoadProgram(argv[2], argv[1], &cpu);
        initialization_is_complete();
    }
    if (cpu == nullptr) return 2;
    unsigned mark_addr = strtoul(argv[3], 0, 0), check_addr = strtoul(argv[4], 0, 0);
    cpu->registers[mark_addr] = new HookRegister(cpu, cpu->registers[mark_addr], mark);
    Stopper stopper;
    while (!done && get_cycles().get() < 2000000000ull) {
        get_cycles().set_break(get_cycles().get() + 1000000u, &stopper);
        cpu->run(false);
    }
    unsigned long check = 0;
    for (int i = 3; i >= 0; i--) check = check << 8 | (cpu->registers[check_addr + i]->get_value() & 0xFFu);
    printf("%llu %lu\n", (unsigned long long)(stop - start), check);
    return done ? 0 : 1;
}
"""


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _board():
    from easylab.board.registry import load_board

    return load_board("pic18").configure(MCU)


def _generate(model: Path, out: Path, schedule: str | None = None):
    """model.c and the PIC18 board's generated headers of a release build."""
    from easylab.build import generate
    from easylab.pipeline import lower_file

    program, result = lower_file(model, schedule=schedule)
    if program is None:
        raise SystemExit(result.report())
    board = _board()
    generate(program, board, out, release=True, checked=board.check(program))
    return program, board


def _build(board, work: Path, name: str, source: str, extra: list[Path]) -> tuple[Path, object]:
    (work / f"{name}.c").write_text(source)
    runtime = ("el_arith.c", "el_crc16.c", "el_modbus.c", "el_persist.c", "el_service.c")
    return board.build_program([work / f"{name}.c", *extra], work, name, runtime)


def _cycles(runner: Path, hexfile: Path, lmap) -> tuple[int, int]:
    symbols = lmap.ram_symbols()
    out = subprocess.run([str(runner), f"p{MCU[3:]}", str(hexfile.with_suffix(".cod")),
                          str(symbols["bench_mark"]), str(symbols["bench_check"])],
                         capture_output=True, text=True, timeout=900)
    if out.returncode != 0:
        raise SystemExit(f"{hexfile.name} did not end cleanly in gpsim: {out.stdout}{out.stderr}")
    cycles, check = out.stdout.strip().splitlines()[-1].split()
    return int(cycles), int(check)


def measure(name: str, case: dict, tmp: Path, runner: Path, tiny: bool = False) -> dict:
    """Cycles and program memory per activation of a bench_codegen case on the PIC18."""
    work = tmp / re.sub(r"\W+", "_", name)
    model = ROOT / case["model"]
    if (VARIANTS / model.name).is_file():
        model = VARIANTS / model.name  # the same dataflow on the PIC18's pins, without the second UART
    program, board = _generate(model, work, case.get("schedule"))
    hand = HERE / "handwritten" / case["handwritten"]
    row = _load("bench_codegen").compare_on_target(
        name, case, program, board, PROGRAM, 2 if tiny else max(1, case["activations"] // 20),
        build=lambda kind, src: _build(board, work, kind, src, [hand]),
        cycles_of=lambda built: _cycles(runner, *built), flash_of=lambda built: built[1].flash, target="PIC18")
    return {"mcu": MCU, **row}


# The flat Convert's buffers do not fit the RAM: the PIC18 compares the
# nested schedule, with a hand-written version of its own.
FLAT_CONVERT = "cd_to_dat Convert (flat)"


def pic18_cases(cases: dict) -> dict:
    """bench_codegen's cases the PIC18 runs: all but the flat Convert, the
    nested one against the hand-written nested C."""
    out = {name: case for name, case in cases.items() if name != FLAT_CONVERT}
    nested = "cd_to_dat Convert (nested)"
    out[nested] = dict(out[nested], handwritten="cd_to_dat_convert_nested.c")
    return out


def _size(out: str) -> tuple[int | None, int | None]:
    m = re.search(r"program memory (\d+) of \d+ .* RAM (\d+) of", out)
    return (int(m.group(1)), int(m.group(2))) if m else (None, None)


def blink_sizes(tmp: Path, tiny: bool = False) -> list[dict]:
    """blink with and without the debug server; and the examples on the
    PIC18F4620 (debug builds: which fit)."""
    builds = [("blink", "pic18f4620", []), ("blink", "pic18f4620", ["--release"]),
              ("blink", "pic18f4520", ["--release"]), ("blink", "pic18f4520", [])]
    if not tiny:
        builds += [(p.stem, "pic18f4620", []) for p in sorted((ROOT / "examples").glob("*.elab"))
                   if p.stem != "blink"]
        builds += [(p.stem, "pic18f4620", ["--variant"]) for p in sorted(VARIANTS.glob("*.elab"))]
    rows = []
    for name, mcu, flags in builds:
        model = ROOT / "examples" / f"{name}.elab"
        if "--variant" in flags:  # the PIC18 variant with its example's debug line
            model = tmp / "variants" / f"{name}.elab"
            model.parent.mkdir(parents=True, exist_ok=True)
            model.write_text((VARIANTS / f"{name}.elab").read_text() + "debug on uart0 baud 115200\n")
        out = tmp / "sizes" / f"{name}-{mcu}-{'-'.join(f.strip('-') for f in flags) or 'debug'}"
        proc = subprocess.run([sys.executable, "-m", "easylab", "build", str(model), "--board", "pic18", "--mcu", mcu,
                               *(f for f in flags if f != "--variant"), "-o", str(out)],
                              capture_output=True, text=True, cwd=ROOT)
        flash, ram = _size(proc.stdout + proc.stderr)
        why = "" if proc.returncode == 0 else proc.stderr.strip().splitlines()[-1][:160]
        rows.append({"model": name + (" (PIC18 variant)" if "--variant" in flags else ""), "mcu": mcu,
                     "flags": " ".join(f for f in flags if f != "--variant") or "(debug build)",
                     "program_memory": flash, "ram": ram, "fits": proc.returncode == 0, "why_not": why})
    return rows


def modbus_response(tmp: Path, runner: Path, tiny: bool = False) -> dict:
    """Cycles the slave needs to answer a 125-register read (function 04):
    the request's PDU handled into its response, and the whole RTU exchange
    with its CRCs (the model and the programs of bench_avr)."""
    avr = _load("bench_avr")
    work = tmp / "modbus"
    work.mkdir()
    model = work / "mbbench.elab"
    model.write_text(avr.MODBUS_MODEL)
    program, board = _generate(model, work)
    # The service tables name the port's Modbus RTU functions (pic18_interfaces.c).
    extra = [p for p in work.glob("*.c") if p.name != "model.c"] + [ROOT / "boards" / "pic18" / "pic18_interfaces.c"]
    n = 1 if tiny else 5
    cycles = {}
    for name, body in avr.MODBUS_BODIES.items():
        built = _build(board, work, f"mb_{name}",
                       PROGRAM.format(decls=avr.modbus_decls(), body=body, n=n, setup=avr.MODBUS_SETUP), extra)
        cycles[name], check = _cycles(runner, *built)
        avr.modbus_check(name, check, n)
    pdu = (cycles["pdu"] - cycles["baseline"]) / n
    frame = (cycles["rtu"] - cycles["baseline"]) / n
    return {"mcu": MCU, "registers": 125, "pdu_cycles": round(pdu), "pdu_and_crc_cycles": round(frame),
            "pdu_and_crc_us_at_10mips": round(frame / 10, 1)}


def _runner(tmp: Path) -> Path:
    runner = tmp / "runner"
    (tmp / "runner.cc").write_text(RUNNER)
    glib = subprocess.run(["pkg-config", "--cflags", "glib-2.0"], capture_output=True, text=True, check=True)
    subprocess.run(["g++", "-O2", "-std=c++14", "-I/usr/include/gpsim", f"-I{ROOT / 'boards' / 'pic18' / 'sim'}",
                    *glib.stdout.split(), "-o", str(runner), str(tmp / "runner.cc"), "-lgpsim"], check=True)
    return runner


def main(out_dir: Path, tiny: bool = False) -> dict:
    sys.path.insert(0, str(ROOT))
    codegen = _load("bench_codegen")
    results = {}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        runner = _runner(tmp)
        cases = pic18_cases(codegen.CASES)
        if tiny:
            cases = dict(list(cases.items())[:1])
        results["cycles"] = [measure(name, case, tmp, runner, tiny) for name, case in cases.items()]
        results["sizes"] = blink_sizes(tmp, tiny)
        results["modbus"] = modbus_response(tmp, runner, tiny)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "pic18.json").write_text(json.dumps(results, indent=2) + "\n")
    print(f"generated against hand-written C on the {MCU} (sdcc, gpsim instruction cycles per activation)")
    print(f"  {'dataflow':28} {'generated':>10} {'hand':>10} {'ratio':>6} {'flash gen':>10} {'hand':>6} {'ratio':>6}")
    for r in results["cycles"]:
        print(f"  {r['case']:28} {r['generated_cycles']:>10} {r['handwritten_cycles']:>10} {r['cycle_ratio']:>6} "
              f"{r['generated_flash']:>10} {r['handwritten_flash']:>6} {r['flash_ratio']:>6}")
    print("sizes (bytes)")
    for r in results["sizes"]:
        fits = "" if r["fits"] else f"  does not fit: {r['why_not']}"
        print(f"  {r['model']:34} {r['mcu']:11} {r['flags']:14} program memory {r['program_memory']!s:>6}  "
              f"RAM {r['ram']!s:>5}{fits}")
    m = results["modbus"]
    print(f"Modbus response on the {MCU}: a {m['registers']}-register read takes {m['pdu_cycles']} cycles in the "
          f"PDU handler, {m['pdu_and_crc_cycles']} as an RTU exchange with its CRCs ({m['pdu_and_crc_us_at_10mips']} us "
          f"at 10 MIPS)")
    return results


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"))
