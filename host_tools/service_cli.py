"""``easylab-service``: read, write, monitor, back up and restore a running
EasyLab firmware's service items over Modbus, by name, through the
``service_map.json`` that ``easylab build`` writes beside the firmware
(docs/service.md, "The tool").

    easylab-service --map build/m/host/service_map.json --tcp 127.0.0.1:1502 read temperature
    easylab-service --map service_map.json --rtu /dev/ttyUSB0 --parity N write cal_gain 1020

Exit status: 0 done; 1 the device did not answer, refused a request, or
is not the one the map describes; 2 a bad command line, map, name or
value. Every failure is one line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .modbus_link import ID_MODEL_NAME, ID_PROGRAM, DeviceException, LinkError, LinkStats, ModbusLink
from .service_map import MapError, ServiceItem, ServiceMap, ValueError_, load_map, read_groups

PROG = "easylab-service"
EXIT_OK, EXIT_DEVICE, EXIT_USAGE = 0, 1, 2
BACKUP_FORMAT = 1


class UsageError(Exception):
    """A bad command line (exit status 2)."""


# ====================================================================== connection


def _parity(text: str | None, mapped: str | None) -> str:
    if text is not None:
        return text
    return {"none": "N", "even": "E", "odd": "O"}.get(mapped or "none", "N")


@dataclass(frozen=True)
class DeviceAddress:
    """Where the device is (the command line, with the map's defaults): enough
    to open its link again and again (the web panel reconnects)."""

    smap: ServiceMap
    tcp: tuple[str, int] | None
    rtu: tuple[str, int, str] | None
    unit: int
    timeout: float
    check: bool

    @property
    def where(self) -> str:
        return f"{self.tcp[0]}:{self.tcp[1]}" if self.tcp else f"{self.rtu[0]} unit {self.unit}"

    def connect(self, stats: LinkStats | None = None) -> ModbusLink:
        """Open the link and, unless --no-check, check the device's program."""
        if self.tcp:
            link = ModbusLink.tcp(*self.tcp, self.unit, self.timeout, stats)
        else:
            link = ModbusLink.rtu(*self.rtu, self.unit, self.timeout, stats)
        if self.check:
            try:
                check_identity(link, self.smap)
            except BaseException:
                link.close()
                raise
        return link


def device_address(args, smap: ServiceMap) -> DeviceAddress:
    """The device of the command line (UsageError when it is not given well)."""
    tcp_cfg = smap.interfaces.get("tcp", {})
    rtu_cfg = smap.interfaces.get("rtu", {})
    if args.tcp and args.rtu:
        raise UsageError("give --tcp or --rtu, not both")
    if args.tcp:
        m = re.fullmatch(r"\[?([^\]]*?)\]?(?::(\d+))?", args.tcp)
        host = m.group(1) if m else args.tcp
        port = int(m.group(2)) if m and m.group(2) else int(tcp_cfg.get("port", 502))
        if not host or not 1 <= port <= 65535:
            raise UsageError(f"--tcp {args.tcp}: give HOST:PORT")
        return DeviceAddress(smap, (host, port), None, args.unit if args.unit is not None else 1, args.timeout,
                             not args.no_check)
    if args.rtu:
        rtu = (args.rtu, args.baud or int(rtu_cfg.get("baud", 19200)), _parity(args.parity, rtu_cfg.get("parity")))
        return DeviceAddress(smap, None, rtu, args.unit if args.unit is not None else int(rtu_cfg.get("unit", 1)),
                             args.timeout, not args.no_check)
    raise UsageError("give the device: --tcp HOST:PORT or --rtu PORT")


def open_link(args, smap: ServiceMap) -> ModbusLink:
    return device_address(args, smap).connect()


def check_identity(link: ModbusLink, smap: ServiceMap) -> None:
    """The device must run the program the map was made for."""
    try:
        ident = link.identify()
    except DeviceException as err:
        raise LinkError(f"the device at {link.where} does not identify itself (43/14: exception {err.code:02d}); "
                        f"it is not an EasyLab firmware, or give --no-check") from None
    program = ident.get(ID_PROGRAM)
    if program is None or program.lower() != smap.program_id.lower():
        model = ident.get(ID_MODEL_NAME, "?")
        raise LinkError(f"wrong device: {link.where} runs model '{model}' (program {program or 'unknown'}), "
                        f"but {smap.path} is the map of model '{smap.model}' (program {smap.program_id})")


# ====================================================================== values


def read_values(link: ModbusLink, items: list[ServiceItem]) -> dict[str, object]:
    values: dict[str, object] = {}
    for group in read_groups(items):
        first = group[0]
        raw = link.read(first.table, first.address, group[-1].end - first.address)
        for it in group:
            off = it.address - first.address
            values[it.name] = bool(raw[off]) if it.is_bit else it.from_registers(raw[off:off + it.registers])
    return values


def write_value(link: ModbusLink, it: ServiceItem, value) -> None:
    try:
        if it.is_bit:
            link.write_coil(it.address, bool(value))
        elif it.registers == 1:
            link.write_register(it.address, it.to_registers(value)[0])
        else:
            link.write_registers(it.address, it.to_registers(value))
    except DeviceException as err:
        if err.code == 3:
            raise DeviceException(f"{it.format(value)} is outside the range of '{it.name}' ({it.describe_range()}): "
                                  f"the device refused it (exception 03), nothing changed", 3) from None
        if err.code == 4:
            raise DeviceException(f"'{it.name}' = {it.format(value)} was applied but could not be stored "
                                  f"(exception 04)", 4) from None
        raise


def _shown(it: ServiceItem, value) -> str:
    return f"{it.format(value)}{' ' + it.unit if it.unit else ''}"


def _items(smap: ServiceMap, names: list[str]) -> list[ServiceItem]:
    return [smap.item(n) for n in names]


# ====================================================================== commands


def cmd_list(args, smap: ServiceMap) -> int:
    rows = [("name", "table", "address", "type", "unit", "scale", "range", "access", "persist")]
    for it in smap.items:
        addr = f"{it.address}" if it.registers == 1 else f"{it.address}..{it.end - 1}"
        rng = f"{it.format(it.range[0])}..{it.format(it.range[1])}" if it.range else ""  # engineering units
        rows.append((it.name, it.table, addr, it.type, it.unit or "", it.scale.text() if it.scaled else "", rng,
                     it.access, "yes" if it.persist else ""))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    print(f"model {smap.model} (program {smap.program_id}): {len(smap.items)} service items")
    for r in rows:
        print("  ".join(cell.ljust(widths[k]) for k, cell in enumerate(r)).rstrip())
    return EXIT_OK


def cmd_read(args, smap: ServiceMap) -> int:
    items = _items(smap, args.names)
    link = open_link(args, smap)
    try:
        values = read_values(link, items)
    finally:
        link.close()
    for it in items:
        print(f"{it.name} = {_shown(it, values[it.name])}")
    return EXIT_OK


def cmd_write(args, smap: ServiceMap) -> int:
    it = smap.item(args.name)
    if not it.writable:
        raise UsageError(f"'{it.name}' is read-only (service ro)")
    value = it.parse(args.value)
    link = open_link(args, smap)
    try:
        write_value(link, it, value)
        now = read_values(link, [it])[it.name]
    finally:
        link.close()
    print(f"{it.name} = {_shown(it, now)}")
    return EXIT_OK


def parse_period(text: str) -> float:
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*(ms|s)?\s*", text)
    if not m:
        raise UsageError(f"--every {text}: give a period such as 500ms or 1s")
    seconds = float(m.group(1)) / (1000.0 if (m.group(2) or "ms") == "ms" else 1.0)
    if seconds < 0.01:
        raise UsageError(f"--every {text}: at least 10ms")
    return seconds


def cmd_monitor(args, smap: ServiceMap) -> int:
    items = _items(smap, args.names)
    period = parse_period(args.every)
    if args.count is not None and args.count < 1:
        raise UsageError("--count: at least 1")
    out_csv = writer = None
    if args.csv:
        try:
            out_csv = open(args.csv, "w", newline="", encoding="utf-8")
        except OSError as err:
            raise UsageError(f"--csv {args.csv}: {err.strerror or err}") from None
        writer = csv.writer(out_csv, lineterminator="\n")
        writer.writerow(["time_s"] + [it.name for it in items])
    link = open_link(args, smap)
    heads = ["time_s"] + [f"{it.name}{' [' + it.unit + ']' if it.unit else ''}" for it in items]
    widths = [max(len(h), 10) for h in heads]
    print("  ".join(h.rjust(w) for h, w in zip(heads, widths)), flush=True)
    start = time.monotonic()
    n = 0
    try:
        while args.count is None or n < args.count:
            due = start + n * period
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            values = read_values(link, items)
            t = time.monotonic() - start
            cells = [f"{t:.3f}"] + [items[k].format(values[it.name]) for k, it in enumerate(items)]
            print("  ".join(c.rjust(w) for c, w in zip(cells, widths)), flush=True)
            if writer is not None:
                writer.writerow(cells)
                out_csv.flush()
            n += 1
    except KeyboardInterrupt:
        pass
    finally:
        link.close()
        if out_csv is not None:
            out_csv.close()
    return EXIT_OK


def backup_document(smap: ServiceMap, values: dict[str, object]) -> dict:
    """A backup (docs/service.md) of the writable params' `values`."""
    return {"format": BACKUP_FORMAT, "model": smap.model, "program_id": smap.program_id,
            "params": {it.name: values[it.name] for it in smap.params()}}


def cmd_backup(args, smap: ServiceMap) -> int:
    params = smap.params()
    link = open_link(args, smap)
    try:
        values = read_values(link, params)
    finally:
        link.close()
    doc = backup_document(smap, values)
    try:
        Path(args.file).write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    except OSError as err:
        raise UsageError(f"{args.file}: {err.strerror or err}") from None
    print(f"backed up {len(params)} params of model {smap.model} to {args.file}")
    return EXIT_OK


def plan_restore(doc, smap: ServiceMap, source: str) -> tuple[list[tuple[ServiceItem, object]], list[str]]:
    """The writes that restore the backup `doc` (read from `source`), and one
    line per param skipped (no longer in the map, or read-only now). A
    document that is no backup of this model, or a value that is not one of
    its param's type, is a UsageError or ValueError_."""
    if not isinstance(doc, dict) or doc.get("format") != BACKUP_FORMAT or not isinstance(doc.get("params"), dict):
        raise UsageError(f"{source}: not a backup made by {PROG} backup")
    if doc.get("model") != smap.model:
        raise UsageError(f"{source} is a backup of model '{doc.get('model')}', the map is of model '{smap.model}'")
    todo: list[tuple[ServiceItem, object]] = []
    skipped: list[str] = []
    for name, raw in doc["params"].items():
        try:
            it = smap.item(name)
        except MapError:
            skipped.append(f"{name}: not in the map any more, skipped")
            continue
        if not it.writable:
            skipped.append(f"{name}: read-only now, skipped")
            continue
        todo.append((it, it.parse_stored(str(int(raw)) if isinstance(raw, bool) else str(raw))))
    return todo, skipped


def restore_params(link: ModbusLink, todo: list[tuple[ServiceItem, object]]) -> list[tuple[ServiceItem, str]]:
    """Write every planned value; the params the device refused, with why."""
    refused: list[tuple[ServiceItem, str]] = []
    for it, value in todo:
        try:
            write_value(link, it, value)
        except DeviceException as err:
            refused.append((it, str(err)))
    return refused


def cmd_restore(args, smap: ServiceMap) -> int:
    try:
        doc = json.loads(Path(args.file).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{args.file}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise UsageError(f"{args.file}: not a backup ({getattr(err, 'strerror', None) or err})") from None
    todo, skipped = plan_restore(doc, smap, args.file)
    for line in skipped:
        print(f"{PROG}: {line}", file=sys.stderr)
    link = open_link(args, smap)
    try:
        refused = restore_params(link, todo)
    finally:
        link.close()
    for it, why in refused:
        print(f"{PROG}: {it.name}: {why}", file=sys.stderr)
    print(f"restored {len(todo) - len(refused)} of {len(todo)} params of model {smap.model} from {args.file}")
    return EXIT_DEVICE if refused else EXIT_OK


def cmd_web(args, smap: ServiceMap) -> int:
    from .web.server import run_panel  # aiohttp only for this command
    return run_panel(args, smap)


# ====================================================================== command line


def _common(p: argparse.ArgumentParser, sub: bool) -> None:
    d = {"default": argparse.SUPPRESS} if sub else {}
    g = p.add_argument_group("map and device")
    g.add_argument("--map", metavar="FILE", help="service_map.json of the firmware (written by easylab build)", **d)
    g.add_argument("--tcp", metavar="HOST:PORT", help="Modbus TCP (default port: the map's)", **d)
    g.add_argument("--rtu", metavar="PORT", help="Modbus RTU on a serial port or pty", **d)
    g.add_argument("--baud", type=int, metavar="B", help="RTU baud rate (default: the map's)", **d)
    g.add_argument("--parity", choices=["N", "E", "O"], type=str.upper, help="RTU parity (default: the map's; "
                   "ptys take N only)", **d)
    g.add_argument("--unit", type=int, metavar="U", help="unit id (default: the map's RTU unit; TCP: 1)", **d)
    g.add_argument("--timeout", type=float, metavar="S", help="seconds to wait for a reply (default 1)", **d)
    g.add_argument("--no-check", action="store_true", help="do not check that the device runs the map's program",
                   **d)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=PROG, description="Read, write and monitor the service items of an "
                                     "EasyLab firmware over Modbus, by name.")
    _common(parser, sub=False)
    parser.set_defaults(timeout=1.0)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def add(name, help_, func):
        p = sub.add_parser(name, help=help_, description=help_)
        _common(p, sub=True)
        p.set_defaults(func=func)
        return p

    add("list", "list the map's items (no device needed)", cmd_list)
    p = add("read", "read items", cmd_read)
    p.add_argument("names", nargs="+", metavar="NAME")
    p = add("write", "write an item, in the model's units", cmd_write)
    p.add_argument("name", metavar="NAME")
    p.add_argument("value", metavar="VALUE")
    p = add("monitor", "read items periodically: a live table", cmd_monitor)
    p.add_argument("names", nargs="+", metavar="NAME")
    p.add_argument("--every", default="500ms", metavar="PERIOD", help="sampling period (default 500ms)")
    p.add_argument("--csv", metavar="FILE", help="also write the samples to a CSV file")
    p.add_argument("--count", type=int, metavar="N", help="stop after N samples (default: until Ctrl-C)")
    p = add("backup", "save every writable param to a file", cmd_backup)
    p.add_argument("file", metavar="FILE")
    p = add("restore", "write the params of a backup file back", cmd_restore)
    p.add_argument("file", metavar="FILE")
    p = add("web", "serve the service panel: a web page to monitor, plot and tune the device", cmd_web)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.epilog = WEB_EPILOG
    p.add_argument("--listen", default="127.0.0.1:8080", metavar="ADDR:PORT",
                   help="where the panel listens (default 127.0.0.1:8080; port 0 picks a free one)")
    p.add_argument("--token", metavar="TOKEN", help="the token a browser must present (default: none on a "
                   "loopback address, a new random one printed at start elsewhere)")
    p.add_argument("--every", default="250ms", metavar="PERIOD", help="sampling period (default 250ms)")
    return parser


WEB_EPILOG = """\
The page lists every service item of the map (unit, range, live value),
plots chosen items, writes rw params (range checked first), and backs up
and restores the params as files in the format of `backup`. The device is
sampled every PERIOD by this process alone; when it stops answering the
panel says so and reconnects by itself.

Safety: on a loopback address (the default) only this machine can open the
panel, and only under a loopback name. On any other address a token is
required (--token, or a random one printed at start with the address to
open); without it nothing can be read or written. Writes must come from the
panel's own page (same origin, JSON, its CSRF header); requests wait for
the device in a queue of 4 and get "busy" beyond that.

  easylab-service --map build/m/host/service_map.json --tcp 127.0.0.1:1502 web
  easylab-service --map service_map.json --rtu /dev/ttyUSB0 web --listen 0.0.0.0:8080
"""


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        if not args.map:
            raise UsageError("give the service map: --map service_map.json")
        smap = load_map(args.map)
        return args.func(args, smap)
    except (UsageError, MapError, ValueError_) as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    except LinkError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return EXIT_DEVICE
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    # `python -m`: run the module under its package name, so that its errors are
    # the classes the modules importing it (the web panel) raise.
    from . import service_cli
    sys.exit(service_cli.main())
