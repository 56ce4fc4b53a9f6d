#!/usr/bin/env bash
# Run every committed example through the command line, into out/examples/<name>/: the launchers
# described as components (a [model] in their scenario) with `liftoff run`, the two-body transients
# with `liftoff transient`.
# Usage: examples/run_all.sh [--regenerate]   (--regenerate first rebuilds the body and geometry files)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
LIFTOFF=.venv/bin/liftoff
for dir in examples/*/; do
  name=$(basename "$dir")
  [ -f "$dir/scenario.toml" ] || continue
  echo "== $name"
  if grep -q '^\[model' "$dir/scenario.toml"; then
    if [ "${1:-}" = "--regenerate" ] && [ -f "$dir/make_files.py" ]; then "$PY" "$dir/make_files.py"; fi
    "$LIFTOFF" run "$dir/scenario.toml" --out "out/examples/$name"
  else
    if [ "${1:-}" = "--regenerate" ]; then "$PY" "$dir/make_bodies.py"; fi
    "$LIFTOFF" transient "$dir/scenario.toml" --out "out/examples/$name"
  fi
done
