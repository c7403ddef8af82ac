#!/usr/bin/env bash
# Release check: what a user gets from `pip install dustoptics`, end to end, on this machine.
#
#   1. Builds the sdist and the wheel from this checkout (`python -m build`, the build backend in
#      its own isolated environment); any line of the build's output that says "warning" fails.
#   2. `twine check --strict` on both; the wheel holds every module and data file of the tree.
#   3. Serves them from a PEP 503 `simple/` index generated here, on 127.0.0.1 at a free port.
#   4. Creates a fresh virtual environment and installs `dustoptics[test]==VERSION` from that
#      index, the dependencies from the registries this machine's pip uses (extra indexes).
#   5. Runs the README's user quick start (`dustoptics build`, `info`, `--version`) with the
#      installed command, and the whole test suite against the installed package: pytest runs
#      from outside the checkout, and a plugin loaded before the repository's conftest.py files
#      imports the installed dustoptics first, so that pytest's putting the checkout on sys.path
#      cannot shadow it (checked, before and inside pytest); the package's doctests run from
#      the installed modules (--pyargs dustoptics).
#
# Usage: bash scripts/release_check.sh [WORKDIR]     (WORKDIR: default a new temporary folder)
# Environment: RELEASE_CHECK_PYTEST_ARGS, extra pytest arguments (e.g. "-x"); a checkout at a
# tag vX.Y.Z must build exactly X.Y.Z (no dev or local label), or the check fails.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
WORK=${1:-$(mktemp -d -t dustoptics-release.XXXXXX)}
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
PYTHON=${PYTHON:-python3}
step() { printf '\n=== release check: %s (%s s)\n' "$1" "$SECONDS"; }
fail() { echo "release check: $*" >&2; exit 1; }

# --- 1. Build -------------------------------------------------------------------------------
step "build sdist and wheel"
"$PYTHON" -m venv "$WORK/build-env"
"$WORK/build-env/bin/python" -m pip install --quiet --upgrade pip
"$WORK/build-env/bin/python" - "$ROOT/pyproject.toml" > "$WORK/release-requirements.txt" <<'EOF'
import sys, tomllib
print("\n".join(tomllib.load(open(sys.argv[1], "rb"))["project"]["optional-dependencies"]["release"]))
EOF
"$WORK/build-env/bin/python" -m pip install --quiet -r "$WORK/release-requirements.txt"
DIST="$WORK/dist"
rm -rf "$DIST"
# PYTHONDONTWRITEBYTECODE (set on some machines) makes setuptools print "byte-compiling is
# disabled" warnings: the build runs without it, so that any warning left is the project's.
(cd "$ROOT" && env -u PYTHONDONTWRITEBYTECODE "$WORK/build-env/bin/python" -m build --outdir "$DIST" .) \
  > "$WORK/build.log" 2>&1 || { cat "$WORK/build.log"; fail "python -m build failed"; }
if grep -n -i "warn" "$WORK/build.log"; then
  fail "python -m build printed warnings (above; full output in $WORK/build.log)"
fi
tail -n 1 "$WORK/build.log"
shopt -s nullglob
WHEELS=("$DIST"/dustoptics-*.whl)
SDISTS=("$DIST"/dustoptics-*.tar.gz)
shopt -u nullglob
[ "${#WHEELS[@]}" -eq 1 ] && [ "${#SDISTS[@]}" -eq 1 ] || fail "expected one wheel and one sdist in $DIST"
VERSION=$(basename "${WHEELS[0]}" | cut -d- -f2)
echo "version: $VERSION"
if TAG=$(git -C "$ROOT" describe --tags --exact-match --match 'v[0-9]*' 2>/dev/null); then
  [ "$VERSION" = "${TAG#v}" ] || fail "HEAD is tagged $TAG but builds as $VERSION (modified tracked files?)"
fi

# --- 2. Metadata and contents ---------------------------------------------------------------
step "twine check --strict and the wheel's contents"
"$WORK/build-env/bin/python" -m twine check --strict "${WHEELS[0]}" "${SDISTS[0]}"
"$WORK/build-env/bin/python" - "$ROOT" "${WHEELS[0]}" <<'EOF'
"""Every module and data file of the tree is in the wheel, at its installed path."""
import subprocess, sys, zipfile
from pathlib import PurePosixPath

