#!/usr/bin/env python3
"""Writes editors/tree-sitter-elab/, the tree-sitter grammar of .elab files,
from the model language's own grammar (generator/frontend/elab.lark):

- ``grammar.js``: the grammar in tree-sitter's DSL, for the tree-sitter CLI
  (``tree-sitter generate`` makes an equivalent parser from it);
- ``src/parser.c``: the parser itself, in the C form the CLI writes (ABI
  14), made here without the CLI from lark's own LALR(1) tables and a DFA
  lexer built from the terminals' regular expressions;
- ``queries/highlights.scm``, ``package.json``, ``tree-sitter.json``.

    python tools/tree_sitter_grammar.py          # write the files
    python tools/tree_sitter_grammar.py --check  # exit 1 if one is out of date

How the tree follows lark's: one node per rule; a ``_rule``, a ``?rule``
with one child and lark's own helper rules (``__x_star_0``) are inlined; an
alias (``-> binary``) names its node. Keywords are contextual as in the
front end: the lexer reads a word as ``name`` and tree-sitter's keyword
extraction makes it the keyword only where the parse state has an action
for it (what lark's contextual lexer and ``keyword_as_name`` do). Inline C
(``{{ ... }}``) is one token that ends at the balancing ``}}``, up to
C_CODE_DEPTH nested braces (a regular language cannot count further).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections import deque
from dataclasses import dataclass
from pathlib import Path

from tree_sitter_lexer import MAX_CHAR, LexerBuilder, LexState, Nfa, add_regex, normalise

ROOT = Path(__file__).resolve().parents[1]
OUTPUT = ROOT / "editors" / "tree-sitter-elab"
VERSION = "0.1.0"

# Deepest brace nesting inside one inline C block that the tree-sitter lexer
# follows (the front end follows any depth).
C_CODE_DEPTH = 8
# The terminals lark skips between tokens: WS is skipped by the lexer, the
# comments are tree-sitter "extras" (nodes that may stand anywhere).
WHITESPACE = "WS"
COMMENTS = ("COMMENT", "BLOCK_COMMENT")
WORD_TERMINAL = "NAME"
END = "$END"
ROOT_RULE = "source_file"


def _word_re() -> re.Pattern:
    return re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _c_code_regex(depth: int = C_CODE_DEPTH) -> str:
    """``{{ ... }}`` up to the balancing ``}}``: the text between the outer
    braces is balanced, starts with ``{`` and ends with ``}``, as
    inline_c.blank_inline_c reads it (braces in C strings count too)."""
    balanced = "[^{}]*"
    for _ in range(depth - 2):
        balanced = rf"(?:[^{{}}]|\{{{balanced}\}})*"
    group = rf"\{{{balanced}\}}"
    return rf"\{{{group}(?:[^{{}}]*{group})*\}}"


# ---------------------------------------------------------------------------
# The grammar: lark's rules, reshaped so that every node tree-sitter makes is
# the one lark's tree builder makes.


@dataclass
class Symbol:
    """One tree-sitter symbol: a terminal or a nonterminal."""
    key: str            # lark's name, or a made-up one for a synthetic rule
    name: str           # the node's type as tree-sitter shows it
    terminal: bool
    visible: bool
    named: bool
    index: int = 0


@dataclass
class Grammar:
    symbols: list[Symbol]
    by_key: dict[str, Symbol]
    rules: list             # lark Rule objects over the reshaped symbols
    terminals: dict          # lark TerminalDef by name
    keywords: dict[str, str]  # word keyword's spelling -> its terminal
    lark: object


def _lark():
    import lark

    from easylab.frontend.grammar import grammar_text

    return lark.Lark(grammar_text(), parser="lalr", lexer="contextual", keep_all_tokens=True,
                     maybe_placeholders=False)


def _node_of(rule) -> str | None:
    """The node a lark rule makes when it reduces, or None where lark
    inlines it (docs/language.md's tree; lark's ChildFilter/ExpandSingleChild)."""
    if rule.alias:
        return rule.alias
    if rule.origin.name.startswith("_"):
        return None
    if rule.options.expand1 and len(rule.expansion) == 1:
        return None
    return rule.origin.name


def build_grammar() -> Grammar:
    """lark's rules and terminals as tree-sitter symbols (tokens first)."""
    from lark.grammar import NonTerminal, Rule, Terminal

    parser = _lark()
    terminals = {t.name: t for t in parser.terminals}
    word = _word_re()
    keywords = {t.pattern.value: t.name for t in parser.terminals
                if t.pattern.type == "str" and word.fullmatch(t.pattern.value)}

    by_origin: dict[str, list] = {}
    for rule in parser.rules:
        by_origin.setdefault(rule.origin.name, []).append(rule)
    # An origin is a node of its own only if every rule of it makes its node.
    plain = {o for o, rules in by_origin.items() if all(_node_of(r) == o for r in rules)}

    rules, synthetic = [], []
    for origin, origin_rules in by_origin.items():
        for number, rule in enumerate(origin_rules):
            node = _node_of(rule)
            if origin in plain or node is None:
                rules.append(Rule(rule.origin, rule.expansion, order=len(rules)))
                continue
            wrapper = NonTerminal(f"{origin}__{number}")
            synthetic.append((wrapper.name, node))
            rules.append(Rule(rule.origin, [wrapper], order=len(rules)))
            rules.append(Rule(wrapper, rule.expansion, order=len(rules)))

    used = {s.name for r in rules for s in r.expansion if isinstance(s, Terminal)}
    token_names = [n for n in terminals if n in used or n in COMMENTS]
    symbols = [Symbol(END, "end", True, False, True)]
    for name in token_names:
        pattern = terminals[name].pattern
        if pattern.type == "str":
            symbols.append(Symbol(name, pattern.value, True, True, False))
        else:
            display = "comment" if name in COMMENTS else name.lower()
            symbols.append(Symbol(name, display, True, True, True))
    for origin in by_origin:
        if origin in plain:
            display = ROOT_RULE if origin == "start" else origin
            symbols.append(Symbol(origin, display, False, True, True))
        else:
            hidden = origin if origin.startswith("_") else f"_{origin}"  # tree-sitter's mark of a hidden rule
            # Named, though hidden: the runtime rebalances hidden unnamed
            # nodes whose first child is of their own symbol as tree-sitter's
            # own `x -> x x` repeats, which lark's `x -> x item` are not.
            symbols.append(Symbol(origin, hidden, False, False, True))
    for key, node in synthetic:
        symbols.append(Symbol(key, node, False, True, True))
    for index, symbol in enumerate(symbols):
        symbol.index = index
    by_key = {s.key: s for s in symbols}
    clash = {s.name for s in symbols if s.named and s.visible and s.terminal} & \
            {s.name for s in symbols if s.visible and not s.terminal}
    assert not clash, f"a token and a rule would have the same node type: {clash}"
    return Grammar(symbols, by_key, rules, terminals, keywords, parser)


