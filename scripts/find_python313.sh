#!/usr/bin/env bash
# Print a working CPython 3.13 (bpy 5.2 is built for exactly 3.13). A pyenv shim may be on
# PATH without the version being selected, so each candidate is run, not just found.
for candidate in "${PYTHON313:-}" python3.13 /root/.pyenv/versions/3.13*/bin/python3.13 \
                 "$HOME"/.pyenv/versions/3.13*/bin/python3.13 /usr/local/bin/python3.13 /usr/bin/python3.13; do
  [ -n "$candidate" ] || continue
  if "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 13))' >/dev/null 2>&1; then
    command -v "$candidate" || echo "$candidate"
    exit 0
  fi
done
echo "no working Python 3.13 found: install CPython 3.13 (e.g. pyenv install 3.13) or set PYTHON313=/path/to/python3.13" >&2
exit 1