root, wheel = sys.argv[1], sys.argv[2]
tracked = subprocess.run(
    ["git", "-C", root, "ls-files", "dustoptics", "refractive_indices"],
    capture_output=True, text=True, check=True,
).stdout.split()
expected = set()
for name in tracked:
    path = PurePosixPath(name)
    if path.parts[0] == "refractive_indices":
        path = PurePosixPath("dustoptics", *path.parts)
    expected.add(str(path))
names = set(zipfile.ZipFile(wheel).namelist())
missing = sorted(expected - names)
if missing:
    sys.exit(f"the wheel lacks {len(missing)} files of the tree: {missing[:20]}")
print(f"wheel: all {len(expected)} files of dustoptics/ and refractive_indices/ present")
EOF

# --- 3. A local package index on the loopback -----------------------------------------------
step "serve a PEP 503 index on 127.0.0.1"
INDEX="$WORK/index"
rm -rf "$INDEX" && mkdir -p "$INDEX/simple/dustoptics"
cp "${WHEELS[0]}" "${SDISTS[0]}" "$INDEX/simple/dustoptics/"
"$WORK/build-env/bin/python" - "$INDEX/simple" <<'EOF'
"""The PEP 503 pages: the root lists the project, the project page links its files with sha256."""
import hashlib, html, sys
from pathlib import Path

simple = Path(sys.argv[1])
links = []
for f in sorted((simple / "dustoptics").iterdir()):
    digest = hashlib.sha256(f.read_bytes()).hexdigest()
    links.append(f'<a href="{html.escape(f.name)}#sha256={digest}">{html.escape(f.name)}</a><br>')
