"""The F16 proxy: `easylab proxy --board f16` writes the Softune project of
the proxy (as `easylab build --board f16` does for firmware), its link on
UART1 (boards/f16/f16_uart.c), and `--check` passes its C through the
board's 16-bit proxies (clang for MSP430 and gcc, C89 -pedantic, 16-bit
int, clang-tidy). Nothing here runs an F2MC-16: the s51 simulation of
the board has no UART on a pty (docs/remote.md)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

from easylab.build import build
from easylab.pipeline import lower_file
from easylab.remote.proxy import build_proxy
from remote_testlib import EASYLAB, ROOT

BLINK = ROOT / "boards" / "f16" / "conformance" / "blink.elab"  # the example with the MB90F543's pin


def proxy(out: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*EASYLAB, "proxy", str(BLINK), "--board", "f16", "-o", str(out), *args],
                          capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)


def test_easylab_proxy_writes_the_softune_project_and_checks_its_c(tmp_path):
    out = tmp_path / "p"
    proc = proxy(out, "--check", "--baud", "76800")
    assert proc.returncode == 0, proc.stderr
    for tool in (r"clang --target=msp430 -std=c89 -pedantic-errors -Wall -Wextra -Werror: (\d+) files clean",
                 r"gcc -std=c89 -pedantic-errors -Wall -Wextra -Werror: (\d+) files clean"):
        assert re.search(tool, proc.stdout), proc.stdout
    assert "(16-bit int): no finding" in proc.stdout
    assert re.search(r"mb90f543: flash about \d+ of 131072 bytes, RAM about \d+ of 6144 bytes", proc.stdout)
    assert proc.stdout.splitlines()[-1] == str(out)
    # The project builds the proxy with Softune: proxy.c and the runtime's link, the proxy's defines.
    makefile = (out / "Makefile").read_text()
    assert "-D EL_REMOTE_PROXY=1 -D EL_REMOTE_BAUD=76800UL" in makefile
    assert "obj/proxy.obj: proxy.c" in makefile and "obj/el_remote.obj: runtime/el_remote.c" in makefile
    config = (out / "el_f16_config.h").read_text()
    assert "#define EL_F16_REMOTE_UART 1u" in config and "#elif EL_REMOTE_BAUD == 76800UL" in config
    assert "#pragma intvect el_f16_uart1_rx_interrupt 40" in (out / "el_f16_vectors.c").read_text()
    assert "#define EL_RMT_TX_FRAME 22u" in (out / "el_remote_config.h").read_text()


def test_the_link_is_compiled_in_a_proxy_build_only(tmp_path):
    """The MSP430 objects of the proxy define the link and the reset; those
    of the firmware of the same model do not."""
    program, result = lower_file(BLINK)
    assert program is not None, result.report()
    link = {"el_remote_port_read", "el_remote_port_write", "el_remote_port_end", "el_f16_remote_open",
            "el_f16_hw_reset"}
    proxy_build = build_proxy(program, "f16", tmp_path / "proxy", baud=76800)
    firmware = build(program, "f16", tmp_path / "firmware")
    assert link <= proxy_build.board.symbols(proxy_build.compiled)
    assert not {"el_remote_port_read", "el_f16_remote_open"} & firmware.board.symbols(firmware.compiled)


def test_a_baud_rate_uart1_does_not_make_is_refused(tmp_path):
    proc = proxy(tmp_path / "p", "--baud", "115200")
    assert proc.returncode == 1
    assert ("the proxy's link: UART1 of the mb90f543 makes these rates within 2 %: 1200, 2400, 4800, 9600, "
            "19200, 38400, 76800 (easylab proxy --baud)") in proc.stderr


def test_an_unmade_baud_rate_is_one_error_before_any_compiler_runs(tmp_path):
    """The rates come from part.py's usable_rates, the table the generated
    el_f16_config.h holds: checked before anything is generated, so the
    build says it once, with no compiler's output, and writes nothing."""
    out = tmp_path / "p"
    proc = proxy(out, "--baud", "57600")
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [
        "easylab: error: 57600 baud: the proxy's link: UART1 of the mb90f543 makes these rates within 2 %: 1200, "
        "2400, 4800, 9600, 19200, 38400, 76800 (easylab proxy --baud)"]
    assert not out.exists()


def test_a_simulation_build_of_the_proxy_is_refused(tmp_path):
    """The board's s51 simulation has no UART to carry the link."""
    proc = proxy(tmp_path / "p", "--sim", "--baud", "76800")
    assert proc.returncode == 1
    assert ("the f16 board's simulation (the model on an 8051 in s51) has no UART for a remote-execution proxy's "
            "link: build the proxy without --sim") in proc.stderr
