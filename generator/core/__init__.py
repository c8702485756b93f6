"""The vocabulary every stage shares: source spans and diagnostics, value
types, typed expression trees, CRC-16, the installation's folders and the
build error. Nothing here imports another stage."""
