#!/usr/bin/env bash
# Run every committed example through the command line; results go to out/examples/<name>/results.h5.
# Usage: examples/run_all.sh [--regenerate]   (--regenerate first rebuilds the body files)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
LIFTOFF=.venv/bin/liftoff
for dir in examples/*/; do
  name=$(basename "$dir")
  [ -f "$dir/scenario.toml" ] || continue
  if [ "${1:-}" = "--regenerate" ]; then "$PY" "$dir/make_bodies.py"; fi
  echo "== $name"
  "$LIFTOFF" transient "$dir/scenario.toml" --out "out/examples/$name"
done
