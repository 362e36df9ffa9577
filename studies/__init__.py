"""Research scripts behind the docs (not installed: run them from the top of a checkout,
``.venv/bin/python -m studies.<name> ...``; studies/README.md lists them)."""
