"""Generated code against hand-written C: instructions per activation.

For pt100_sensor's Acquire and cd_to_dat's Convert, a harness includes the
generated model.c (so its static functions are reachable) and the
hand-written reference of bench/handwritten/, runs both N activations on
the same inputs, checks that they compute the same values, and counts the
instructions of each loop with valgrind's callgrind (exact and repeatable,
unlike wall-clock time). Run: python bench/bench_codegen.py [out_dir]
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HANDWRITTEN = ROOT / "bench" / "handwritten"
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-Wno-unused-function"]

CASES = {
    "pt100_sensor Acquire": {
        "model": "examples/pt100_sensor.elab", "dataflow": "Acquire", "handwritten": "pt100_acquire.c",
        "activations": 2000,
        "generated": """
            {task}.{raw} = (uint16_t)(250u + (i % 150u));
            {task}.{gain} = 1000; {task}.{offset} = 0; {task}.{high} = 800;
            {task}.ch0_n = 0u; /* what the task's release does for the channel */
            {fn}();
            check += (uint32_t)(uint16_t){task}.{temperature} + (uint32_t){task}.{alarm};""",
        "hand": """
            hw_acquire((uint16_t)(250u + (i % 150u)), 1000, 0, 800);
            check += (uint32_t)(uint16_t)hw_temperature + (uint32_t)hw_alarm;""",
        "decls": "extern int16_t hw_temperature; extern bool hw_alarm; "
                 "void hw_acquire(uint16_t, int16_t, int16_t, int16_t);",
        "names": {"raw": "sensor.raw", "gain": "cal_gain", "offset": "cal_offset", "high": "alarm_high",
                  "temperature": "temperature", "alarm": "alarm"},
    },
    # The hand-written Convert runs the flat single-appearance schedule (one
    # loop per stage over whole arrays): generated with the same schedule,
    # and with the example's own (the nested schedule: 3.6x less buffer
    # memory for longer loop code).
    "cd_to_dat Convert (flat)": {
        "model": "examples/cd_to_dat.elab", "dataflow": "Convert", "handwritten": "cd_to_dat_convert.c",
        "activations": 200, "schedule": "flat",
        "generated": """
            {fn}();
            check += {task}.{checksum};""",
        "hand": """
            hw_convert();
            check += hw_checksum;""",
        "decls": "extern uint32_t hw_checksum; void hw_convert(void);",
        "names": {"checksum": "checksum"},
    },
}
CASES["cd_to_dat Convert (nested)"] = dict(CASES["cd_to_dat Convert (flat)"], schedule=None)

HARNESS = """
#include "model.c"
#include <stdio.h>
#include <stdlib.h>
{decls}
void el_sim_open(uint8_t d) {{ (void)d; }}
void el_sim_start(uint8_t d) {{ (void)d; }}
void el_sim_read(uint8_t d) {{ (void)d; }}
void el_sim_write(uint8_t d) {{ (void)d; }}
void el_sim_stop(uint8_t d) {{ (void)d; }}
void el_sim_close(uint8_t d) {{ (void)d; }}
/* The service interface's hooks (its tables are not linked here). */
void el_svc_gen_boot(void) {{ }}
void el_svc_gen_poll(void) {{ }}

__attribute__((noinline)) uint32_t bench_generated(uint32_t n)
{{
    uint32_t i, check = 0u;
    for (i = 0u; i < n; i++) {{ {generated}
    }}
    return check;
}}

__attribute__((noinline)) uint32_t bench_handwritten(uint32_t n)
{{
    uint32_t i, check = 0u;
    for (i = 0u; i < n; i++) {{ {hand}
    }}
    return check;
}}