# ---------------------------------------------------------------------------
# The parse table: lark's LALR(1) analysis of the reshaped rules.


@dataclass
class Table:
    states: list[dict]       # tree-sitter state -> {symbol key: action}; state 0 is the error state


def build_table(grammar: Grammar) -> Table:
    """LALR(1) states numbered breadth-first from the start state (lark's
    own numbering follows set iteration order, which varies by run)."""
    from lark.common import ParserConf
    from lark.parsers.lalr_analysis import IntParseTable, LALR_Analyzer, Shift

    analyzer = LALR_Analyzer(ParserConf(grammar.rules, {}, ["start"]))
    analyzer.compute_lalr()
    table = IntParseTable.from_ParseTable(analyzer.parse_table)
    start, end = table.start_states["start"], table.end_states["start"]
    number = {start: 1}
    queue = deque([start])
    while queue:
        state = queue.popleft()
        for key in sorted(table.states[state]):
            kind, arg = table.states[state][key]
            if kind is Shift and arg not in number:
                number[arg] = len(number) + 1
                queue.append(arg)
    states: list[dict] = [dict() for _ in range(len(number) + 1)]
    for lark_state, ts_state in number.items():
        states[ts_state] = {key: (("shift", number[arg]) if kind is Shift else ("reduce", arg))
                            for key, (kind, arg) in table.states[lark_state].items()}
    states[number[end]][END] = ("accept", None)
    return Table(states)


