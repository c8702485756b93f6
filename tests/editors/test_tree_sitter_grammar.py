"""The tree-sitter grammar (editors/tree-sitter-elab/, written by
tools/tree_sitter_grammar.py from elab.lark): its parser.c compiles
warning-free, loads in tree-sitter, and parses every .elab in the
repository, the back-to-back tests' random models and mutated examples
(hypothesis) exactly as the front end does: no ERROR node where the front
end reads the text, the same tree (one node per lark rule, the same
tokens), an ERROR where the front end finds a syntax error. The highlight
query compiles and colours keywords as keywords only where the grammar
has one."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import pytest
import tree_sitter
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tree_sitter_lang import (GRAMMAR_DIR, ROOT, compile_language, edit_between, first_error, lark_shape,
                              tree_sitter_shape)

sys.path[:0] = [str(ROOT / "tools"), str(ROOT / "tests" / "frontend"), str(ROOT / "tests" / "crosscheck")]
import tree_sitter_grammar  # noqa: E402
from modelgen import generate  # noqa: E402
from mutations import HypothesisChooser, mutate  # noqa: E402

ELAB_FILES = sorted(ROOT / p for p in subprocess.run(["git", "ls-files", "*.elab"], cwd=ROOT, capture_output=True,
                                                     text=True, check=True).stdout.split())
MUTATION_SEEDS = [*sorted((ROOT / "examples").glob("*.elab")), ROOT / "tests" / "frontend" / "models" /
                  "all_features.elab"]


@pytest.fixture(scope="module")
def language(tmp_path_factory) -> tree_sitter.Language:
    return compile_language(tmp_path_factory.mktemp("tree-sitter-elab"))


@pytest.fixture(scope="module")
def parser(language) -> tree_sitter.Parser:
    return tree_sitter.Parser(language)


def assert_parses_as_the_front_end(parser, text: str, where: str) -> bool:
    """tree-sitter's tree of ``text`` is the front end's, or both reject
    it; whether the front end read it."""
    source = text.encode("utf-8")
    tree = parser.parse(source)
    expected = lark_shape(text)
    if expected is None:
        assert tree.root_node.has_error, f"{where}: the front end finds a syntax error, tree-sitter none"
        return False
    error = first_error(tree.root_node)
    assert error is None, f"{where}: {error.type} node at {error.start_point}: {error.text[:80]!r}"
    assert tree_sitter_shape(tree.root_node, source) == expected, where
    return True


def test_the_committed_files_are_written_from_elab_lark():
    assert tree_sitter_grammar.main(["--check"]) == 0


@pytest.mark.parametrize("compiler, flags", [("clang", ["-std=c11"]), ("gcc", ["-std=c99", "-pedantic"])])
def test_parser_c_compiles_warning_free_with_other_compilers_and_standards(compiler, flags):
    proc = subprocess.run([compiler, *flags, "-Wall", "-Wextra", "-Werror", "-fsyntax-only", "-I",
                           str(GRAMMAR_DIR / "src"), str(GRAMMAR_DIR / "src" / "parser.c")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr


def test_the_language_is_abi_14_with_the_grammar_s_nodes(language):
    assert language.abi_version == 14
    kinds = {language.node_kind_for_id(i) for i in range(language.node_kind_count)}
    assert {"source_file", "model_decl", "dataflow", "chart", "step", "binary", "duration_lit", "comment",
            "c_code", "name", "model", "min-buffer", "->"} <= kinds
    # ?rules and lark's helpers are hidden, as lark inlines them
    hidden = {language.node_kind_for_id(i) for i in range(language.node_kind_count)
              if not language.node_kind_is_visible(i)}
    assert {"_expr", "_item", "_primary"} <= hidden and not hidden & {"model_decl", "binary", "name"}


@pytest.mark.parametrize("path", ELAB_FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_elab_in_the_repository_parses_as_the_front_end_parses_it(parser, path):
    assert assert_parses_as_the_front_end(parser, path.read_text(encoding="utf-8"), str(path))


def test_the_repository_has_elab_files_with_inline_c_and_comments():
    texts = [p.read_text(encoding="utf-8") for p in ELAB_FILES]
    assert len(texts) >= 40
    assert any("{{" in t for t in texts) and any("/*" in t for t in texts) and any("//" in t for t in texts)


@pytest.mark.parametrize("seed", range(25))
def test_random_models_parse_as_the_front_end_parses_them(parser, seed):
    model = generate(3100 + seed)
    assert assert_parses_as_the_front_end(parser, model.text, model.name)


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_mutated_examples_get_an_error_exactly_where_the_front_end_finds_one(parser, data):
    path = data.draw(st.sampled_from(MUTATION_SEEDS))
    text = mutate(path.read_text(encoding="utf-8"), HypothesisChooser(data.draw))
    assert_parses_as_the_front_end(parser, text, f"mutation of {path.name}")


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_an_edited_tree_reparses_as_a_fresh_parse(parser, data):
    """Editors reparse incrementally: the old tree, told of the edit, gives
    the tree a fresh parse gives (on texts with a syntax error, an error
    too: recovery may take another path)."""
    path = data.draw(st.sampled_from(MUTATION_SEEDS))
    before = path.read_text(encoding="utf-8")
    after = mutate(before, HypothesisChooser(data.draw))
    old, new = before.encode(), after.encode()
    for source, target in ((old, new), (new, old)):
        tree = parser.parse(source)
        edit_between(tree, source, target)
        incremental, fresh = parser.parse(target, tree), parser.parse(target)
        if fresh.root_node.has_error:
            assert incremental.root_node.has_error
        else:
            assert str(incremental.root_node) == str(fresh.root_node)


@pytest.mark.parametrize("text, accepted", [
    ("actor type A() { step {{ x = 1; }} }", True),
    ("actor type A() { step {{ if (a) { b(); } }} }", True),
    ("actor type A() { step {{ a } b { c }} }", True),        # the front end's balancing rule
    ("actor type A() { step {{ if (a) { b(); }} }", False),   # unbalanced
    ("actor type A() { step {{ x = 1; } }", False),          # closed by '}' alone
    ("// {{ not a block\nmodel m", True),
    ('model m "{{"', True),
    ("task t period 5 ms offset 1 ms { run f }", True),       # `offset` a keyword after a period
    ("dataflow f { step = Gain(k = 1) a.step -> step.x }", True),  # `step` a name where no keyword stands
    ("dataflow f { a -> b", False),
    ("param p: int16 = 1 +", False),
])
def test_inline_c_and_contextual_keywords(parser, text, accepted):
    assert assert_parses_as_the_front_end(parser, text, text) is accepted


def test_inline_c_nested_to_the_documented_depth(parser):
    depth = tree_sitter_grammar.C_CODE_DEPTH
    body = "{" * (depth - 2) + "x" + "}" * (depth - 2)
    assert assert_parses_as_the_front_end(parser, f"actor type A() {{ step {{{{ {body} }}}} }}", "nested")


def _captures(language, text: str) -> dict[tuple[int, int], set[str]]:
    query = tree_sitter.Query(language, (GRAMMAR_DIR / "queries" / "highlights.scm").read_text())
    tree = tree_sitter.Parser(language).parse(text.encode())
    found: dict[tuple[int, int], set[str]] = {}
    for capture, nodes in tree_sitter.QueryCursor(query).captures(tree.root_node).items():
        for node in nodes:
            found.setdefault(node.start_point, set()).add(capture)
    return found


def test_the_highlight_query_colours_keywords_comments_and_declared_names(language):
    text = ("// a comment\n"
            "model m \"x\"\n"
            "param step: int16 = 5 ms\n"
            "dataflow flow {\n"
            "    g = Gain(k = 1)\n"
            "    g.step -> step\n"
            "}\n"
            "task t period 10 ms { run flow }\n")
    captures = _captures(language, text)
    assert captures[(0, 0)] == {"comment"}
    assert captures[(1, 0)] == {"keyword"}
    assert captures[(1, 6)] == {"module"}
    assert captures[(1, 8)] == {"string"}
    assert captures[(2, 0)] == {"keyword"}
    assert captures[(2, 6)] == {"variable"}          # `step` declared as a param: a name, not a keyword
    assert captures[(2, 12)] == {"type"}
    assert captures[(2, 20)] == {"number"}
    assert captures[(2, 22)] == {"type.builtin"}     # the unit
    assert captures[(3, 9)] == {"function"}
    assert "keyword" not in captures.get((5, 6), set())   # `g.step`
    assert "keyword" not in captures.get((5, 14), set())  # `-> step`
    assert captures[(7, 7)] == {"keyword"}           # period
    assert captures[(7, 22)] == {"keyword"}          # run


def test_helix_s_queries_are_neovim_s_with_helix_s_capture_names(language):
    helix = (GRAMMAR_DIR / "queries" / "helix" / "highlights.scm").read_text()
    query = tree_sitter.Query(language, helix)
    names = {query.capture_name(i) for i in range(query.capture_count)}
    assert {"keyword", "comment", "string", "constant.numeric", "constant.builtin.boolean", "namespace"} <= names
    assert not names & {"number", "boolean", "module"}
    assert helix == tree_sitter_grammar.helix_captures((GRAMMAR_DIR / "queries" / "highlights.scm").read_text())
    tree_sitter.Query(language, (GRAMMAR_DIR / "queries" / "helix" / "injections.scm").read_text())


def test_every_keyword_of_the_grammar_is_in_the_highlight_query():
    grammar = tree_sitter_grammar.build_grammar()
    query = (GRAMMAR_DIR / "queries" / "highlights.scm").read_text()
    for word in grammar.keywords:
        assert json.dumps(word) in query, word
    assert '"min-buffer"' in query


def test_the_injection_query_marks_inline_c(language):
    query = tree_sitter.Query(language, (GRAMMAR_DIR / "queries" / "injections.scm").read_text())
    tree = tree_sitter.Parser(language).parse(b"actor type A() {\n  step {{ y = x; }}\n}\n")
    nodes = tree_sitter.QueryCursor(query).captures(tree.root_node)["injection.content"]
    assert [n.text for n in nodes] == [b"{{ y = x; }}"]


NODE_DSL = r"""
const fs = require("fs");
const rules = {}; const refs = new Set();
const $ = new Proxy({}, {get: (_, name) => { refs.add(name); return {ref: name}; }});
const node = (kind) => (...args) => ({kind, args});
Object.assign(global, {seq: node("seq"), choice: node("choice"), optional: node("optional"),
  repeat: node("repeat"), repeat1: node("repeat1"), token: node("token"), alias: node("alias"),
  prec: node("prec"), field: node("field")});