page = "<!DOCTYPE html>\n<html><body>\n{}\n</body></html>\n"
(simple / "dustoptics" / "index.html").write_text(page.format("\n".join(links)))
(simple / "index.html").write_text(page.format('<a href="dustoptics/">dustoptics</a><br>'))
EOF
PORT=$("$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$PYTHON" -m http.server "$PORT" --bind 127.0.0.1 --directory "$INDEX" > "$WORK/http.log" 2>&1 &
SERVER=$!
trap 'kill "$SERVER" 2>/dev/null || true' EXIT
for _ in $(seq 50); do
  "$PYTHON" -c "import urllib.request as u; u.urlopen('http://127.0.0.1:$PORT/simple/dustoptics/', timeout=1)" 2>/dev/null && break
  sleep 0.2
done
echo "index: http://127.0.0.1:$PORT/simple (pid $SERVER)"

# --- 4. Install the wheel into a fresh environment ------------------------------------------
step "install dustoptics[test]==$VERSION from the local index"
# `--index-url` replaces pip's own index, so the registries this machine's pip reads (its
# index-url, PyPI when unset, and its extra-index-url) are passed back as extra indexes.
mapfile -t EXTRA < <("$PYTHON" - <<'EOF'
import subprocess, sys
out = subprocess.run([sys.executable, "-m", "pip", "config", "list"], capture_output=True, text=True).stdout
values = {}
for line in out.splitlines():
    key, _, value = line.partition("=")
    values.setdefault(key.split(".", 1)[-1], []).extend(value.strip().strip("'\"").split())
urls = values.get("index-url") or ["https://pypi.org/simple"]
for url in dict.fromkeys(urls[-1:] + values.get("extra-index-url", [])):
    print(f"--extra-index-url={url}")
EOF
)
echo "extra indexes: ${EXTRA[*]}"
VENV="$WORK/venv"
rm -rf "$VENV"
"$PYTHON" -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip 2>&1 \
  | { grep -v "^WARNING: Location '.*' is ignored: it is neither a file nor a directory\.$" || true; }
# Only the wheel: pip must not build the sdist, and the exact version keeps any other
# "dustoptics" on the extra indexes out.
# (pip's notes on this machine's partial local mirrors, "Location ... is ignored", are dropped)
"$VENV/bin/python" -m pip install --quiet --only-binary=dustoptics \
  --index-url "http://127.0.0.1:$PORT/simple" "${EXTRA[@]}" "dustoptics[test]==$VERSION" 2>&1 \
  | { grep -v "^WARNING: Location '.*' is ignored: it is neither a file nor a directory\.$" || true; }
grep -q '"GET /simple/dustoptics/' "$WORK/http.log" || fail "pip did not ask the local index"
# (the wheel's name is URL-encoded in the log: "+" of a local version label is "%2B")
grep -q 'GET /simple/dustoptics/dustoptics-[^ ]*-py3-none-any\.whl HTTP/1\.[01]" 200' "$WORK/http.log" \
  || fail "pip did not download the wheel from the local index"
kill "$SERVER" 2>/dev/null || true

# --- 5. The quick start and the test suite against the installed package -------------------
step "quick start with the installed package"
RUN="$WORK/run"
rm -rf "$RUN" && mkdir -p "$RUN"
export XDG_CACHE_HOME="$WORK/cache"   # numba's cache of the installed package, kept here
unset PYTHONPATH
cd "$RUN"
"$VENV/bin/python" - "$VENV" <<'EOF'
import sys
from pathlib import Path
import dustoptics
where = Path(dustoptics.__file__).resolve()
assert where.is_relative_to(Path(sys.argv[1]).resolve()), f"dustoptics imported from {where}"
print(f"dustoptics {dustoptics.__version__} from {where.parent}")
EOF
[ "$("$VENV/bin/dustoptics" --version)" = "dustoptics $VERSION" ] || fail "dustoptics --version is not $VERSION"
# The README's install lines: the first installs (done above, from the local index), the
# others run as written with the environment's commands first on PATH.
mapfile -t INSTALL < <(bash "$ROOT/.ci/quickstart_lines.sh" "$ROOT/README.md" Install)
[ "${INSTALL[0]:-}" = "python3 -m pip install dustoptics" ] \
  || fail "README's install block does not start with 'python3 -m pip install dustoptics'"
[ "${#INSTALL[@]}" -ge 2 ] || fail "README's install block runs nothing after the install"
for line in "${INSTALL[@]:1}"; do
  echo "+ $line"
  PATH="$VENV/bin:$PATH" bash -euo pipefail -c "$line"
done
"$VENV/bin/dustoptics" info tables/blue-moons/blue-moons.nc > info.txt
head -n 5 info.txt

step "the test suite against the installed package"
SITE=$("$VENV/bin/python" -c 'import dustoptics, pathlib; print(pathlib.Path(dustoptics.__file__).parent)')
# A plugin (on PYTHONPATH, which holds nothing else), loaded before any conftest.py, imports
# the installed dustoptics: pytest puts the checkout's directories first on sys.path
# (pytest's default import mode, as the suite always runs), and a package already imported is
# not looked up again.  After collection it checks that the tests' dustoptics is that one.
mkdir -p "$WORK/plugin"
cat > "$WORK/plugin/release_check_site.py" <<'PLUGIN'
"""pytest plugin of scripts/release_check.sh: the tests run against the installed package."""
import os
from pathlib import Path

import dustoptics  # the installed copy, before the checkout is on sys.path


def pytest_collection_finish(session):
    import dustoptics as imported

    assert imported is dustoptics
    where = Path(dustoptics.__file__).resolve()
    site = Path(os.environ["RELEASE_CHECK_SITE"]).resolve()
    if not where.is_relative_to(site):
        raise RuntimeError(f"the tests import dustoptics from {where}, not from {site}")
    print(f"\nrelease check: the tests import dustoptics from {where.parent}")
PLUGIN
# shellcheck disable=SC2086
RELEASE_CHECK_SITE="$SITE" PYTHONPATH="$WORK/plugin" "$VENV/bin/python" -m pytest \
  -p no:cacheprovider -p release_check_site \
  --rootdir="$ROOT" -c "$ROOT/pyproject.toml" ${RELEASE_CHECK_PYTEST_ARGS:-} \
  "$ROOT/tests" --pyargs dustoptics
echo "release check passed: dustoptics $VERSION ($SECONDS s)"
