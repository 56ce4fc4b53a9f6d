#!/usr/bin/env bash
# Run every committed example through the command line, into out/examples/<name>/: the two-body
# transients (a make_bodies.py beside them) with `liftoff transient`, the launchers described as
# components with `liftoff run`.
# Usage: examples/run_all.sh [--regenerate]   (--regenerate first rebuilds the body and geometry files)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
LIFTOFF=.venv/bin/liftoff
for dir in examples/*/; do
  name=$(basename "$dir")
  [ -f "$dir/scenario.toml" ] || continue
  echo "== $name"
  if [ -f "$dir/make_bodies.py" ]; then
    if [ "${1:-}" = "--regenerate" ]; then "$PY" "$dir/make_bodies.py"; fi
    "$LIFTOFF" transient "$dir/scenario.toml" --out "out/examples/$name"
  else
    if [ "${1:-}" = "--regenerate" ] && [ -f "$dir/make_files.py" ]; then "$PY" "$dir/make_files.py"; fi
    "$LIFTOFF" run "$dir/scenario.toml" --out "out/examples/$name"
  fi
done
