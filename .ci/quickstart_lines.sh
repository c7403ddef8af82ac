#!/usr/bin/env bash
# Print the command lines of a README section's first ```bash block, one per line, exactly as
# written: by default the "## Quick start" section's (CI runs them), "Install" for the user's
# install lines (scripts/release_check.sh runs them against the installed wheel).
# Usage: bash .ci/quickstart_lines.sh README.md [SECTION]
set -euo pipefail
awk -v heading="## ${2:-Quick start}" '
  /^## / { in_section = ($0 == heading) ; next }
  in_section && !in_block && /^```bash[[:space:]]*$/ { in_block = 1; next }
  in_block && /^```[[:space:]]*$/ { exit }
  in_block && NF { print }
' "${1:-README.md}"
