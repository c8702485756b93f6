"""Import of SDF3 application graphs (Stuijk, Geilen & Basten 2006).

Reads ``<sdf3 type="sdf">`` documents: ``applicationGraph/sdf`` holds
``actor`` elements with ``port`` children (``name``, ``type`` in/out,
``rate``) and ``channel`` elements (``srcActor``, ``srcPort``, ``dstActor``,
``dstPort``, optional ``initialTokens``).  Everything else (``sdfProperties``,
``csdf`` graphs' extras) is ignored; cyclo-static rates are refused.

The XML is parsed with expat directly and defensively: any DOCTYPE (and so
any entity declaration) is refused, external entities are never fetched, and
documents above a size limit are refused before parsing.  Every problem
surfaces as :class:`Sdf3Error` with the line it was found at.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Union
from xml.parsers import expat

from .errors import GraphError, Sdf3Error
from .graph import SdfGraph

MAX_SDF3_BYTES = 16 * 1024 * 1024
_INTEGER = re.compile(r"\s*([0-9]{1,18})\s*")


@dataclass(frozen=True)
class XmlLocation:
    """Where an SDF3 channel was declared; the ``loc`` of imported edges."""

    source: str
    line: int

    def __str__(self) -> str:
        return f"{self.source}:{self.line}"


class _Element:
    __slots__ = ("tag", "attributes", "line", "children")

    def __init__(self, tag: str, attributes: dict[str, str], line: int) -> None:
        # Namespace prefixes carry no meaning for SDF3 element names.
        self.tag = tag.rpartition(":")[2]
        self.attributes = attributes
        self.line = line
        self.children: list[_Element] = []

    def find_all(self, tag: str) -> list["_Element"]:
        return [child for child in self.children if child.tag == tag]


def load_sdf3(path_or_text: Union[str, bytes, os.PathLike], max_bytes: int = MAX_SDF3_BYTES) -> SdfGraph:
    """Read an SDF3 ``type="sdf"`` application graph into an :class:`SdfGraph`.

    ``path_or_text`` is a path (``str`` or path object) or the XML document
    itself (``bytes``, or a ``str`` starting with ``<``).  Edges get the
    channel name as label and an :class:`XmlLocation` as ``loc``.  Raises
    Sdf3Error for anything malformed or unsupported.
    """
    source, data = _read(path_or_text, max_bytes)
    root = _parse(source, data)
    return _build_graph(source, root)


def _read(path_or_text: Union[str, bytes, os.PathLike], max_bytes: int) -> tuple[str, Union[str, bytes]]:
    if isinstance(path_or_text, bytes):
        source, data = "<sdf3 text>", path_or_text
    elif isinstance(path_or_text, str) and path_or_text.lstrip().startswith("<"):
        source, data = "<sdf3 text>", path_or_text
    elif isinstance(path_or_text, (str, os.PathLike)):
        path = Path(path_or_text)
        source = str(path)
        try:
            size = path.stat().st_size
            if size > max_bytes:
                raise Sdf3Error(f"{source}: {size} bytes, more than the limit of {max_bytes}")
            data = path.read_bytes()
        except OSError as error:
            raise Sdf3Error(f"cannot read {source}: {error.strerror or error}") from None
    else:
        raise Sdf3Error(f"expected a path or XML text, not {type(path_or_text).__name__}")
    if len(data) > max_bytes:
        raise Sdf3Error(f"{source}: {len(data)} bytes, more than the limit of {max_bytes}")
    return source, data


def _parse(source: str, data: Union[str, bytes]) -> _Element:
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: list[_Element] = []
    roots: list[_Element] = []

    def refuse(what: str):
        def handler(*_args) -> None:
            raise Sdf3Error(
                f"{source}:{parser.CurrentLineNumber}: {what} are not accepted in SDF3 files"
            )
        return handler

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = _Element(tag, attributes, parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def end(_tag: str) -> None:
        stack.pop()

    parser.StartDoctypeDeclHandler = refuse("DOCTYPE declarations")
    parser.EntityDeclHandler = refuse("entity declarations")
    parser.ExternalEntityRefHandler = refuse("external entities")
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as error:
        raise Sdf3Error(
            f"{source}:{error.lineno}:{error.offset + 1}: not well-formed XML: "
            f"{expat.ErrorString(error.code)}"
        ) from None
    return roots[0]


def _attribute(source: str, element: _Element, name: str) -> str:
    value = element.attributes.get(name)
    if value is None or not value.strip():
        raise Sdf3Error(f"{source}:{element.line}: <{element.tag}> needs a {name!r} attribute")
    return value.strip()


def _integer(source: str, element: _Element, name: str, minimum: int, default: int | None = None) -> int:
    if default is not None and name not in element.attributes:
        return default
    text = _attribute(source, element, name)
    match = _INTEGER.fullmatch(text)
    if not match or int(match.group(1)) < minimum:
        kind = "a positive integer" if minimum > 0 else "a non-negative integer"
        extra = " (cyclo-static rate lists are not supported)" if "," in text else ""
        raise Sdf3Error(
            f"{source}:{element.line}: {name}={text!r} of <{element.tag}> must be {kind}{extra}"
        )
    return int(match.group(1))


def _single_child(source: str, parent: _Element, tag: str) -> _Element:
    found = parent.find_all(tag)
    if not found:
        raise Sdf3Error(f"{source}:{parent.line}: <{parent.tag}> has no <{tag}> element")
    if len(found) > 1:
        raise Sdf3Error(f"{source}:{found[1].line}: <{parent.tag}> has more than one <{tag}>")
    return found[0]


def _build_graph(source: str, root: _Element) -> SdfGraph:
    if root.tag != "sdf3":
        raise Sdf3Error(f"{source}:{root.line}: root element is <{root.tag}>, expected <sdf3>")
    kind = _attribute(source, root, "type")
    if kind != "sdf":
        raise Sdf3Error(f"{source}:{root.line}: SDF3 graphs of type {kind!r} are not supported, only 'sdf'")
    application = _single_child(source, root, "applicationGraph")
    sdf = _single_child(source, application, "sdf")
    graph = SdfGraph(name=sdf.attributes.get("name") or application.attributes.get("name"))

    # ports[actor][port] = (direction, rate, element line)
    ports: dict[str, dict[str, tuple[str, int]]] = {}
    for actor in sdf.find_all("actor"):
        name = _attribute(source, actor, "name")
        if name in ports:
            raise Sdf3Error(f"{source}:{actor.line}: duplicate actor {name!r}")
        ports[name] = {}
        for port in actor.find_all("port"):
            port_name = _attribute(source, port, "name")
            if port_name in ports[name]:
                raise Sdf3Error(f"{source}:{port.line}: actor {name!r} has two ports named {port_name!r}")
            direction = _attribute(source, port, "type")
            if direction not in ("in", "out"):
                raise Sdf3Error(
                    f"{source}:{port.line}: port {name}.{port_name} has type {direction!r}, "
                    "expected 'in' or 'out'"
                )
            ports[name][port_name] = (direction, _integer(source, port, "rate", 1))
        graph.add_actor(name)

    connected: dict[tuple[str, str], int] = {}
    for channel in sdf.find_all("channel"):
        ends = []
        for role, direction in (("src", "out"), ("dst", "in")):
            actor = _attribute(source, channel, f"{role}Actor")
            port = _attribute(source, channel, f"{role}Port")
            if actor not in ports:
                raise Sdf3Error(f"{source}:{channel.line}: channel refers to unknown actor {actor!r}")
            if port not in ports[actor]:
                raise Sdf3Error(f"{source}:{channel.line}: actor {actor!r} has no port {port!r}")
            if ports[actor][port][0] != direction:
                raise Sdf3Error(
                    f"{source}:{channel.line}: {actor}.{port} is an {ports[actor][port][0]!r} port, "
                    f"but the channel uses it as its {role} ({direction!r}) end"
                )
            if (actor, port) in connected:
                raise Sdf3Error(
                    f"{source}:{channel.line}: port {actor}.{port} is already connected "
                    f"by the channel at line {connected[(actor, port)]}"
                )
            connected[(actor, port)] = channel.line
            ends.append((actor, port, ports[actor][port][1]))
        (src, src_port, prod), (dst, dst_port, cons) = ends
        delay = _integer(source, channel, "initialTokens", 0, default=0)
        channel_name = channel.attributes.get("name")
        if channel_name:
            label = f"{channel_name} ({src} -> {dst})"
        else:
            label = f"{src}.{src_port} -> {dst}.{dst_port}"
        try:
            graph.add_edge(src, dst, prod, cons, delay, name=label, loc=XmlLocation(source, channel.line))
        except GraphError as error:  # pragma: no cover - values were checked above
            raise Sdf3Error(f"{source}:{channel.line}: {error}") from None
    return graph