int main(int argc, char **argv)
{{
    uint32_t n = (uint32_t)strtoul(argv[1], 0, 10);
    uint32_t a = 0u, b = 0u;
    if (argc > 2 && argv[2][0] == 'g') a = bench_generated(n);
    if (argc > 2 && argv[2][0] == 'h') b = bench_handwritten(n);
    if (argc > 2 && argv[2][0] == 'c') {{ a = bench_generated(n); b = bench_handwritten(n);
        if (a != b) {{ printf("MISMATCH %lu %lu\\n", (unsigned long)a, (unsigned long)b); return 1; }} }}
    printf("%lu %lu\\n", (unsigned long)a, (unsigned long)b);
    return 0;
}}
"""


def _instructions(exe: Path, n: int, which: str, fn: str, tmp: Path) -> int:
    out = tmp / f"callgrind.{which}.out"
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--collect-atstart=no",
                    f"--toggle-collect={fn}", str(exe), str(n), which], check=True, capture_output=True)
    text = out.read_text()
    m = re.search(r"^(?:summary|totals):\s+(\d+)", text, re.MULTILINE)
    return int(m.group(1))


def measure(name: str, case: dict, tmp: Path, tiny: bool = False) -> dict:
    """Instructions per activation of the generated and hand-written code."""
    sys.path.insert(0, str(ROOT))
    from easylab.board.registry import load_board
    from easylab.codegen import c_model
    from easylab.codegen.render import render
    from easylab.core.paths import runtime_dir
    from easylab.pipeline import lower_file

    program, result = lower_file(ROOT / case["model"], schedule=case.get("schedule"))
    if program is None:
        raise SystemExit(result.report())
    board = load_board("host")
    work = tmp / re.sub(r"\W+", "_", name)
    work.mkdir()
    # A release build, as on the AVR (bench_avr.py): no debug interface in the way.
    (work / "model.c").write_text(render(program, board, release=True)["model.c"])
    view = c_model.build_view(program, board)
    df = next(d for d in program.dataflows if d.name == case["dataflow"])
    fields = {k: view.items[program.item(v).id].local for k, v in case["names"].items()}
    fmt = dict(fields, task=f"el_t{df.task}", fn=f"el_df{df.id}_{c_model.ident(df.name)}")
    harness = HARNESS.format(decls=case["decls"], generated=case["generated"].format(**fmt), hand=case["hand"])
    (work / "harness.c").write_text(harness)
    exe = work / "bench"
    subprocess.run(["gcc", *CFLAGS, f"-I{runtime_dir()}", f"-I{ROOT / 'boards' / 'host'}", f"-I{work}",
                    "-o", str(exe), str(work / "harness.c"), str(runtime_dir() / "el_arith.c"),
                    str(runtime_dir() / "el_wide.c"),
                    str(HANDWRITTEN / case["handwritten"]), "-lm"], check=True)
    n = 5 if tiny else case["activations"]
    same = subprocess.run([str(exe), str(n), "c"], capture_output=True, text=True)
    if same.returncode != 0:
        raise SystemExit(f"{name}: generated and hand-written code disagree: {same.stdout}{same.stderr}")
    generated = _instructions(exe, n, "g", "bench_generated", work)
    handwritten = _instructions(exe, n, "h", "bench_handwritten", work)
    return {"case": name, "activations": n, "generated_per_activation": round(generated / n, 1),
            "handwritten_per_activation": round(handwritten / n, 1),
            "ratio": round(generated / handwritten, 3)}


def compare_on_target(name: str, case: dict, program, board, program_text: str, n: int,
                      build, cycles_of, flash_of, target: str) -> dict:
    """One case on a simulated part: `program_text` (a board's benchmark
    program with {decls}, {body}, {n}, {setup}) is built three times by
    `build(kind, source)`, with the generated dataflow, the hand-written
    one and neither; `cycles_of(built)` runs one and gives (cycles between
    its marks, checksum), `flash_of(built)` its program memory. Both sides'
    checksums must agree; cycles and flash are per activation and net of
    the baseline."""
    from easylab.codegen import c_model

    view = c_model.build_view(program, board)
    df = next(d for d in program.dataflows if d.name == case["dataflow"])
    fields = {k: view.items[program.item(v).id].local for k, v in case["names"].items()}
    fmt = dict(fields, task=f"el_t{df.task}", fn=f"el_df{df.id}_{c_model.ident(df.name)}")
    bodies = {"generated": case["generated"].format(**fmt), "handwritten": case["hand"], "baseline": ""}
    built = {k: build(k, program_text.format(decls=case["decls"], body=body, n=n, setup=""))
             for k, body in bodies.items()}
    (gen_cycles, gen_check), (hw_cycles, hw_check), (base_cycles, _) = (
        cycles_of(built[k]) for k in ("generated", "handwritten", "baseline"))
    if gen_check != hw_check:
        raise SystemExit(f"{name}: generated and hand-written code disagree on the {target}: {gen_check} != {hw_check}")
    base_flash = flash_of(built["baseline"])
    gen_flash = flash_of(built["generated"]) - base_flash
    hw_flash = flash_of(built["handwritten"]) - base_flash
    gen = (gen_cycles - base_cycles) / n
    hw = (hw_cycles - base_cycles) / n
    return {"case": name, "activations": n, "generated_cycles": round(gen, 1),
            "handwritten_cycles": round(hw, 1), "cycle_ratio": round(gen / hw, 3),
            "generated_flash": gen_flash, "handwritten_flash": hw_flash,
            "flash_ratio": round(gen_flash / hw_flash, 3)}


def main(out_dir: Path, tiny: bool = False) -> list[dict]:
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (Debian package: valgrind)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, case in CASES.items():
            rows.append(measure(name, case, Path(tmp), tiny))
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "codegen.json").write_text(json.dumps(rows, indent=2) + "\n")
    print("generated C against hand-written C (x86-64, gcc -O2, callgrind instructions per activation)")
    print(f"  {'dataflow':28} {'generated':>10} {'hand-written':>13} {'ratio':>6}")
    for r in rows:
        print(f"  {r['case']:28} {r['generated_per_activation']:>10} {r['handwritten_per_activation']:>13} "
              f"{r['ratio']:>6}")
    return rows


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"))
