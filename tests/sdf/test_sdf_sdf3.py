"""SDF3 import: well-formed documents, and every malformed one as Sdf3Error."""

from pathlib import Path

import pytest

from easylab.analysis.sdf import Sdf3Error, analyze, load_sdf3

DATA = Path(__file__).parent / "data"


def document(actors: str, channels: str, root: str = '<sdf3 type="sdf" version="1.0">') -> str:
    return f"""<?xml version="1.0"?>
{root}
  <applicationGraph name="g">
    <sdf name="g" type="G">
{actors}
{channels}
    </sdf>
  </applicationGraph>
</sdf3>
"""


TWO_ACTORS = """
      <actor name="a" type="A"><port name="o" type="out" rate="2"/><port name="s" type="out" rate="1"/>
        <port name="t" type="in" rate="1"/></actor>
      <actor name="b" type="B"><port name="i" type="in" rate="3"/></actor>"""
CHANNEL = '<channel name="c" srcActor="a" srcPort="o" dstActor="b" dstPort="i" initialTokens="0"/>'


def test_minimal_document_and_self_loop_channel():
    text = document(TWO_ACTORS, CHANNEL + '\n<channel name="state" srcActor="a" srcPort="s" dstActor="a" dstPort="t" initialTokens="1"/>')
    graph = load_sdf3(text)
    assert graph.actors == ("a", "b")
    edge, loop = graph.edges
    assert (edge.src, edge.dst, edge.prod, edge.cons, edge.delay) == ("a", "b", 2, 3, 0)
    assert loop.is_self_loop and loop.delay == 1
    assert edge.loc.line == 9 and edge.loc.source == "<sdf3 text>"
    analysis = analyze(graph)
    # The self-loop is reported apart and stays out of the totals.
    assert analysis.buffer_total == 6
    assert [(e, size) for e, size in analysis.self_loops] == [(loop, 1)]
    data = analysis.to_json_dict("g")
    assert data["self_loops"] == [{"src": "a", "dst": "a", "size": 1}]
    assert data["buffer_total"] == 6
    assert "self-loop" in analysis.render_text("g")


def test_bytes_and_path_inputs(tmp_path):
    text = document(TWO_ACTORS, CHANNEL)
    path = tmp_path / "g.xml"
    path.write_text(text)
    for source in (text.encode(), str(path), path):
        assert [e.prod for e in load_sdf3(source).edges] == [2]


BAD_DOCUMENTS = {
    "not well-formed": document(TWO_ACTORS, CHANNEL).replace("</sdf>", ""),
    "DOCTYPE": '<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;">]>'
               '<sdf3 type="sdf"><applicationGraph><sdf>&lol2;</sdf></applicationGraph></sdf3>',
    "DOCTYPE declarations": '<!DOCTYPE sdf3 SYSTEM "http://example.com/evil.dtd"><sdf3 type="sdf"/>',
    "expected <sdf3>": '<graph type="sdf"/>',
    "type 'csdf' are not supported": document(TWO_ACTORS, CHANNEL, '<sdf3 type="csdf">'),
    "needs a 'type' attribute": document(TWO_ACTORS, CHANNEL, "<sdf3>"),
    "no <applicationGraph>": '<sdf3 type="sdf"></sdf3>',
    "no <sdf>": '<sdf3 type="sdf"><applicationGraph name="x"/></sdf3>',
    "<actor> needs a 'name'": document('<actor type="A"/>', ""),
    "duplicate actor 'a'": document(TWO_ACTORS + '<actor name="a"/>', ""),
    "two ports named 'o'": document('<actor name="a"><port name="o" type="out" rate="1"/><port name="o" type="out" rate="1"/></actor>', ""),
    "expected 'in' or 'out'": document('<actor name="a"><port name="o" type="inout" rate="1"/></actor>', ""),
    "rate='0' of <port> must be a positive integer": document('<actor name="a"><port name="o" type="out" rate="0"/></actor>', ""),
    "rate='-2'": document('<actor name="a"><port name="o" type="out" rate="-2"/></actor>', ""),
    "rate='1.5'": document('<actor name="a"><port name="o" type="out" rate="1.5"/></actor>', ""),
    "cyclo-static rate lists are not supported": document('<actor name="a"><port name="o" type="out" rate="1,2"/></actor>', ""),
    "<port> needs a 'rate'": document('<actor name="a"><port name="o" type="out"/></actor>', ""),
    "unknown actor 'z'": document(TWO_ACTORS, CHANNEL.replace('dstActor="b"', 'dstActor="z"')),
    "has no port 'x'": document(TWO_ACTORS, CHANNEL.replace('srcPort="o"', 'srcPort="x"')),
    "is an 'in' port": document(TWO_ACTORS, CHANNEL.replace('srcPort="o"', 'srcPort="t"')),
    "needs a 'dstPort'": document(TWO_ACTORS, CHANNEL.replace('dstPort="i"', "")),
    "already connected": document(TWO_ACTORS, CHANNEL + CHANNEL.replace('srcPort="o"', 'srcPort="s"')),
    "initialTokens='-1'": document(TWO_ACTORS, CHANNEL.replace('initialTokens="0"', 'initialTokens="-1"')),
    "initialTokens='many'": document(TWO_ACTORS, CHANNEL.replace('initialTokens="0"', 'initialTokens="many"')),
}


@pytest.mark.parametrize("problem", sorted(BAD_DOCUMENTS))
def test_malformed_documents_raise_sdf3_error(problem):
    with pytest.raises(Sdf3Error) as caught:
        load_sdf3(BAD_DOCUMENTS[problem])
    assert problem in str(caught.value)
    assert caught.value.__cause__ is None or isinstance(caught.value.__cause__, Sdf3Error)


def test_external_entity_is_refused():
    text = '<?xml version="1.0"?><sdf3 type="sdf">&ext;</sdf3>'
    with pytest.raises(Sdf3Error):
        load_sdf3(text)


def test_size_limit_and_unreadable_files(tmp_path):
    with pytest.raises(Sdf3Error, match="more than the limit of 100"):
        load_sdf3(document(TWO_ACTORS, CHANNEL), max_bytes=100)
    path = tmp_path / "big.xml"
    path.write_text(document(TWO_ACTORS, CHANNEL))
    with pytest.raises(Sdf3Error, match="more than the limit"):
        load_sdf3(path, max_bytes=100)
    with pytest.raises(Sdf3Error, match="cannot read"):
        load_sdf3(tmp_path / "missing.xml")
    with pytest.raises(Sdf3Error, match="cannot read"):
        load_sdf3(tmp_path)
    with pytest.raises(Sdf3Error, match="expected a path or XML text"):
        load_sdf3(42)


def test_error_messages_carry_line_numbers():
    with pytest.raises(Sdf3Error, match=r"<sdf3 text>:9: channel refers to unknown actor 'z'"):
        load_sdf3(BAD_DOCUMENTS["unknown actor 'z'"])