# ---------------------------------------------------------------------------
# parser.c


def _c_identifier(symbol: Symbol) -> str:
    if symbol.key == END:
        return "ts_builtin_sym_end"
    prefix = "anon_sym" if symbol.terminal and not symbol.named else "sym" if symbol.visible else "aux_sym"
    return f"{prefix}_{re.sub(r'[^A-Za-z0-9_]', '_', symbol.key)}"


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _c_char(code: int) -> str:
    if 32 <= code < 127 and chr(code) not in "'\\":
        return f"'{chr(code)}'"
    return {39: "'\\''", 92: "'\\\\'", 9: "'\\t'", 10: "'\\n'", 13: "'\\r'"}.get(code, hex(code))


def _c_condition(ranges) -> str:
    parts = []
    for lo, hi in ranges:
        if lo == hi:
            parts.append(f"lookahead == {_c_char(lo)}")
        elif hi == MAX_CHAR:
            parts.append(f"lookahead >= {_c_char(lo)}")
        else:
            parts.append(f"({_c_char(lo)} <= lookahead && lookahead <= {_c_char(hi)})")
    return " ||\n          ".join(parts)


def _c_lex_function(name: str, states: list[LexState], ids: dict[str, str]) -> list[str]:
    lines = [f"static bool {name}(TSLexer *lexer, TSStateId state) {{", "  START_LEXER();",
             "  eof = lexer->eof(lexer);", "  switch (state) {"]
    for index, state in enumerate(states):
        lines.append(f"    case {index}:")
        if state.eof_to is not None:
            lines.append(f"      if (eof) ADVANCE({state.eof_to});")
        if state.accept is not None:
            lines.append(f"      ACCEPT_TOKEN({ids[state.accept]});")
        for ranges, target, skip in state.moves:
            lines.append(f"      if ({_c_condition(ranges)}) {'SKIP' if skip else 'ADVANCE'}({target});")
        lines.append("      END_STATE();")
    lines += ["    default:", "      return false;", "  }", "}", ""]
    return lines


def _lexers(grammar: Grammar, table: Table):
    """The main lexer (its states and each parse state's start state) and
    the keyword lexer."""
    word_keywords = set(grammar.keywords.values())
    tokens = [s for s in grammar.symbols if s.terminal and s.key != END]
    patterns = {}
    for s in tokens:
        if s.key in word_keywords:
            continue
        pattern = grammar.terminals[s.key].pattern
        if s.key == "C_CODE":
            patterns[s.key] = (_c_code_regex(), 0)
        else:
            patterns[s.key] = (pattern.to_regexp(), 0)
    # Ties go as lark's lexer sends them: higher priority, then a string
    # before a pattern, then the longer pattern.
    rank = {s.key: (-grammar.terminals[s.key].priority, grammar.terminals[s.key].pattern.type != "str",
                    -len(grammar.terminals[s.key].pattern.value), s.index) for s in tokens}
    skip = _ranges_of_whitespace(grammar)
    main = LexerBuilder(patterns, rank)
    end_state = main.add_accepting(END)
    modes: dict[frozenset, int] = {}
    lex_mode = []
    all_tokens = frozenset(patterns)
    for number, actions in enumerate(table.states):
        if number == 0:
            wanted = all_tokens
            has_end = True
        else:
            wanted = {k for k in actions if k in grammar.by_key and grammar.by_key[k].terminal and k != END}
            has_end = END in actions
            if wanted & word_keywords:
                wanted = (wanted - word_keywords) | {WORD_TERMINAL}
            wanted = frozenset(wanted | set(COMMENTS))
        key = (wanted, has_end)
        if key not in modes:
            modes[key] = main.add_mode(wanted, skip, end_state if has_end else None)
        lex_mode.append(modes[key])
    keyword_lexer = LexerBuilder({t: (re.escape(w), 0) for w, t in grammar.keywords.items()}, rank)
    keyword_lexer.add_mode(sorted(grammar.keywords.values()), [], None)
    return main.states, lex_mode, keyword_lexer.states


