"""Reading the maps ``easylab build`` writes (debug_map.json,
service_map.json) for the host tools: the JSON read with every failure
turned into one line, then validated against the map's JSON Schema.

A map is data from outside (a file given with --map): whatever it holds,
the tools say what is wrong with it in one line and exit non-zero, never
with a traceback. The schemas below are the single statement of what a
tool relies on; what passes them the tools can use.
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema

# A value of a range or an initial value: an integer of the widest type or a
# finite float32 (its largest magnitude), never NaN or infinity.
_FLOAT32_MAX = 3.4028234663852886e38
_NUMBER = {"type": "number", "minimum": -_FLOAT32_MAX, "maximum": _FLOAT32_MAX}
_ID = {"type": "integer", "minimum": 0, "maximum": 65535}
_NAME = {"type": "string", "minLength": 1, "maxLength": 1000}
_TEXT = {"type": "string", "maxLength": 10000}
_RANGE = {"oneOf": [{"type": "null"}, {"type": "array", "items": _NUMBER, "minItems": 2, "maxItems": 2}]}
# An item's scale (docs/language.md): engineering value = stored value x scale.
_SCALE = {"type": "number", "exclusiveMinimum": 0, "maximum": 1e6}
_TYPES = ["bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "time"]

DEBUG_MAP_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "EasyLab debug map (debug_map.json)",
    "type": "object",
    "required": ["format", "program_id", "items"],
    "properties": {
        "format": {"const": "easylab-debug-map"},
        "model": _TEXT,
        "title": {"type": ["string", "null"], "maxLength": 10000},
        "program_id": {"type": "string", "pattern": "^0[xX][0-9a-fA-F]{1,8}$"},
        "tick_us": {"type": "integer", "minimum": 0, "maximum": 2 ** 32 - 1},
        "items": {"type": "array", "items": {
            "type": "object",
            "required": ["id", "name", "kind", "type", "count", "flags"],
            "properties": {
                "id": _ID, "name": _NAME,
                "kind": {"enum": ["param", "var", "dev_out", "dev_in", "state", "status", "dev_state", "chart",
                                  "step_time", "fired"]},
                "type": {"enum": _TYPES},
                "count": {"type": "integer", "minimum": 1, "maximum": 65535},
                "flags": {"type": "array", "items": {"enum": ["read", "write", "range"]}},
                "unit": {"type": ["string", "null"], "maxLength": 1000},
                "range": _RANGE,
                "location": _TEXT,
                "chart": _ID, "step": _ID,
                "scale": _SCALE,
            },
            # a chart's state names its chart (and a step's time its step)
            "allOf": [{"if": {"properties": {"kind": {"enum": ["chart", "fired"]}}, "required": ["kind"]},
                       "then": {"required": ["chart"]}},
                      {"if": {"properties": {"kind": {"const": "step_time"}}, "required": ["kind"]},
                       "then": {"required": ["chart", "step"]}}],
        }},
        "charts": {"type": "array", "items": {
            "type": "object",
            "required": ["id", "name", "steps", "transitions"],
            "properties": {
                "id": _ID, "name": _NAME,
                "steps": {"type": "array", "items": {"type": "object", "required": ["id", "name"],
                                                     "properties": {"id": _ID, "name": _NAME}}},
                "transitions": {"type": "array", "items": {"type": "object", "required": ["id", "name"],
                                                           "properties": {"id": _ID, "name": _NAME}}},
            },
        }},
        "actors": {"type": "array", "items": {"type": "object", "required": ["id", "name"],
                                              "properties": {"id": _ID, "name": _NAME}}},
        "tasks": {"type": "array", "items": {"type": "object", "required": ["id", "name"],
                                             "properties": {"id": _ID, "name": _NAME}}},
    },
}

SERVICE_MAP_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "EasyLab service map (service_map.json)",
    "type": "object",
    "required": ["format", "items"],
    "properties": {
        "format": {"const": 1},
        "model": _TEXT,
        "title": {"type": ["string", "null"], "maxLength": 10000},
        "program_id": _TEXT,
        "interfaces": {
            "type": "object",
            "properties": {
                "tcp": {"type": "object", "properties": {"port": {"type": "integer", "minimum": 0,
                                                                  "maximum": 65535},
                                                         "unit": {"type": "integer", "minimum": 0,
                                                                  "maximum": 255}}},
                "rtu": {"type": "object", "properties": {"baud": {"type": "integer", "minimum": 1,
                                                                  "maximum": 100_000_000},
                                                         "parity": {"enum": ["none", "even", "odd"]},
                                                         "unit": {"type": "integer", "minimum": 0,
                                                                  "maximum": 255}}},
            },
        },
        "items": {"type": "array", "items": {
            "type": "object",
            "required": ["id", "name", "table", "address", "registers", "type", "access"],
            "properties": {
                "id": _ID, "name": _NAME,
                "kind": {"type": "string", "maxLength": 100},
                "table": {"enum": ["coil", "discrete", "holding", "input"]},
                "address": {"type": "integer", "minimum": 0, "maximum": 65535},
                "registers": {"enum": [1, 2]},
                "type": {"enum": _TYPES},
                "unit": {"type": ["string", "null"], "maxLength": 1000},
                "range": _RANGE,
                "access": {"enum": ["ro", "rw"]},
                "persist": {"type": "boolean"},
                "scale": _SCALE,
            },
            # A 32-bit value's second register is an address too.
            "if": {"properties": {"registers": {"const": 2}}, "required": ["registers"]},
            "then": {"properties": {"address": {"maximum": 65534}}},
        }},
    },
}

_VALIDATORS = {id(schema): jsonschema.Draft202012Validator(schema)
               for schema in (DEBUG_MAP_SCHEMA, SERVICE_MAP_SCHEMA)}


class MapFileError(Exception):
    """A map file that cannot be used; the message is one line."""


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def _short(text: str, limit: int = 120) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def read_map(path: str | Path, schema: dict, what: str, missing: str = "no such file") -> dict:
    """The map at ``path`` as JSON, valid against ``schema``; otherwise
    :class:`MapFileError` saying in one line what is wrong (``what`` names
    the kind of map, ``missing`` is the message for a file not there)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MapFileError(f"{path}: {missing}") from None
    except UnicodeDecodeError:
        raise MapFileError(f"{path}: not a {what}: not UTF-8 text") from None
    except OSError as err:
        raise MapFileError(f"{path}: cannot read: {err.strerror or err}") from None
    try:
        data = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as err:
        raise MapFileError(f"{path}: not a {what}: not JSON ({err.msg}, line {err.lineno})") from None
    except RecursionError:
        raise MapFileError(f"{path}: not a {what}: JSON nested too deeply") from None
    except ValueError as err:  # an integer of too many digits, NaN, Infinity
        raise MapFileError(f"{path}: not a {what}: {_short(str(err))}") from None
    try:
        error = jsonschema.exceptions.best_match(_VALIDATORS[id(schema)].iter_errors(data))
        message = error and error.message
    except RecursionError:  # a message quoting a value nested a thousand deep
        raise MapFileError(f"{path}: not a {what}: JSON nested too deeply") from None
    if error is not None:
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in error.absolute_path) or "the top"
        raise MapFileError(f"{path}: not a {what}: at {where.lstrip('.')}: {_short(message)}")
    return data
