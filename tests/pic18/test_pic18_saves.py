"""The PIC18 board's shared register saves (boards/pic18/saves.py) on
assembly as sdcc writes it."""

from __future__ import annotations

from easylab.board.registry import board_module

saves = board_module("pic18", "saves")

HEAD = "\tlist\tp=18f4620\n\tradix\tdec\n\n\textern\t_other\n"


def function(name: str, frame: bool, k: int, body: str = "\tNOP\n", exits: int = 1) -> str:
    """sdcc's assembly of a function that uses k registers."""
    lines = [f"S_m__{name}\tcode", f"_{name}:", f";\t.line\t1; m.c\tvoid {name}(void)"]
    if frame:
        lines += ["\tMOVFF\tFSR2H, POSTDEC1", "\tMOVFF\tFSR2L, POSTDEC1", "\tMOVFF\tFSR1H, FSR2H",
                  "\tMOVFF\tFSR1L, FSR2L"]
    lines += [f"\tMOVFF\tr0x{r:02x}, POSTDEC1" for r in range(k)]
    for _ in range(exits):
        lines += [body.rstrip("\n")]
        lines += [f"\tMOVFF\tPREINC1, r0x{r:02x}" for r in range(k - 1, -1, -1)]
        if frame:
            lines += ["\tMOVFF\tPREINC1, FSR2L", "\tMOVFF\tPREINC1, FSR2H"]
        lines += ["\tRETURN\t", ""]
    return "\n".join(lines) + "\n"


def test_a_function_with_a_frame_enters_and_leaves_through_the_shared_routines():
    out = saves.share_saves(HEAD + function("f", True, 3))
    assert "\tMOVLW\t0x03\n\tCALL\t_el_pic18_enter\n" in out
    assert "\tGOTO\t_el_pic18_leave_frame_3\n" in out
    assert "r0x" not in out and "FSR2" not in out and "RETURN" not in out
    assert "\textern\t_el_pic18_enter\n\textern\t_el_pic18_leave_frame_3\n" in out
    assert saves.longest_restores([out]) == (-1, 3)


def test_a_function_without_a_frame_saves_through_them_from_two_registers():
    out = saves.share_saves(HEAD + function("g", False, 2) + function("h", False, 1))
    assert "\tMOVLW\t0x02\n\tCALL\t_el_pic18_save_regs\n" in out and "\tGOTO\t_el_pic18_leave_2\n" in out
    assert out.count("\tMOVFF\tr0x00, POSTDEC1") == 1  # h's one register: the call would cost as much
    assert saves.longest_restores([out]) == (2, -1)


def test_every_exit_of_a_function_is_rewritten():
    out = saves.share_saves(HEAD + function("f", True, 2, exits=2))
    assert out.count("\tGOTO\t_el_pic18_leave_frame_2\n") == 2 and "r0x" not in out


def test_an_exit_that_does_not_return_at_once_keeps_its_frame_pops():
    text = HEAD + function("f", True, 2).replace("\tMOVFF\tPREINC1, FSR2H\n", "\tMOVFF\tPREINC1, FSR2H\n_x:\n")
    out = saves.share_saves(text)
    assert "\tCALL\t_el_pic18_leave_2\n\tMOVFF\tPREINC1, FSR2L\n\tMOVFF\tPREINC1, FSR2H\n" in out


def test_what_is_not_the_saves_mirror_and_interrupt_handlers_stay_as_sdcc_wrote_them():
    odd = function("f", True, 3).replace("\tMOVFF\tPREINC1, r0x01\n", "")
    isr = function("isr", False, 3).replace("\tRETURN\t", "\tRETFIE\t")
    gaps = function("g", False, 5)
    for r in (1, 2, 3):
        gaps = gaps.replace(f"\tMOVFF\tr0x{r:02x}, POSTDEC1\n", "").replace(f"\tMOVFF\tPREINC1, r0x{r:02x}\n", "")
    for text in (odd, isr, gaps):
        assert saves.share_saves(HEAD + text) == HEAD + text


def test_the_routines_module_has_each_entry_the_files_call():
    asm = saves.routines("18f4620", 2, 0)
    for name in ("_el_pic18_save_regs", "_el_pic18_enter", "_el_pic18_leave_1", "_el_pic18_leave_2",
                 "_el_pic18_leave_frame_0"):
        assert f"\tglobal\t{name}\n" in asm and f"\n{name}:\n" in asm
    assert "_el_pic18_leave_frame_1" not in asm
    # entry k pops r0x(k-1) first and falls through to r0x00
    assert "_el_pic18_leave_2:\n\tMOVFF\tPREINC1, r0x01\n_el_pic18_leave_1:\n\tMOVFF\tPREINC1, r0x00\n\tRETURN" in asm


def test_a_register_the_function_leaves_out_is_saved_too():
    text = function("g", False, 4)
    text = text.replace("\tMOVFF\tr0x02, POSTDEC1\n", "").replace("\tMOVFF\tPREINC1, r0x02\n", "")
    out = saves.share_saves(HEAD + text)
    assert "\tMOVLW\t0x04\n\tCALL\t_el_pic18_save_regs\n" in out and "\tGOTO\t_el_pic18_leave_4\n" in out