def _ranges_of_whitespace(grammar: Grammar) -> list[tuple[int, int]]:
    """The characters of the skipped terminal (a repeat of a character set)."""
    nfa = Nfa()
    add_regex(nfa, WHITESPACE, grammar.terminals[WHITESPACE].pattern.to_regexp())
    return normalise(r for edges in nfa.edges for ranges, _ in edges for r in ranges)


def render_parser_c(grammar: Grammar, table: Table) -> str:
    """src/parser.c in the layout the tree-sitter CLI writes for ABI 14."""
    ids = {s.key: _c_identifier(s) for s in grammar.symbols}
    symbols = grammar.symbols
    token_count = sum(1 for s in symbols if s.terminal)
    public = {}
    for s in symbols:
        public.setdefault((s.name, s.visible, s.named, s.terminal), s)
    lex_states, lex_mode, keyword_states = _lexers(grammar, table)

    # The actions: one list per distinct (state, token) action, shared.
    actions_index: dict[tuple, int] = {(): 0}
    actions_lines = ["  [0] = {.entry = {.count = 0, .reusable = false}},"]
    next_index = 1

    def action_id(items: tuple[str, ...]) -> int:
        nonlocal next_index
        if items not in actions_index:
            actions_index[items] = next_index
            actions_lines.append(f"  [{next_index}] = {{.entry = {{.count = {len(items)}, .reusable = false}}}}, "
                                 + ", ".join(items) + ",")
            next_index += 1 + len(items)
        return actions_index[items]

    recover = action_id(("RECOVER()",))
    extra = action_id(("SHIFT_EXTRA()",))
    rows: list[dict[int, int]] = []
    for number, actions in enumerate(table.states):
        row: dict[int, int] = {}
        if number == 0:
            for s in symbols:
                if s.terminal:
                    row[s.index] = recover
        for key, (kind, arg) in sorted(actions.items(), key=lambda kv: grammar.by_key[kv[0]].index):
            symbol = grammar.by_key[key]
            if not symbol.terminal:
                row[symbol.index] = arg  # a goto
            elif kind == "shift":
                row[symbol.index] = action_id((f"SHIFT({arg})",))
            elif kind == "reduce":
                origin = grammar.by_key[arg.origin.name]
                row[symbol.index] = action_id((f"REDUCE({ids[origin.key]}, {len(arg.expansion)}, 0, 0)",))
            else:
                row[symbol.index] = action_id(("ACCEPT_INPUT()",))
        for key in COMMENTS:
            row[grammar.by_key[key].index] = extra
        rows.append(row)

    large = 2
    max_length = max((len(r.expansion) for r in grammar.rules), default=1)
    out = [
        "// Written by tools/tree_sitter_grammar.py from generator/frontend/elab.lark: edit that, not this.",
        '#include "tree_sitter/parser.h"', "",
        "#if defined(__GNUC__) || defined(__clang__)",
        '#pragma GCC diagnostic ignored "-Wmissing-field-initializers"',
        "#endif", "",
        "#define LANGUAGE_VERSION 14",
        f"#define STATE_COUNT {len(table.states)}",
        f"#define LARGE_STATE_COUNT {large}",
        f"#define SYMBOL_COUNT {len(symbols)}",
        "#define ALIAS_COUNT 0",
        f"#define TOKEN_COUNT {token_count}",
        "#define EXTERNAL_TOKEN_COUNT 0",
        "#define FIELD_COUNT 0",
        f"#define MAX_ALIAS_SEQUENCE_LENGTH {max_length}",
        "#define PRODUCTION_ID_COUNT 1", "",
        "enum ts_symbol_identifiers {",
    ]
    out += [f"  {ids[s.key]} = {s.index}," for s in symbols[1:]]
    out += ["};", "", "static const char * const ts_symbol_names[] = {"]
    out += [f"  [{ids[s.key]}] = {_c_string(s.name)}," for s in symbols]
    out += ["};", "", "static const TSSymbol ts_symbol_map[] = {"]
    out += [f"  [{ids[s.key]}] = {ids[public[(s.name, s.visible, s.named, s.terminal)].key]}," for s in symbols]
    out += ["};", "", "static const TSSymbolMetadata ts_symbol_metadata[] = {"]
    for s in symbols:
        out += [f"  [{ids[s.key]}] = {{", f"    .visible = {str(s.visible).lower()},",
                f"    .named = {str(s.named).lower()},", "  },"]
    out += ["};", "",
            "static const char * const ts_field_names[] = {", "  [0] = NULL,", "};", "",
            "static const TSFieldMapSlice ts_field_map_slices[PRODUCTION_ID_COUNT] = {", "  [0] = {0},", "};", "",
            "static const TSFieldMapEntry ts_field_map_entries[] = {", "  [0] = {0},", "};", "",
            "static const TSSymbol ts_alias_sequences[PRODUCTION_ID_COUNT][MAX_ALIAS_SEQUENCE_LENGTH] = {",
            "  [0] = {0},", "};", "",
            "static const uint16_t ts_non_terminal_alias_map[] = {", "  0,", "};", "",
            "static const TSStateId ts_primary_state_ids[STATE_COUNT] = {"]
    out += [f"  [{n}] = {n}," for n in range(len(table.states))]
    out += ["};", ""]
    out += _c_lex_function("ts_lex", lex_states, ids)
    out += _c_lex_function("ts_lex_keywords", keyword_states, ids)
    out += ["static const TSLexMode ts_lex_modes[STATE_COUNT] = {"]
    out += [f"  [{n}] = {{.lex_state = {m}}}," for n, m in enumerate(lex_mode)]
    out += ["};", "", "static const uint16_t ts_parse_table[LARGE_STATE_COUNT][SYMBOL_COUNT] = {"]
    for n in range(large):
        out.append(f"  [{n}] = {{")
        for index, value in sorted(rows[n].items()):
            macro = "ACTIONS" if symbols[index].terminal else "STATE"
            out.append(f"    [{ids[symbols[index].key]}] = {macro}({value}),")
        out.append("  },")
    out += ["};", "", "static const uint16_t ts_small_parse_table[] = {"]
    offsets, offset = [], 0
    for n in range(large, len(rows)):
        groups: dict[tuple[bool, int], list[int]] = {}
        for index, value in sorted(rows[n].items()):
            groups.setdefault((symbols[index].terminal, value), []).append(index)
        offsets.append(offset)
        out.append(f"  [{offset}] = {len(groups)},")
        offset += 1
        for (terminal, value), members in sorted(groups.items(), key=lambda g: (len(g[1]), g[0])):
            out.append(f"    {'ACTIONS' if terminal else 'STATE'}({value}), {len(members)},")
            out += [f"      {ids[symbols[i].key]}," for i in members]
            offset += 2 + len(members)
    out += ["};", "", "static const uint32_t ts_small_parse_table_map[] = {"]
    out += [f"  [SMALL_STATE({n + large})] = {o}," for n, o in enumerate(offsets)]
    out += ["};", "", "static const TSParseActionEntry ts_parse_actions[] = {"]
    out += actions_lines
    out += ["};", "",
            "#ifdef __cplusplus", 'extern "C" {', "#endif",
            "#ifdef TREE_SITTER_HIDE_SYMBOLS", "#define TS_PUBLIC",
            "#elif defined(_WIN32)", "#define TS_PUBLIC __declspec(dllexport)",
            "#else", '#define TS_PUBLIC __attribute__((visibility("default")))', "#endif", "",
            "TS_PUBLIC const TSLanguage *tree_sitter_elab(void) {",
            "  static const TSLanguage language = {",
            "    .version = LANGUAGE_VERSION,",
            "    .symbol_count = SYMBOL_COUNT,",
            "    .alias_count = ALIAS_COUNT,",
            "    .token_count = TOKEN_COUNT,",
            "    .external_token_count = EXTERNAL_TOKEN_COUNT,",
            "    .state_count = STATE_COUNT,",
            "    .large_state_count = LARGE_STATE_COUNT,",
            "    .production_id_count = PRODUCTION_ID_COUNT,",
            "    .field_count = FIELD_COUNT,",
            "    .max_alias_sequence_length = MAX_ALIAS_SEQUENCE_LENGTH,",
            "    .parse_table = &ts_parse_table[0][0],",
            "    .small_parse_table = ts_small_parse_table,",
            "    .small_parse_table_map = ts_small_parse_table_map,",
            "    .parse_actions = ts_parse_actions,",
            "    .symbol_names = ts_symbol_names,",
            "    .field_names = ts_field_names,",
            "    .field_map_slices = ts_field_map_slices,",
            "    .field_map_entries = ts_field_map_entries,",
            "    .symbol_metadata = ts_symbol_metadata,",
            "    .public_symbol_map = ts_symbol_map,",
            "    .alias_map = ts_non_terminal_alias_map,",
            "    .alias_sequences = &ts_alias_sequences[0][0],",
            "    .lex_modes = ts_lex_modes,",
            "    .lex_fn = ts_lex,",
            "    .keyword_lex_fn = ts_lex_keywords,",
            f"    .keyword_capture_token = {ids[WORD_TERMINAL]},",
            "    .primary_state_ids = ts_primary_state_ids,",
            "  };",
            "  return &language;",
            "}",
            "#ifdef __cplusplus", "}", "#endif", ""]
    return "\n".join(out)


