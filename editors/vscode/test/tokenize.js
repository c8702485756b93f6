// Tokenizes .elab texts with the extension's TextMate grammar, as VS Code
// does (vscode-textmate on the Oniguruma regex engine). Reads a JSON array
// of texts on stdin; writes, per text, its lines' tokens as
// [line, startColumn, endColumn, scopes] (lines and columns from 0).
// tests/editors/ compares them with the model language's own lexer.
"use strict";
const fs = require("fs");
const path = require("path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const GRAMMAR = path.join(__dirname, "..", "syntaxes", "elab.tmLanguage.json");

async function main() {
  const wasm = fs.readFileSync(path.join(path.dirname(require.resolve("vscode-oniguruma")), "onig.wasm"));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.byteLength));
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve({
      createOnigScanner: (sources) => new oniguruma.OnigScanner(sources),
      createOnigString: (s) => new oniguruma.OnigString(s),
    }),
    // Only the model language here: `source.c` (inline C) is VS Code's own.
    loadGrammar: async (scopeName) =>
      scopeName === "source.elab"
        ? vsctm.parseRawGrammar(fs.readFileSync(GRAMMAR, "utf8"), GRAMMAR)
        : null,
  });
  const grammar = await registry.loadGrammar("source.elab");
  const texts = JSON.parse(fs.readFileSync(0, "utf8"));
  const results = texts.map((text) => {
    let stack = vsctm.INITIAL;
    const tokens = [];
    text.split(/\r\n|\n/).forEach((line, index) => {
      const result = grammar.tokenizeLine(line, stack);
      for (const t of result.tokens) {
        tokens.push([index, t.startIndex, Math.min(t.endIndex, line.length), t.scopes]);
      }
      stack = result.ruleStack;
    });
    return tokens;
  });
  process.stdout.write(JSON.stringify(results));
}

main().catch((err) => {
  console.error(err && err.stack ? err.stack : String(err));
  process.exit(1);
});
