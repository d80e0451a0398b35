#!/usr/bin/env bash
# The package as a user gets it: build the sdist and, from it, the wheel; install the wheel (not editable)
# into a fresh virtualenv on another Python than the development one; then, in an empty folder,
# `bvsr init`, `bvsr build`, `bvsr check exports/bvsr`. Without extras, `bvsr sweep` must stop with exit
# code 2 naming the `studies` extra.
#
#   tools/wheel_check.sh [PYTHON_VERSION [EXTRAS]]     e.g. tools/wheel_check.sh 3.13 studies,crosscheck
#
# PYTHON_VERSION (default 3.12) is looked up in $PYENV_ROOT/versions (default /root/.pyenv/versions); when
# it is not there the check says so and exits 0. The lock (requirements/lock.txt) constrains the install.
# BVSR_WHEEL_REFERENCE=<export folder> also compares the export with that one, file for file (the
# manifest's volatile section aside). BVSR_WHEEL_KEEP=1 keeps the work folder.
set -euo pipefail

version=${1:-3.12}
extras=${2:-}
repo=$(cd "$(dirname "$0")/.." && pwd)
versions=${PYENV_ROOT:-/root/.pyenv}/versions
python=$(ls -d "$versions/$version".*/bin/python "$versions/$version"/bin/python 2>/dev/null | sort -V | tail -1 || true)
if [ -z "$python" ]; then
    echo "wheel check: no Python $version under $versions: skipped"
    exit 0
fi

work=$(mktemp -d /tmp/bvsr-wheel-check.XXXXXX)
if [ "${BVSR_WHEEL_KEEP:-}" != 1 ]; then trap 'rm -rf "$work"' EXIT; fi
say() { printf '[%5ds] %s\n' "$SECONDS" "$*"; }
say "Python $("$python" -c 'import platform; print(platform.python_version())') ($python); work folder $work"

# Build from the committed tree (HEAD): what a clone gets, without .venv, exports or caches.
"$python" -m venv "$work/builder"
"$work/builder/bin/pip" install --quiet build
mkdir "$work/src"
git -C "$repo" archive HEAD | tar -x -C "$work/src"
"$work/builder/bin/python" -m build --outdir "$work/dist" "$work/src" > "$work/build.log" 2>&1 ||
    { tail -30 "$work/build.log"; exit 1; }
wheel=$(ls "$work"/dist/bvsr_cad-*.whl)
say "built $(basename "$wheel") ($(du -k "$wheel" | cut -f1) KiB) and $(basename "$(ls "$work"/dist/bvsr_cad-*.tar.gz)")"

"$python" -m venv "$work/venv"
start=$SECONDS
"$work/venv/bin/pip" install --quiet -c "$repo/requirements/lock.txt" "$wheel${extras:+[$extras]}"
count=$("$work/venv/bin/pip" list --format=freeze 2>/dev/null | grep -cv '^\(pip\|setuptools\)==')
say "installed bvsr_cad${extras:+[$extras]} in $((SECONDS - start)) s: $count packages ($(du -sm "$work/venv" | cut -f1) MiB)"

export PATH="$work/venv/bin:$PATH" BVSR_CACHE="$work/cache"
bvsr --version
mkdir "$work/empty" && cd "$work/empty"
bvsr build -q  # no file here: the default tail shipped in the wheel
say "bvsr build in an empty folder: exports/bvsr/ ($(find exports/bvsr -type f | wc -l) files)"
mkdir "$work/init" && cd "$work/init"
bvsr init > "$work/init.log"
say "bvsr init: $(grep -c '^  [a-z]*/' "$work/init.log") files"
python -m bvsr_cad build -q  # the copy bvsr init wrote (its data file found beside it)
say "bvsr build after bvsr init: exports/bvsr/ ($(find exports/bvsr -type f | wc -l) files)"
bvsr check exports/bvsr -q | tail -1
say "bvsr check exports/bvsr passed"

if [ -z "$extras" ]; then
    set +e
    bvsr sweep studies/vertebra.toml -q 2> "$work/sweep.err"
    code=$?
    set -e
    if [ "$code" != 2 ] || ! grep -q "pip install 'bvsr_cad\[studies\]'" "$work/sweep.err"; then
        echo "bvsr sweep without the studies extra: exit $code, expected 2 naming the extra:"
        cat "$work/sweep.err"
        exit 1
    fi
    say "bvsr sweep without the studies extra: exit 2, $(cat "$work/sweep.err")"
fi

if [ -n "${BVSR_WHEEL_REFERENCE:-}" ]; then
    python "$repo/tools/compare_exports.py" "$BVSR_WHEEL_REFERENCE" exports/bvsr
fi
say "wheel check passed"