# ---------------------------------------------------------------------------
# grammar.js, the queries and the package files


def _js_regex(pattern: str) -> str:
    """A JavaScript regular expression literal; lark's patterns hold their
    control characters as themselves."""
    escapes = {"/": "\\/", "\n": "\\n", "\t": "\\t", "\r": "\\r", "\f": "\\f"}
    return "/" + "".join(escapes.get(c, c) for c in pattern) + "/"


def _js_rule_name(grammar: Grammar, key: str) -> str:
    symbol = grammar.by_key[key]
    if key == "start":
        return ROOT_RULE
    if symbol.visible:
        return key
    return key if key.startswith("_") else f"_{key}"


def _js_symbol(grammar: Grammar, sym) -> str:
    symbol = grammar.by_key[sym.name]
    if symbol.terminal:
        return json.dumps(symbol.name) if not symbol.named else f"$.{symbol.name}"
    return f"$.{_js_rule_name(grammar, sym.name)}"


def render_grammar_js(grammar: Grammar) -> str:
    """grammar.js: the same rules, tokens and node names as parser.c."""
    by_origin: dict[str, list] = {}
    for rule in grammar.rules:
        by_origin.setdefault(rule.origin.name, []).append(rule)
    synthetic = {key for key in by_origin if grammar.by_key[key].visible
                 and grammar.by_key[key].name != key and key != "start"}
    lines = [
        "// The tree-sitter grammar of EasyLab models (.elab).",
        "// Written by tools/tree_sitter_grammar.py from generator/frontend/elab.lark: edit that, not this.",
        "// `tree-sitter generate` makes from it a parser equivalent to src/parser.c.",
        "",
        "module.exports = grammar({",
        "  name: 'elab',",
        "  word: $ => $.name,",
        "  extras: $ => [/[ \\t\\f\\r\\n]/, $.comment],",
        "  rules: {",
    ]

    def body(origin: str) -> str:
        alternatives = []
        optional = False
        for rule in by_origin[origin]:
            if not rule.expansion:
                optional = True
                continue
            if len(rule.expansion) == 1 and rule.expansion[0].name in synthetic:
                wrapper = rule.expansion[0].name
                alternatives.append(f"alias($._{wrapper}, $.{grammar.by_key[wrapper].name})")
                continue
            parts = [_js_symbol(grammar, s) for s in rule.expansion]
            alternatives.append(parts[0] if len(parts) == 1 else f"seq({', '.join(parts)})")
        text = alternatives[0] if len(alternatives) == 1 else \
            "choice(\n      " + ",\n      ".join(alternatives) + ",\n    )"
        return f"optional({text})" if optional else text

    ordered = ["start"] + [o for o in by_origin if o != "start"]
    for origin in ordered:
        name = f"_{origin}" if origin in synthetic else _js_rule_name(grammar, origin)
        lines.append(f"    {name}: $ => {body(origin)},")
    lines.append("")
    for symbol in grammar.symbols:
        if not symbol.terminal or not symbol.named or symbol.key in (END, COMMENTS[1]):
            continue
        if symbol.key == COMMENTS[0]:
            lines.append("    comment: $ => token(choice(/\\/\\/[^\\n]*/,"
                         " seq('/*', /[^*]*\\*+([^/*][^*]*\\*+)*/, '/'))),")
        elif symbol.key == "C_CODE":
            lines.append(f"    // Inline C: up to the balancing '}}}}', at most {C_CODE_DEPTH} braces deep.")
            lines.append(f"    {symbol.name}: $ => {_js_regex(_c_code_regex())},")
        else:
            pattern = grammar.terminals[symbol.key].pattern.value
            lines.append(f"    {symbol.name}: $ => token({_js_regex(pattern)}),")
    lines += ["  },", "});", ""]
    return "\n".join(lines)


