"""Host tools: transports, the debug protocol client, `easylab-debug` and `easylab-service`."""
