"""`make vsix`: the VS Code extension packed by vsce, with its grammar,
language configuration, client and the client's runtime package, and
without the test tools (npm's registry only)."""

from __future__ import annotations

import json
import subprocess
import zipfile

from textmate import EXTENSION, ROOT, npm_install


def test_make_vsix_packs_the_grammar_configuration_and_client():
    version = json.loads((EXTENSION / "package.json").read_text())["version"]
    vsix = ROOT / "build" / f"easylab-elab-{version}.vsix"
    vsix.unlink(missing_ok=True)
    npm_install()  # under its lock; then `make vsix` finds the packages installed
    proc = subprocess.run(["make", "-s", "vsix"], cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    with zipfile.ZipFile(vsix) as z:
        names = set(z.namelist())
        manifest = json.loads(z.read("extension/package.json"))
        grammar = json.loads(z.read("extension/syntaxes/elab.tmLanguage.json"))
    assert {"extension/extension.js", "extension/language-configuration.json",
            "extension/syntaxes/elab.tmLanguage.json", "extension.vsixmanifest"} <= names
    assert any(n.startswith("extension/node_modules/vscode-languageclient/") for n in names)
    assert not any("/vscode-textmate/" in n or "/@vscode/vsce/" in n or n.startswith("extension/test/")
                   for n in names), "development packages in the .vsix"
    language = manifest["contributes"]["languages"][0]
    assert (language["id"], language["extensions"]) == ("elab", [".elab"])
    assert manifest["contributes"]["grammars"][0]["scopeName"] == grammar["scopeName"] == "source.elab"
    assert manifest["contributes"]["configuration"]["properties"]["easylab.server.command"]["default"] == "easylab"
    assert grammar == json.loads((EXTENSION / "syntaxes" / "elab.tmLanguage.json").read_text())


def test_the_client_starts_the_configured_server_over_stdio():
    """extension.js, in Node with stand-ins for VS Code's API and for
    vscode-languageclient (which needs the real editor), hands the client
    the configured command and arguments, on stdio, for .elab files."""
    script = r"""
const Module = require("module");
const started = [];
const settings = {command: "/opt/easylab/bin/easylab", args: ["lsp"]};
const vscode = {
  workspace: {
    getConfiguration: (section) => ({get: (k) => section === "easylab.server" ? settings[k] : undefined}),
    onDidChangeConfiguration: () => ({dispose() {}}),
    createFileSystemWatcher: (glob) => ({glob}),
  },
  window: {showErrorMessage: (m) => started.push(["error", m])},
};
class LanguageClient {
  constructor(id, name, server, client) { Object.assign(this, {id, server, client}); }
  async start() { started.push(["start", this.id, this.server, this.client.documentSelector]); }
}
const stubs = {vscode, "vscode-languageclient/node": {LanguageClient, TransportKind: {stdio: 0}}};
require.resolve("vscode-languageclient/node");  // the real one is installed
const load = Module._load;
Module._load = function (request, ...rest) {
  return request in stubs ? stubs[request] : load.call(this, request, ...rest);
};
require("./extension.js").activate({subscriptions: []}).then(() => console.log(JSON.stringify(started)));
"""
    npm_install()
    proc = subprocess.run(["node", "-e", script], cwd=EXTENSION, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    started = json.loads(proc.stdout.strip().splitlines()[-1])
    assert started[0][0] == "start", started
    _, client_id, server, selector = started[0]
    assert client_id == "easylab" and selector == [{"scheme": "file", "language": "elab"}]
    assert server == {"command": "/opt/easylab/bin/easylab", "args": ["lsp"], "transport": 0}  # stdio