# How the highlight query names what it colours (nvim-treesitter's and
# Helix's capture names).
UNIT_TERMINALS = ("US", "MS", "SEC")
LOGICAL_TERMINALS = ("AND", "OR", "NOT")
BOOLEAN_TERMINALS = ("TRUE", "FALSE")
DECLARED_NAMES = [
    ("model_decl", "module"), ("import_decl", "module"), ("const_decl", "constant"),
    ("param_decl", "variable"), ("var_decl", "variable"), ("channel_decl", "variable"),
    ("device_type", "type"), ("actor_type", "type"), ("type_ref", "type"), ("type_param", "type"),
    ("dataflow", "function"), ("chart", "function"), ("task", "function"), ("run_action", "function"),
    ("step", "label"), ("step_set", "label"), ("state_var", "variable"), ("actor_port", "property"),
    ("data_port", "property"), ("data_export", "property"), ("formal_param", "variable.parameter"),
    ("actual", "variable.parameter"), ("node_decl", "module"), ("link_decl", "module"),
]


def render_highlights(grammar: Grammar) -> str:
    """queries/highlights.scm: keywords, types, numbers, strings, comments,
    operators and the names declarations introduce."""
    # Every word of the grammar is a keyword, `min-buffer` too (as in
    # tools/textmate_grammar.py).
    words = {s.key: s.name for s in grammar.symbols
             if s.terminal and not s.named and re.fullmatch(r"[a-z][a-z-]*", s.name)}
    keywords = sorted(w for t, w in words.items()
                      if t not in UNIT_TERMINALS + LOGICAL_TERMINALS + BOOLEAN_TERMINALS)
    operators = sorted(s.name for s in grammar.symbols if s.terminal and not s.named and s.key != END
                       and s.key not in words and s.name not in "()[]{},.:@")
    quoted = lambda names: " ".join(json.dumps(n) for n in names)  # noqa: E731
    declared = [rule for rule, _ in DECLARED_NAMES if rule in {s.name for s in grammar.symbols}]
    assert len(declared) == len(DECLARED_NAMES), "a rule of DECLARED_NAMES left the grammar"
    lines = [
        "; Written by tools/tree_sitter_grammar.py from generator/frontend/elab.lark: edit that, not this.",
        "",
        "(comment) @comment",
        "(string) @string",
        "[(int) (real)] @number",
        "(c_code) @embedded",
        "(persist_attr) @keyword",
        "",
        f"[{quoted(keywords)}] @keyword",
        f"[{quoted(words[t] for t in LOGICAL_TERMINALS)}] @keyword.operator",
        f"[{quoted(words[t] for t in BOOLEAN_TERMINALS)}] @boolean",
        f"(duration_lit [{quoted(words[t] for t in UNIT_TERMINALS)}] @type.builtin)",
        "",
        f"[{quoted(operators)}] @operator",
        '["(" ")" "[" "]" "{" "}"] @punctuation.bracket',
        '["," "." ":" "@"] @punctuation.delimiter',
        "",
        "; The name a declaration introduces (the first name of the node).",
    ]
    lines += [f"({rule} . (name) @{capture})" for rule, capture in DECLARED_NAMES]
    lines += ["(instance (name) @variable (name) @type)", "(device_decl (name) @variable (name) @type)",
              "(path (name) @variable)", ""]
    return "\n".join(lines)


