"""Devices of the user's own, end to end (docs/boards.md, "Chip models"):
an MCP3201-class SPI ADC and an I2C humidity sensor, each with its handler
file and the model of its chip (`sim "FILE.c"`, sim/el_chip.h), in a model
folder outside the package. On one stimulus the host board, local
execution, the AVR in simavr and the PIC18 in gpsim give the same trace:
the stimulus columns of the devices' `out` data reach the chip models,
the firmware's own handlers read the chips over the simulated buses."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from firmware_builds import build, cli, run_program

SOURCE = Path(__file__).with_name("own_chips")
DURATION = "100ms"


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """The model folder, copied outside the package."""
    out = tmp_path_factory.mktemp("user") / "own_chips"
    shutil.copytree(SOURCE, out)
    return out


def local_trace(folder: Path, name: str, out: Path) -> bytes:
    trace = out / f"{name}.local.csv"
    proc = cli("run", folder / f"{name}.elab", "--fast", "--duration", DURATION, "--stimulus",
               folder / f"{name}.stimulus.csv", "--trace", trace)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return trace.read_bytes()


def board_trace(folder: Path, name: str, board: str, out: Path) -> bytes:
    built = build(folder / f"{name}.elab", board, out / f"{name}-{board}", *(["--sim"] if board != "host" else []))
    trace = out / f"{name}.{board}.csv"
    run_program(built.simulator or built.executable, "--fast", "--duration", DURATION, "--stimulus",
                folder / f"{name}.stimulus.csv", "--trace", trace)
    return trace.read_bytes()


@pytest.mark.parametrize("name", ["own_spi", "own_i2c"])
@pytest.mark.parametrize("board", ["host", "avr", "pic18"])
def test_a_device_of_ones_own_gives_local_executions_trace(folder, tmp_path, name, board):
    reference = local_trace(folder, name, tmp_path)
    rows = reference.decode().splitlines()
    assert len({row.split(",")[1] for row in rows[1:]}) >= 3, "the stimulus should move the device's value"
    assert board_trace(folder, name, board, tmp_path) == reference


def test_both_devices_on_the_avr_at_once(folder, tmp_path):
    """One model with both chips (the AVR has an SPI and a TWI; the PIC18's
    one MSSP serves one of them)."""
    assert board_trace(folder, "own", "avr", tmp_path) == local_trace(folder, "own", tmp_path)


def test_a_value_the_chip_cannot_have_ends_the_run_with_the_chips_word(folder, tmp_path):
    stimulus = tmp_path / "wrong.csv"
    stimulus.write_text("time_us,adc.value\n0,100\n20000,5000\n")
    built = build(folder / "own_spi.elab", "avr", tmp_path / "b", "--sim")
    proc = run_program(built.simulator, "--fast", "--duration", DURATION, "--stimulus", stimulus, "--trace",
                       tmp_path / "t.csv", ok=False)
    assert proc.returncode != 0
    assert "adc (chip model): a count of 5000: the chip converts 0 .. 4095" in proc.stderr, proc.stderr


def test_a_missing_or_second_chip_model_is_an_error_at_its_place(tmp_path):
    text = (SOURCE / "own_spi.elab").read_text()
    folder = tmp_path / "m"
    shutil.copytree(SOURCE, folder)
    (folder / "drivers" / "mcp3201_chip.c").unlink()
    proc = cli("check", folder / "own_spi.elab")
    line = next(k for k, row in enumerate(text.splitlines(), 1) if 'sim "drivers/mcp3201_chip.c"' in row)
    assert proc.returncode == 1
    assert f"own_spi.elab:{line}:" in proc.stdout + proc.stderr
    assert "chip model 'drivers/mcp3201_chip.c' not found" in proc.stdout + proc.stderr
    (folder / "twice.elab").write_text(text.replace('sim "drivers/mcp3201_chip.c"',
                                                    'sim "drivers/hygro_chip.c" sim "drivers/hygro_chip.c"'))
    proc = cli("check", folder / "twice.elab")
    assert proc.returncode == 1 and "has two chip models" in proc.stdout + proc.stderr


def test_the_spi_example_of_docs_boards_md_is_this_model():
    docs = (Path(__file__).resolve().parents[2] / "docs" / "boards.md").read_text()
    elab = (SOURCE / "own_spi.elab").read_text()
    start = elab.index("device type Mcp3201")
    assert elab[start:elab.index("}\n", start) + 2] in docs
    for name in ("mcp3201_mcu.c", "mcp3201_chip.c"):
        assert (SOURCE / "drivers" / name).read_text() in docs, name


@pytest.mark.parametrize("board", ["avr", "pic18"])
def test_a_column_nothing_in_the_simulation_reads_is_an_error(tmp_path, board):
    """Without its chip model the device's datum has nothing behind it in
    the simulator: its stimulus column is refused, naming it and the
    columns that exist, where it used to be dropped without a word."""
    folder = tmp_path / "m"
    shutil.copytree(SOURCE, folder)
    model = folder / "nochip.elab"
    model.write_text((folder / "own_spi.elab").read_text().replace(' sim "drivers/mcp3201_chip.c"', "")
                     .replace("var level: uint16", "var level: uint16\nparam gain: uint8 = 1"))
    stimulus = tmp_path / "s.csv"
    stimulus.write_text("time_us,adc.value\n0,100\n")
    built = build(model, board, tmp_path / "b", "--sim")
    proc = run_program(built.simulator, "--fast", "--duration", DURATION, "--stimulus", stimulus, ok=False)
    assert proc.returncode != 0
    assert "column 'adc.value': nothing in this program reads it: its device runs the model's own handlers" \
        in proc.stderr, proc.stderr
    assert "valid columns: time_us, gain, level\n" in proc.stderr, proc.stderr
    fine = tmp_path / "fine.csv"
    fine.write_text("time_us,gain\n0,2\n")
    run_program(built.simulator, "--fast", "--duration", DURATION, "--stimulus", fine)