global.grammar = (g) => g;
const g = require(process.argv[1]);
for (const [name, body] of Object.entries(g.rules)) { rules[name] = true; body($); }
g.word($); g.extras($);
console.log(JSON.stringify({name: g.name, rules: Object.keys(rules), refs: [...refs]}));
"""


def test_grammar_js_is_valid_javascript_naming_only_its_own_rules():
    """grammar.js evaluated by Node with a stand-in for tree-sitter's DSL:
    every `$.rule` it names is one of its rules, the first is the root,
    and its named rules are the nodes parser.c makes."""
    node = shutil.which("node")
    assert node, "Node.js is needed (the Makefile installs it)"
    proc = subprocess.run([node, "-e", NODE_DSL, str(GRAMMAR_DIR / "grammar.js")], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert result["name"] == "elab"
    assert result["rules"][0] == "source_file"
    # an alias names the node of the hidden rule behind it (`binary`, `int_lit`)
    aliases = set(re.findall(r"alias\(\$\.\w+, \$\.(\w+)\)", (GRAMMAR_DIR / "grammar.js").read_text()))
    assert set(result["refs"]) - aliases <= set(result["rules"])
    grammar = tree_sitter_grammar.build_grammar()
    named = {s.name for s in grammar.symbols if s.visible and s.named}
    visible_rules = {r for r in result["rules"] if not r.startswith("_")}
    assert visible_rules | aliases == named