# Helix's names for the captures whose names differ from Neovim's
# (queries/helix/ holds its copy of the queries).
HELIX_CAPTURES = {"number": "constant.numeric", "boolean": "constant.builtin.boolean", "module": "namespace",
                  "property": "variable.other.member", "embedded": "special"}


def helix_captures(query: str) -> str:
    """A query with Helix's capture names."""
    return re.sub(r"@([\w.]+)", lambda m: "@" + HELIX_CAPTURES.get(m.group(1), m.group(1)), query)


# `#set!` before `#offset!`: py-tree-sitter 0.26 frees the query's
# predicates twice the other way round (the editors take either order).
INJECTIONS = """; Inline C between {{ and }} is C.
((c_code) @injection.content
  (#set! injection.language "c")
  (#offset! @injection.content 0 2 0 -2))
"""


def render_package_files() -> dict[str, str]:
    """package.json and tree-sitter.json as the tree-sitter CLI reads them."""
    package = {
        "name": "tree-sitter-elab",
        "version": VERSION,
        "description": "EasyLab model language (.elab) grammar for tree-sitter",
        "main": "bindings/node",
        "keywords": ["tree-sitter", "parser", "elab", "easylab"],
        "files": ["grammar.js", "queries/*", "src/**"],
        "scripts": {"generate": "tree-sitter generate", "test": "tree-sitter test"},
        "tree-sitter": [{"scope": "source.elab", "file-types": ["elab"], "highlights": "queries/highlights.scm",
                         "injections": "queries/injections.scm"}],
    }
    config = {
        "grammars": [{"name": "elab", "camelcase": "Elab", "scope": "source.elab", "path": ".",
                      "file-types": ["elab"], "highlights": "queries/highlights.scm",
                      "injections": "queries/injections.scm", "injection-regex": "^elab$"}],
        "metadata": {"version": VERSION, "description": "EasyLab model language (.elab) grammar for tree-sitter",
                     "links": {}},
        "bindings": {"c": True},
    }
    return {"package.json": json.dumps(package, indent=2) + "\n",
            "tree-sitter.json": json.dumps(config, indent=2) + "\n"}


