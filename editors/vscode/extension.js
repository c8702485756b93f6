// The EasyLab extension's client: starts the language server (`easylab lsp`)
// over stdio for .elab files. Plain JavaScript, no build step.
"use strict";
const vscode = require("vscode");
const { LanguageClient, TransportKind } = require("vscode-languageclient/node");

let client;

/** The server's command and arguments from the settings (easylab.server.*). */
function serverOptions() {
  const settings = vscode.workspace.getConfiguration("easylab.server");
  const command = settings.get("command") || "easylab";
  const args = settings.get("args") || ["lsp"];
  return { command, args, transport: TransportKind.stdio };
}

async function start() {
  client = new LanguageClient("easylab", "EasyLab language server", serverOptions(), {
    documentSelector: [{ scheme: "file", language: "elab" }],
    synchronize: { fileEvents: vscode.workspace.createFileSystemWatcher("**/*.elab") },
  });
  try {
    await client.start();
  } catch (err) {
    vscode.window.showErrorMessage(
      `EasyLab: could not start '${serverOptions().command} ${serverOptions().args.join(" ")}' ` +
        `(setting easylab.server.command): ${err.message || err}`
    );
  }
}

async function activate(context) {
  context.subscriptions.push(
    vscode.workspace.onDidChangeConfiguration(async (event) => {
      if (event.affectsConfiguration("easylab.server")) {
        await stop();
        await start();
      }
    })
  );
  await start();
}

async function stop() {
  if (client) {
    const running = client;
    client = undefined;
    if (running.isRunning()) {
      await running.stop();
    }
  }
}

function deactivate() {
  return stop();
}

module.exports = { activate, deactivate };
