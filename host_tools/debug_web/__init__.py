"""`easylab-debug web`: the online mode (docs/online.md)."""
