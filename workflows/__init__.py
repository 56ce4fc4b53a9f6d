"""The `liftoff` command line and the geometry-to-loads workflows (workflows/cli.py)."""
