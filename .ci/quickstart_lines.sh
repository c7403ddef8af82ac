#!/usr/bin/env bash
# Print the command lines of the README's quick start, one per line, exactly as
# written: the lines of the first ```bash block after the "## Quick start" heading.
# Usage: bash .ci/quickstart_lines.sh README.md
set -euo pipefail
awk '
  /^## / { in_section = ($0 == "## Quick start") ; next }
  in_section && !in_block && /^```bash[[:space:]]*$/ { in_block = 1; next }
  in_block && /^```[[:space:]]*$/ { exit }
  in_block && NF { print }
' "${1:-README.md}"
