"""The service panel (``easylab-service web``): a web server and the page it serves."""
