#!/usr/bin/env bash
# Print the path of a Python >= 3.12 on this machine: $PYTHON, python3.13/python3.12 on
# PATH, or an installed pyenv 3.13/3.12. Prints nothing if none is found.
ok() { "$1" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 12) else 1)' >/dev/null 2>&1; }
for c in python3.12 python3.13 python3; do
  p=$(command -v "$c" 2>/dev/null) && ok "$p" && { echo "$p"; exit 0; }
done
root=${PYENV_ROOT:-$HOME/.pyenv}
for v in $(ls -d "$root"/versions/3.12* "$root"/versions/3.13* 2>/dev/null); do
  for c in "$v/bin/python3" "$v/bin/python"; do
    [ -x "$c" ] && ok "$c" && { echo "$c"; exit 0; }
  done
done
exit 0