def main(argv=None) -> int:
    args = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    args.add_argument("--check", action="store_true", help="exit 1 if a written file is out of date")
    opts = args.parse_args(argv)
    files = render_all()
    stale = [path for path, text in files.items() if not path.is_file() or path.read_text() != text]
    if opts.check:
        for path in stale:
            print(f"{path.relative_to(ROOT)} is out of date: run tools/tree_sitter_grammar.py", file=sys.stderr)
        return 1 if stale else 0
    for path in stale:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(files[path])
        print(f"wrote {path.relative_to(ROOT)}")
    return 0


def render_all() -> dict[Path, str]:
    """Every file this tool writes, by path."""
    grammar = build_grammar()
    table = build_table(grammar)
    files = {OUTPUT / "src" / "parser.c": render_parser_c(grammar, table),
             OUTPUT / "grammar.js": render_grammar_js(grammar),
             OUTPUT / "queries" / "highlights.scm": render_highlights(grammar),
             OUTPUT / "queries" / "injections.scm": INJECTIONS,
             OUTPUT / "queries" / "helix" / "highlights.scm": helix_captures(render_highlights(grammar)),
             OUTPUT / "queries" / "helix" / "injections.scm": INJECTIONS}
    files.update({OUTPUT / name: text for name, text in render_package_files().items()})
    return files


if __name__ == "__main__":
    sys.exit(main())
