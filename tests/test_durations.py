"""The table that orders the suite's files (tests/durations.py)."""

from pathlib import Path

from durations import TABLE, file_seconds, load

ROOT = Path(__file__).resolve().parent.parent


def test_a_durations_report_sums_per_file():
    report = """
============================= slowest 3 durations ==============================
226.44s call     tests/a/test_x.py::test_one[p]
23.27s setup    tests/a/test_x.py::test_two
1.5s teardown tests/b/test_y.py::test_three
"""
    assert file_seconds(report) == {"tests/a/test_x.py": 226.44 + 23.27, "tests/b/test_y.py": 1.5}


def test_the_table_names_files_that_exist():
    table = load()
    assert table, f"{TABLE} is missing or empty"
    assert [name for name in table if not (ROOT / name).is_file()] == []
