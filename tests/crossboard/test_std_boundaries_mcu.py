"""The std actors at their arguments' ends (std_ends.py) build with every
MCU board's compiler: avr-gcc, the F16's C89 checks and its 8051 proxy's
sdcc, the PIC18's sdcc (a comparison an argument decides is no error:
docs/language.md, "Actor code and compiler warnings")."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

from boundaries import NUMBERS
from firmware_builds import build
from std_ends import models  # noqa: F401 (a fixture)


def test_avr_builds_them(tmp_path, models):
    with ThreadPoolExecutor(max_workers=2) as pool:
        jobs = [pool.submit(build, models[key], "avr", tmp_path / key, "--mcu", "atmega2560")
                for key in ("mcu", "user")]
        for job in jobs:
            job.result()


def test_f16_checks_and_its_proxy_build_them(tmp_path, models):
    """--check: gcc and clang in C89, clang-tidy with a 16-bit int, over
    every actor; --sim: the 16-bit proxy, sdcc -mmcs51, over the comparing
    actors of each type (the 8051's 64 KB of code holds one type's)."""
    jobs = [(key, "--check") for key in ("small", "wide", "user")]
    jobs += [(f"cmp_{t.name}", "--sim") for t in NUMBERS] + [("user", "--sim")]
    with ThreadPoolExecutor(max_workers=2) as pool:
        done = [pool.submit(build, models[key], "f16", tmp_path / f"{key}{mode}", mode) for key, mode in jobs]
        for job in done:
            job.result()


def test_pic18_builds_them(tmp_path, models):
    """sdcc's pic16 port over the comparing actors (every type, every end;
    sdcc's warning 94 comes from its front end, which the 8051 proxy's
    builds above run over each type too) and the user actor: the PIC18
    build writes actors into their dataflows' functions, above the pragma
    at the end of model.c, and must move it."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        jobs = [pool.submit(build, models[key], "pic18", tmp_path / key, "--mcu", "pic18f4620")
                for key in ("cmp_small", "cmp_wide", "user")]
        for job in jobs:
            job.result()
